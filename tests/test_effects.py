"""The effect plugins: the catalogue's contract, the registry and its entry points, validated
parameters, vectorised hooks, and starts within bounds."""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import numpy as np
import pytest

from spicethermal.core.errors import DataFormatError
from spicethermal.effects import (
    CATALOGUE,
    DEVICE,
    ENTRY_POINT_GROUP,
    MEASUREMENT,
    DeviceEffect,
    Effect,
    EffectPlugin,
    Evidence,
    MeasurementEffect,
    known_names,
    rival_names,
)
from spicethermal.effects.base import CurveEvidence
from spicethermal.effects.temperature_coefficient import law

ROOT = Path(__file__).resolve().parent.parent
#: Names and kinds are a contract (docs/model-format.md).
CONTRACT = {"temperature-coefficient": DEVICE, "phase-change": DEVICE,
            "sample-window": MEASUREMENT, "electrical-transient": MEASUREMENT,
            "tsp-nonlinearity": MEASUREMENT}


def test_the_catalogue_is_the_contract_and_the_rivals_are_not_in_it():
    assert {n: CATALOGUE[n].kind for n in known_names()} == CONTRACT
    assert rival_names() and not set(rival_names()) & set(known_names())
    for name, p in CATALOGUE.items():
        assert isinstance(p, DeviceEffect | MeasurementEffect) and p.name == name
        assert p.params and all(s.low <= s.default <= s.high for s in p.params.values())
        assert p.traits.shown_by and p.forms


def test_every_builtin_effect_is_registered_through_the_entry_point_group():
    declared = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"][
        "entry-points"][ENTRY_POINT_GROUP]
    assert set(declared) == set(CATALOGUE)


def test_parameters_are_validated_with_a_message_that_names_them():
    with pytest.raises(DataFormatError, match="known effects"):
        Effect.create("convection")
    with pytest.raises(DataFormatError, match="alpha_per_k"):
        Effect.create("temperature-coefficient", alpha_per_k=1.0)
    with pytest.raises(DataFormatError, match="form"):
        Effect.create("sample-window", form="middle")
    with pytest.raises(DataFormatError, match="local form"):
        Effect.create("temperature-coefficient", c_slope_per_k=1e-3)
    e = Effect.from_dict({"name": "phase-change", "params": {"latent_j": 0.1}})
    assert e.form == "logistic" and Effect.from_dict(e.to_dict()) == e


@pytest.mark.parametrize("name", sorted(CONTRACT))
def test_hooks_are_vectorised_over_a_batch(name):
    p = CATALOGUE[name]
    batch = {k: np.full((3, 1), s.default) for k, s in p.params.items()}
    temps = np.tile(np.array([30.0, 28.0, 26.0, 25.5]), (3, 1))
    for form in p.forms:
        if isinstance(p, DeviceEffect):
            s = p.resistance_scale(form, batch, temps, temps[:, :1])
            h = p.stored_heat(form, batch, temps, np.ones_like(temps))
            assert s is None or s.shape == (3, 4)
            assert h is None or (h[0].shape == (3, 4) and h[1].shape == (3, 4))


def test_a_stored_heat_is_the_integral_of_its_capacity():
    for form in ("logistic", "gaussian", "plateau"):
        e = Effect.create("phase-change", form, t_c=60.0, width_k=2.0, latent_j=1.5, node=1)
        p = {k: np.full((1, 1), v) for k, v in e.params.items()}
        t = np.linspace(30.0, 90.0, 6001)[None, :]
        temps = np.stack([t[0]] * 3, axis=1)  # a batch of N ladders of 3 nodes: node 1
        heat, cap = e.plugin.stored_heat(form, p, temps, np.ones_like(temps))
        assert heat[-1, 1] == pytest.approx(1.5, rel=1e-3) and heat[:, 0].max() == 0
        assert np.trapezoid(cap[:, 1], t[0]) == pytest.approx(heat[-1, 1] - heat[0, 1],
                                                               rel=1e-4)


def _evidence() -> Evidence:
    t = np.geomspace(1e-4, 10.0, 40)
    model = 25.0 + 10.0 * np.exp(-t)
    curves = (CurveEvidence(t, model - 0.3 * np.exp(-t / 1e-3), model, 0.1, 25.0,
                            np.array([35.0, 31.0, 27.0])),
              CurveEvidence(t, model * 1.01, model, 0.3, 25.0, np.array([60.0, 45.0, 30.0])))
    f = np.array([1e3, 1e4])
    return Evidence(cooling=curves, pwm=(f, np.array([0.5, 0.5]), np.array([0.1, 0.1]),
                                         np.array([30.0, 30.0]), np.array([30.1, 30.2])),
                    declared_window_s=1e-4,
                    calibration=(np.linspace(20, 100, 9), np.linspace(20, 100, 9) + 0.1),
                    rth_k_per_w=100.0, n_nodes=3, node_c_j_per_k=(1e-3, 1e-2, 1e-1),
                    tau_s=(1e-4, 1e-2, 1.0))


@pytest.mark.parametrize("name", sorted(CATALOGUE))
def test_every_start_is_valid_and_within_bounds(name):
    p: EffectPlugin = CATALOGUE[name]
    ev = _evidence()
    for form in p.forms:
        for variant in p.variants(form, ev):
            starts = p.guess(form, variant, ev)
            for s in starts:
                assert set(s) <= set(p.params)
                values = {k: float(np.clip(v, p.params[k].low, p.params[k].high))
                          for k, v in {**variant, **s}.items()}
                assert all(math.isfinite(v) for v in values.values())
                Effect(name, values, form)  # validated


def test_a_device_effect_renders_spice_for_every_layer_it_touches():
    e = Effect.create("temperature-coefficient", "local", alpha_per_k=2e-3, first_layer=1)
    p = e.plugin
    assert p.spice_resistance_scale(e, 0, "V(N0)", "V(TJ)") is None
    assert p.spice_resistance_scale(e, 1, "V(N1)", "V(TJ)") == \
        "MAX(0.05,1+(0.002)*(V(N1)-(25.0)))"
    band = Effect.create("phase-change", t_c=60.0, width_k=1.0, latent_j=2.0, node=1)
    assert band.plugin.spice_stored_heat(band, 0, "V(TJ)", 1.0) is None
    assert "EXP" in band.plugin.spice_stored_heat(band, 1, "V(N1)", 1.0)


def test_the_quadratic_law_renders_as_it_computes():
    """R(T) = R0·(1 + α ΔT + γ ΔT²), clipped at 5 %: a resistance with a maximum where the
    curvature is negative, and the SPICE expression gives the law's own values."""
    e = Effect.create("temperature-coefficient", "quadratic", alpha_per_k=4e-3,
                      curvature_per_k2=-1e-4, t0_c=25.0, first_layer=1)
    assert law(e, [25.0, 45.0, 65.0]).tolist() == pytest.approx([1.0, 1.04, 1.0])
    assert law(e, 500.0) == pytest.approx(0.05)
    assert e.plugin.spice_resistance_scale(e, 0, "V(N0)", "V(TJ)") is None
    text = e.plugin.spice_resistance_scale(e, 1, "V(N1)", "V(TJ)")
    for t in (-40.0, 25.0, 45.0, 80.0, 500.0):
        value = eval(text.replace("MAX", "max").replace("V(N1)", repr(t)))  # noqa: S307
        assert value == pytest.approx(float(law(e, t)), rel=1e-12)


def test_a_ringing_is_started_at_its_frequency_from_sparse_first_readings():
    """A transient ringing through a dozen cycles before it dies, read at ten readings a
    decade (a few per cycle at best): the first start has its frequency and span."""
    t = np.geomspace(1e-6, 1e-1, 51)
    ring_hz, masked = 8e5, 1.5e-5
    rng = np.random.default_rng(0)
    curves = []
    for power in (0.1, 0.3):
        model = 25.0 + 100 * power * np.exp(-t / 1e-3)
        error = -2.0 * np.exp(-5 * t / masked) * np.cos(2 * math.pi * ring_hz * t)
        curves.append(CurveEvidence(t, model + error + rng.normal(0, 0.02, t.size), model,
                                    power, 25.0, np.array([model[0], 25.0])))
    start = CATALOGUE["electrical-transient"].guess("ringing", {}, Evidence(cooling=tuple(
        curves)))[0]
    assert start["ring_hz"] == pytest.approx(ring_hz, rel=0.05)
    assert 0.5 < start["masked_s"] / masked < 2 and start["amplitude_k"] < 0


def test_a_transient_is_shown_only_while_the_junction_has_cooled_little():
    """A junction cooling as exp(−t/1 ms) from 10 K above the reference has given up
    1 − exp(−m/1 ms) of its rise when a masked span m ends: a transient is shown up to a
    quarter (0.1 ms: 9.5 %), not beyond (1 ms: 63 %); before the first reading (0.1 ms) the
    share of that reading scales as √t (25 µs: half of 9.5 %)."""
    t = np.geomspace(1e-4, 1e-1, 31)
    path = 25.0 + 10.0 * np.exp(-t / 1e-3)
    ev = Evidence(cooling=(CurveEvidence(t, path, path, 0.1, 25.0, np.array([35.0]),
                                         path[:, None]),))
    plugin = CATALOGUE["electrical-transient"]
    why = {m: plugin.unshown(Effect.create("electrical-transient", "fixed", amplitude_k=1.0,
                                           masked_s=m), ev) for m in (2.5e-5, 1e-4, 1e-3, 1e-2)}
    assert why[2.5e-5] == why[1e-4] == ""
    assert "first 1e+03 µs after the cut, over which the junction gives up 63 % of its rise" \
        in why[1e-3]
    assert "gives up 100 % of its rise" in why[1e-2]
    # a curve without the model's path shows nothing against it
    bare = Evidence(cooling=(CurveEvidence(t, path, path, 0.1, 25.0, np.array([35.0])),))
    assert plugin.unshown(Effect.create("electrical-transient", masked_s=1e-2), bare) == ""


@pytest.mark.parametrize("form", ["fixed", "power", "ringing"])
def test_a_transient_is_started_only_over_spans_the_data_can_show(form):
    """The first readings sit 0.3 K above a model whose junction cools as exp(−t/1 ms), and
    the error dies over 10 ms: by then the junction has given up nearly all of its rise. No
    start masks more than the 0.29 ms over which it gives up a quarter (the first reading
    past them, 0.32 ms, at most); without the model's paths the scan reaches the long span."""
    t = np.geomspace(1e-6, 1e-1, 51)
    path = 25.0 + 10.0 * np.exp(-t / 1e-3)
    reading = path + 0.3 * np.exp(-5 * t / 1e-2)
    plugin = CATALOGUE["electrical-transient"]
    with_paths = Evidence(cooling=(CurveEvidence(t, reading, path, 0.1, 25.0, np.array([35.0]),
                                                 path[:, None]),))
    starts = plugin.guess(form, {}, with_paths)
    assert starts and max(s["masked_s"] for s in starts) <= 3.2e-4
    bare = Evidence(cooling=(CurveEvidence(t, reading, path, 0.1, 25.0, np.array([35.0])),))
    assert max(s["masked_s"] for s in plugin.guess(form, {}, bare)) > 3.2e-4


def test_a_ringing_too_slow_to_ring_is_described_as_such():
    """A ringing form whose frequency went to its bound of 0 Hz is the fixed form: no
    frequency of 1e-300 Hz is printed."""
    def text(ring_hz):
        return Effect.create("electrical-transient", "ringing", amplitude_k=0.2, masked_s=1e-4,
                             ring_hz=ring_hz).describe()
    assert text(1e5) == ("cooling readings off by +0.2 K at the cut, ringing at 1e+05 Hz, "
                         "gone after 100 µs")
    assert text(0.0) == ("cooling readings off by +0.2 K at the cut, too slow to ring before it "
                         "dies (under a quarter cycle), gone after 100 µs")


def test_a_band_is_shown_only_where_the_temperatures_reached_cross_its_centre():
    """The evidence's node 1 reaches 31 and 45 °C before the cuts from 25 °C: a band centred
    there is shown; one centred below the reference or above the hottest is only a tail."""
    ev = _evidence()
    for t_c, shown in ((40.0, True), (-5.0, False), (52.0, False), (26.0, True)):
        band = Effect.create("phase-change", t_c=t_c, width_k=5.0, latent_j=0.1, node=1)
        why = band.plugin.unshown(band, ev)
        assert (why == "") is shown, why
        assert shown or "outside the 25–45 °C that node 1 reaches" in why


@pytest.mark.parametrize("t_first", [1e-5, 5e-3])
def test_a_transient_is_started_no_longer_than_the_span_its_plugin_says_the_data_show(t_first):
    """The longest span the transient's starts may mask is where the share of the rise its
    ``unshown`` reads from the model's path crosses the limit (between two readings; before the
    first, where that reading's share scaled as √t reaches it), the shortest over the curves."""
    from spicethermal.effects import electrical_transient as et

    t = np.geomspace(t_first, 1.0, 30)

    def curve(tau: float) -> CurveEvidence:
        path = 25.0 + 10.0 * np.exp(-t / tau)
        return CurveEvidence(t, path, path, 1.0, 25.0, np.array([35.0]), path[:, None])

    slow, fast = curve(0.01), curve(0.005)
    longest = et._longest_shown([slow])
    assert et._share_cooled(slow, longest) == pytest.approx(et.MAX_MASKED_SHARE)
    assert et._longest_shown([slow, fast]) == et._longest_shown([fast]) < longest
