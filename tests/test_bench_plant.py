"""The simulated plant and the simulated instrument: exact against closed forms, the device
effects against ThermalModel.simulate, determinism."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from spicethermal.bench import protocol as p
from spicethermal.bench.devices import (
    ARTEFACTS,
    CURVED_TSP,
    SAMPLE_WINDOW,
    artefacts,
    bench_data,
    preset,
    shown_as,
)
from spicethermal.bench.plant import Frontend, Plant
from spicethermal.bench.simulator import SimulatedDevice, parse_effects
from spicethermal.core.errors import InstrumentError
from spicethermal.effects import DEVICE, MEASUREMENT, Effect, known_names, plugin
from spicethermal.engines.pwm import steady_state
from spicethermal.model import Schedule, ThermalModel


def test_actuator_preset_is_the_papers_device():
    a = preset("actuator")
    assert a.foster.rth == pytest.approx(146.0)
    assert min(a.foster.tau) == pytest.approx(2e-4) and max(a.foster.tau) == pytest.approx(12.0)
    assert a.powers_w[0] == pytest.approx(0.094)


def test_mur880e_preset_matches_the_datasheet_points():
    m = preset("mur880e")
    assert m.foster.rth == pytest.approx(1.51)
    t = [1e-5, 1e-4, 1e-3, 1e-2, 1e-1, 1.0]
    r = [0.018, 0.06, 0.18, 0.39, 0.6, 0.9]
    assert m.foster.r_norm(t) == pytest.approx(r, rel=2e-3)
    assert m.reference == "case" and m.heatsink is not None


@pytest.mark.parametrize("t_s", [1e-4, 3e-3, 0.5, 20.0])
def test_plant_heating_step_is_exactly_zth(t_s):
    pl = Plant(preset("actuator"))
    pl.step(t_s, 0.094)
    assert pl.theta[0] == pytest.approx(0.094 * float(pl.preset.foster.zth(t_s)), rel=1e-10)


def test_plant_cooling_from_steady_state_is_exactly_the_cooling_curve():
    pl = Plant(preset("actuator"))
    pl.step(1e6, 0.3)
    t = np.geomspace(1e-4, 50, 9)
    got = []
    last = 0.0
    for ti in t:
        pl.step(ti - last, 0.0)
        last = ti
        got.append(pl.theta[0])
    assert got == pytest.approx(0.3 * pl.preset.foster.cooling(t), rel=1e-9)


@pytest.mark.parametrize("freq_hz,duty", [(500.0, 0.2), (25000.0, 0.8)])
def test_periodic_blocks_match_the_analytic_pwm_steady_state(freq_hz, duty):
    pl = Plant(preset("actuator"))
    period = 1 / freq_hz
    pl.step_periods(int(200 / period), period, duty * period, 0.094)  # 200 s: steady
    peak_by_plant = pl.theta[0] + 0.0
    ss = steady_state(pl.preset.foster, 0.094, freq_hz, duty)
    # at a period boundary the junction is at its valley
    assert peak_by_plant == pytest.approx(ss.valley_k, rel=1e-6)
    pl.step(duty * period, 0.094)
    assert pl.theta[0] == pytest.approx(ss.peak_k, rel=1e-6)
    pl.step(1e-4, 0.0)
    assert pl.theta[0] == pytest.approx(steady_state(pl.preset.foster, 0.094, freq_hz, duty,
                                                     1e-4).reading_k, rel=1e-6)


def test_periodic_blocks_equal_period_by_period_stepping():
    a, b = Plant(preset("mur880e")), Plant(preset("mur880e"))
    period, on = 1e-3, 0.3e-3
    a.step_periods(37, period, on, 10.0)
    for _ in range(37):
        b.step(on, 10.0)
        b.step(period - on, 0.0)
    assert a.theta == pytest.approx(b.theta, rel=1e-9)


@pytest.mark.parametrize("name", ["temperature-coefficient", "phase-change"])
def test_device_effects_follow_thermal_model_simulate(name):
    dev = preset("actuator")
    pl = Plant(dev, effects=[name])
    effect = Effect(name, dev.effect_params[name])
    model = ThermalModel(pl.cauer, (effect,))
    times = [2.0, 20.0, 60.0]
    ref = model.simulate(times, Schedule.step(0.3), tref_c=dev.ambient_c).tj_k
    linear = 0.3 * dev.foster.zth(times)
    got, last = [], 0.0
    for t in times:
        pl.heat(t - last, 0.3)
        last = t
        got.append(pl.theta[0])
    assert got == pytest.approx(ref, rel=3e-3)
    assert np.max(np.abs(ref - linear)) > 0.3  # the effect is visible at this power


def test_frontend_tsp_nonlinearity_and_quantization():
    dev = preset("actuator")
    rng = np.random.default_rng(0)
    lin = Frontend(dev, [], 0.0, rng)
    quad = Frontend(dev, [CURVED_TSP], 0.0, rng)
    assert lin.v_forward(75.0) - lin.v_forward(25.0) == pytest.approx(-0.1)
    assert quad.v_forward(75.0) - lin.v_forward(75.0) == pytest.approx(
        dev.diode.quad_v_per_k2 * 2500)
    assert Frontend.code(-1.0) == 0 and Frontend.code(9.0) == 1023
    assert Frontend.code(2.5) == 512


def test_the_bench_names_no_effect_it_finds_them_through_the_registry():
    """The presets' device effects are data (spicethermal/data/sim_bench.json), checked against
    the registry; each artefact of the front end shows as a catalogued measurement effect, and
    the URL's names reach the hardware through that map."""
    data = bench_data()
    for entry in data["devices"].values():
        assert all(plugin(e["name"]).kind == DEVICE for e in entry["effects"])
    assert list(shown_as()) == list(ARTEFACTS)
    assert all(n in known_names() and plugin(n).kind == MEASUREMENT for n in shown_as().values())
    assert artefacts(["sample-window", "phase-change"]) == {SAMPLE_WINDOW}
    dev = SimulatedDevice("actuator", effects=["phase-change"])
    assert dev.ideal_hold and not dev.frontend.curved_tsp and not dev.frontend.cut_transient
    assert [e.name for e in dev.plant.device_effects] == ["phase-change"]
    assert dev.plant.device_effects[0].params["latent_j"] == 1.0  # the preset's, not a default
    dev.close()


def test_any_device_effect_of_the_registry_is_simulated_with_its_own_physics(register_plugin):
    """A device effect the presets hold no data for (offered as a third-party package would
    offer it) is simulated by the plant through its plugin, at its defaults."""
    from spicethermal.effects.temperature_coefficient import TemperatureCoefficient

    class Warmer(TemperatureCoefficient):
        name = "warmer"
        params = {**TemperatureCoefficient.params,
                  "alpha_per_k": replace(TemperatureCoefficient.params["alpha_per_k"],
                                         default=0.01)}

    register_plugin(Warmer)
    assert parse_effects("warmer") == ("warmer",)
    hot, cold = Plant(preset("actuator"), ["warmer"]), Plant(preset("actuator"))
    hot.heat(60.0, 0.3)
    cold.heat(60.0, 0.3)
    assert hot.theta[0] > cold.theta[0] + 1.0  # R rises with T at α = +0.01/K


def test_effect_names_are_checked():
    assert parse_effects(None) == ("electrical-transient", "sample-window", "tsp-nonlinearity")
    assert parse_effects("none") == ()
    assert parse_effects("sample-window,phase-change") == ("sample-window", "phase-change")
    with pytest.raises(InstrumentError, match="unknown effect 'magic'"):
        parse_effects("magic")


def _session(seed: int) -> bytes:
    dev = SimulatedDevice("actuator", seed=seed)
    out = bytearray()
    dev.write(p.Hello().frame(1))
    out += dev.pump()
    dev.write(p.Cooling(94000, 20000, 100, 2, 100, 2000, 10).frame(2))
    for _ in range(500):
        chunk = dev.pump()
        if not chunk:
            break
        out += chunk
        dev.write(p.Ack(len(out)).frame(0))  # keeps the window open (value only acknowledges)
    dev.close()
    return bytes(out)


def test_same_seed_same_bytes_and_different_seed_different_noise():
    a, b, c = _session(4), _session(4), _session(5)
    assert a == b
    assert a != c
