"""The independent validation generator against closed forms, its bundles through the project's
reader, its draws and linear suite, and the scorer's reading of a verdict."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.special import lambertw

from spicethermal.identify.readings import cooling_tj_c
from spicethermal.io.bundle import Bundle
from spicethermal.validation.cases import (
    ACCEPTABLE,
    CATALOGUE_NAMES,
    DEVICES,
    FORMS,
    Case,
    bench_for,
    catalogue,
)
from spicethermal.validation.detect import detectability
from spicethermal.validation.draws import KINDS, draw
from spicethermal.validation.linear import (
    SHAPES,
    FosterNetwork,
    LinearNetwork,
    linear_cases,
    linear_fast,
    shape_network,
)
from spicethermal.validation.measure import Bench, Transient, Tsp, measure
from spicethermal.validation.network import LatentHeat, Network, ResistanceLaw
from spicethermal.validation.periodic import periodic_start, pwm_reading, ripple_bound

#: full diagnoses: the slow tier (`make test` runs it, `make check` does not)
pytestmark = pytest.mark.slow

R4, C4 = (4.0, 12.0, 40.0, 90.0), (2e-5, 4e-4, 8e-3, 0.3)


# -- the network against closed forms --------------------------------------------------------
def test_foster_of_one_and_two_nodes_is_exact():
    r, tau = Network((10.0,), (0.1,)).foster()
    assert r.tolist() == pytest.approx([10.0]) and tau.tolist() == pytest.approx([1.0])
    r1, r2, c1, c2 = 1.0, 2.0, 1e-3, 1e-1
    # det(G − s C) = 0 for the two-node ladder: c1 c2 s² − (c1 (g1+g2) + c2 g1) s + g1 g2 = 0
    g1, g2 = 1 / r1, 1 / r2
    a, b, c = c1 * c2, -(c1 * (g1 + g2) + c2 * g1), g1 * g2
    s = np.sort(np.roots([a, b, c]).real)
    r, tau = Network((r1, r2), (c1, c2)).foster()
    assert np.sort(1 / tau) == pytest.approx(s, rel=1e-12)
    assert r.sum() == pytest.approx(r1 + r2, rel=1e-12)
    # the junction's impulse response starts at 1/c1: Σ r_k/τ_k = 1/C_junction
    assert float(np.sum(r / tau)) == pytest.approx(1 / c1, rel=1e-12)


@pytest.mark.parametrize("method", ["BDF", "Radau"])
def test_integration_of_linear_ladder_matches_its_foster_response(method):
    net = Network(R4, C4, method=method)
    t = np.logspace(-6, 2, 41)
    start = net.steady(0.2, 25.0)
    assert start[0] == pytest.approx(25.0 + 0.2 * sum(R4), rel=1e-12)
    _, path = net.integrate(start, t[-1], 0.0, 25.0, t_eval=t)
    r, tau = net.foster()
    exact = 25.0 + 0.2 * (r[None, :] * np.exp(-t[:, None] / tau[None, :])).sum(axis=1)
    assert np.max(np.abs(path[:, 0] - exact)) < 1e-5


def test_single_rc_with_temperature_dependent_r_follows_lambert_w():
    """One layer, R = R0 (1 + α (T_mean − T0)), T_mean = (T + Tref)/2, Tref = T0: the rise θ
    obeys ln(θ/θ0) + a (θ − θ0) = −t/τ with a = α/2, τ = R0 C, so θ = W(aθ0 e^{aθ0 − t/τ})/a."""
    r0, c0, alpha, p = 10.0, 0.05, -4e-3, 4.0
    net = Network((r0,), (c0,), laws=(ResistanceLaw("linear", alpha),))
    a = alpha / 2
    theta0 = p * r0 / (1 - a * p * r0)  # steady: θ = P R0 (1 + a θ)
    start = net.steady(p, 25.0)
    assert start[0] - 25.0 == pytest.approx(theta0, rel=1e-10)
    t = np.linspace(0.0, 3.0, 31)[1:]
    _, path = net.integrate(start, t[-1], 0.0, 25.0, t_eval=t)
    exact = lambertw(a * theta0 * np.exp(a * theta0 - t / (r0 * c0))).real / a
    assert np.max(np.abs(path[:, 0] - 25.0 - exact)) < 1e-5


@pytest.mark.parametrize("shape", ["gaussian", "logistic", "plateau", "skewed"])
def test_latent_heat_bands_hold_the_latent_heat(shape):
    h = LatentHeat(0, 0.3, 60.0, 2.5, shape)
    total, _ = quad(h.capacity, 0.0, 120.0, points=[57.5, 60.0, 62.5], limit=200)
    assert total == pytest.approx(0.3, rel=1e-7)
    step = 1e-4
    for t_c in (55.0, 58.9, 60.3, 62.2):
        numeric = (h.capacity(t_c + step) - h.capacity(t_c - step)) / (2 * step)
        assert h.capacity_slope(t_c) == pytest.approx(numeric, rel=1e-5, abs=1e-9)
        below, _ = quad(h.capacity, 0.0, t_c, points=[57.5, 60.0], limit=200)
        assert h.fraction(t_c) == pytest.approx(below / 0.3, abs=1e-7)  # the molten share


def test_a_skewed_band_has_its_long_tail_below():
    h = LatentHeat(0, 1.0, 60.0, 2.0, "skewed")
    assert h.fraction(60.0 - 4.0) > 0.1 > 1.0 - h.fraction(60.0 + 4.0)
    assert h.capacity(60.0) > max(h.capacity(59.0), h.capacity(61.0))  # its mode at t_c


@pytest.mark.parametrize("law", [
    ResistanceLaw("exp", alpha_per_k=-4e-3), ResistanceLaw("quadratic", 1e-3, beta_per_k2=2e-5),
    ResistanceLaw("saturating", amp=-0.2, width_k=8.0),
    ResistanceLaw("kmin", beta_per_k2=4e-4, t1_c=50.0)], ids=lambda law: law.kind)
def test_resistance_laws_outside_the_catalogue(law):
    assert law.factor(25.0) == pytest.approx(1.0)
    for t_c in (30.0, 48.0, 71.0):
        numeric = (law.factor(t_c + 1e-5) - law.factor(t_c - 1e-5)) / 2e-5
        assert law.slope(t_c) == pytest.approx(numeric, rel=1e-6, abs=1e-12)
    if law.kind == "kmin":  # a conductivity with a minimum: the resistance peaks there
        assert law.factor(50.0) > max(law.factor(40.0), law.factor(60.0))
    with pytest.raises(ValueError, match="resistance law"):
        ResistanceLaw("cubic")


@pytest.mark.parametrize("net", [
    Network(R4, C4, laws=(ResistanceLaw("linear", -3e-3),) * 4, control="junction"),
    Network(R4, C4, laws=(ResistanceLaw("power", exponent=1.3),) * 4, c_slope_per_k=(2e-3,) * 4),
    Network(R4, C4, latent=(LatentHeat(2, 0.1, 45.0, 2.0, "logistic"),
                            LatentHeat(0, 0.01, 55.0, 1.0, "gaussian")), power_slope_per_k=3e-3),
    Network(R4, C4, laws=(None, None, None, ResistanceLaw("switch", t0_c=40, drop=0.3))),
    Network(R4, C4, laws=(ResistanceLaw("exp", alpha_per_k=3e-3),
                          ResistanceLaw("quadratic", -1e-3, beta_per_k2=3e-5),
                          ResistanceLaw("saturating", amp=0.2, width_k=6.0),
                          ResistanceLaw("kmin", beta_per_k2=1e-3, t1_c=41.0))),
    Network(R4, C4, latent=(LatentHeat(0, 0.02, 52.0, 2.0, "skewed"),
                            LatentHeat(1, 0.05, 49.0, 1.5, "gaussian", liquid=0.4))),
], ids=["junction-linear", "power-law", "latent-sag", "switch", "other-laws", "other-bands"])
def test_analytic_jacobian_matches_finite_differences(net):
    x = np.array([55.0, 49.0, 44.6, 38.0])
    jac = net.jacobian(x, 0.2, 25.0)
    numeric = np.empty_like(jac)
    for k in range(4):
        e = np.zeros(4)
        e[k] = 1e-6
        numeric[:, k] = (net.rhs(x + e, 0.2, 25.0) - net.rhs(x - e, 0.2, 25.0)) / 2e-6
    assert np.max(np.abs(jac - numeric)) < 1e-6 * np.max(np.abs(numeric))


def test_shooting_matches_the_closed_form_of_a_linear_ladder():
    """A linear ladder sent through the nonlinear path (laws that are constant)."""
    lin = Network(R4, C4)
    forced = Network(R4, C4, laws=(ResistanceLaw("linear", 0.0),) * 4)
    assert not forced.is_linear
    for f, d in ((500.0, 0.2), (25e3, 0.8)):
        for mode in ("end", "average"):
            exact = pwm_reading(lin, 0.1, f, d, 25.0, 1e-4, mode)
            assert pwm_reading(forced, 0.1, f, d, 25.0, 1e-4, mode) == pytest.approx(exact,
                                                                                   abs=1e-6)


def test_shooting_matches_a_long_transient_from_cold():
    net = Network((2.0, 3.0), (1e-4, 2e-4), laws=(ResistanceLaw("power", exponent=1.5),) * 2,
                  latent=(LatentHeat(1, 2e-3, 30.0, 1.5, "gaussian"),))
    f, d, p = 1e3, 0.3, 5.0
    x = np.full(2, 25.0)
    for _ in range(80):  # slowest time constant ~1 ms: 80 periods settle far below 1e-6 K
        x, _ = net.integrate(x, d / f, p, 25.0)
        x, _ = net.integrate(x, (1 - d) / f, 0.0, 25.0)
    assert periodic_start(net, p, f, d, 25.0) == pytest.approx(x, abs=1e-6)


def test_shooting_finds_the_periodic_state_across_a_narrow_plateau():
    """A MOSFET's junction plateau (0.165 J over 4.7 K, edges of 0.47 K) that the ripple at
    500 Hz and 50 % crosses: the chord iteration on the steady state's linearisation stalled
    (a random validation draw could not be generated); Newton on the period map converges."""
    from spicethermal.validation.cases import DEVICES

    dev = DEVICES["mosfet"]
    net = dev.network(latent=(LatentHeat(0, 0.165, 42.46, 4.72, "plateau"),))
    f, d, p = 500.0, 0.5, dev.bench.pwm_power_w
    x = periodic_start(net, p, f, d, 25.0)
    mid, _ = net.integrate(x, d / f, p, 25.0)
    end, _ = net.integrate(mid, (1 - d) / f, 0.0, 25.0)
    assert np.max(np.abs(end - x)) < 1e-6


# -- the bench and its bundles ----------------------------------------------------------------
def test_bundles_read_back_through_the_project_reader(tmp_path):
    net = Network((0.15, 0.45, 0.7, 0.7), (1e-4, 1.5e-3, 0.012, 0.12))
    bench = Bench((9.0, 22.0), 15.0, "case", t_max_s=5.0, per_decade=5, dense_pwm=False,
                  steady=False, volts=True, noise_k=0.0, tsp=Tsp(0.55, -1.8e-3),
                  transient=Transient("ringing", -1.0, 2e-5, 5e4))
    rec = measure(net, bench, seed=3)
    back = Bundle.read(rec.bundle.write(tmp_path / "b"))
    assert back.reference == "case" and len(back.cooling) == 2 and back.pwm.tj_c.size == 6
    assert all(c.tj_steady_c is None and c.tj_c is None for c in back.cooling)
    # noise-free, linear TSP: the reader's calibration turns the volts back into the truth
    assert cooling_tj_c(back, 1) == pytest.approx(rec.truth["cooling_2"], abs=1e-4)
    assert back.pwm.tj_c == pytest.approx(rec.truth["pwm"], abs=1e-5)
    assert back.extra == {}


def test_case_bundles_read_back_and_keep_their_truth_to_themselves(tmp_path):
    for k, c in enumerate([catalogue()[5], *draw(4, 2, "pair")[:1], *draw(4, 2, "phase")[:1]]):
        back = Bundle.read(c.record().bundle.write(tmp_path / f"b{k}"))
        assert back.extra == {} and c.form not in back.device
        assert len(back.cooling) == len(c.bench.cooling_powers_w)


def test_catalogue_covers_every_form_strength_pairs_clean_and_uncatalogued():
    cases = catalogue()
    families = {c.family for c in cases}
    assert families == {"effect", "pair", "clean", "uncatalogued"}
    singles = {(c.expected[0], c.form, c.strength) for c in cases if c.family == "effect"}
    assert len(singles) == sum(len(f) for f in FORMS.values()) * 3
    assert sum(c.family == "pair" for c in cases) == 6
    assert {c.device for c in cases} == {"actuator", "mosfet", "diode"}
    assert all(not c.expected for c in cases if c.family in ("clean", "uncatalogued"))
    assert all(c.acceptable == tuple(sorted(c.expected)) for c in cases if c.expected)
    assert all("none" in c.acceptable for c in cases if not c.expected)


def test_cases_are_repeatable_and_seeds_differ():
    first, second = [c for c in catalogue() if c.family == "clean"][:2]
    a, b = first.record(), first.record()
    assert all(np.array_equal(a.measured[k], b.measured[k]) for k in a.measured)
    other = replace(first, seed=second.seed).record()
    assert not np.array_equal(a.measured["pwm"] - a.truth["pwm"],
                              other.measured["pwm"] - other.truth["pwm"])


def test_detectability_separates_clean_from_a_strong_effect():
    dev = DEVICES["actuator"]
    variant = {"noise_k": 0.02, "per_decade": 10, "dense_pwm": True, "steady": True,
               "volts": False, "n_curves": 2}
    clean = Case("clean", "clean", (), dev.name, dev.network(), bench_for(dev, variant), 7)
    assert not detectability(clean.record()).detectable
    strong = replace(clean, bench=bench_for(dev, variant, transient=Transient("fixed", -4.0)))
    assert detectability(strong.record()).detectable
    assert detectability(strong.record()).max_gain > 10


def test_an_error_of_the_calibration_line_alone_is_not_detectable():
    """The bench's line is off by what its noisy points put into it, an offset and a slope
    that every reading shares and the calibration's residuals show: a linear ladder read
    through a line off by several times the noise is still a linear ladder."""
    dev = DEVICES["actuator"]
    variant = {"noise_k": 0.02, "per_decade": 10, "dense_pwm": True, "steady": True,
               "volts": False, "n_curves": 2}
    rec = Case("clean", "clean", (), dev.name, dev.network(), bench_for(dev, variant),
               7).record()
    cal = rec.bundle.calibration
    centre = float(np.mean(cal.temp_c))
    sign = np.sign(np.polyfit(cal.temp_c, cal.v_tsp_v, 1)[0])

    def off(name, values):  # a reading's error through a line 0.1 K and 0.2 %/K off
        at = cal.temp_c if name == "calibration" else values
        err = 0.1 + 2e-3 * (np.asarray(at, float) - centre)
        return values + (sign * err if name == "calibration" else err)

    shifted = replace(rec, truth={k: off(k, v) for k, v in rec.truth.items()},
                      measured={k: off(k, v) for k, v in rec.measured.items()})
    assert not detectability(shifted).detectable
    # the line's error is fitted, not ignored: a ladder without it is 0.1 K off everywhere
    assert detectability(shifted).rms_linear["calibration"] < 0.03


# -- device classes, artefacts and physics outside the catalogue ------------------------------
def test_device_classes_span_their_scales():
    """Rth and time constants of each class (a MEMS micro-heater of thousands of K/W to an
    IGBT module of a tenth of a K/W)."""
    span = {}
    for name, dev in DEVICES.items():
        r, tau = dev.network().foster()
        span[name] = (r.sum(), tau.min(), tau.max())
    assert span["mems"][0] > 1000 and 3e-6 < span["mems"][1] < 3e-5 and span["mems"][2] < 3
    assert 0.05 < span["igbt"][0] < 0.2 and 3e-4 < span["igbt"][1] < 3e-3
    assert 30 < span["igbt"][2] < 300
    assert DEVICES["mems"].node_rise_k(0) > 50 and DEVICES["igbt"].top_power_w >= 200


@pytest.mark.parametrize("name", ["mems", "igbt"])
def test_new_classes_read_back_through_the_project_reader(name, tmp_path):
    """The MEMS heater's resistive sensor rises with temperature (K > 0); curves in volts go
    through the calibration back to the truth."""
    dev = DEVICES[name]
    bench = bench_for(dev, {"noise_k": 0.0, "per_decade": 5, "dense_pwm": False,
                            "steady": False, "volts": True, "n_curves": 2})
    rec = measure(dev.network(), bench, 1)
    back = Bundle.read(rec.bundle.write(tmp_path / "b"))
    assert cooling_tj_c(back, 1) == pytest.approx(rec.truth["cooling_2"], abs=1e-4)
    assert back.pwm.tj_c == pytest.approx(rec.truth["pwm"], abs=1e-5)
    assert back.pwm.tj_c.size == 6 and back.reference == dev.bench.reference


def test_trigger_delay_and_acquisition_errors():
    net = Network(R4, C4)
    base = Bench((0.3,), 0.1, noise_k=0.0, per_decade=5)
    delay = 2e-4
    plain = measure(net, base, 1)
    late = measure(net, replace(base, time_offset_s=delay), 1)
    r, tau = net.foster()
    t = base.times()
    shifted = 25.0 + 0.3 * (r * np.exp(-(t[:, None] + delay) / tau)).sum(axis=1)
    assert late.truth["cooling_1"] == pytest.approx(shifted, abs=1e-6)
    assert late.truth["pwm"] == pytest.approx(plain.truth["pwm"], abs=1e-12)
    off = measure(net, replace(base, adc_offset_v=-1e-3), 1)  # −1 mV at −2 mV/K: +0.5 K
    assert off.truth["pwm"] - plain.truth["pwm"] == pytest.approx(0.5, abs=1e-9)
    assert off.truth["calibration"] == pytest.approx(plain.truth["calibration"])


def test_a_band_with_hysteresis_solidifies_below_where_it_melts():
    """Cooled from below its melting band, the band is not molten and the curve is the
    band-free network's; cooled from above, it gives up its heat around the lower band."""
    band = LatentHeat(1, 0.3, 55.0, 1.0, "gaussian", gap_k=10.0)
    net = Network(R4, C4, latent=(band,))
    free = Network(R4, C4)
    t = np.geomspace(1e-5, 100.0, 40)
    for power, molten in ((0.15, False), (0.35, True)):
        start = net.steady(power, 25.0)
        _, path = net.cooling_branch(start).integrate(start, t[-1], 0.0, 25.0, t_eval=t)
        _, ref = free.integrate(start, t[-1], 0.0, 25.0, t_eval=t)
        gap = np.max(np.abs(path[:, 0] - ref[:, 0]))
        assert (gap > 0.5) if molten else (gap < 1e-4), (power, gap)
    cooling = net.cooling_branch(net.steady(0.35, 25.0)).latent[0]
    assert cooling.t_c == 45.0 and cooling.liquid == 1.0
    partly = band.cooling_branch(55.0)
    assert partly.liquid == pytest.approx(0.5)
    total, _ = quad(partly.capacity, 30.0, 60.0, points=[45.0], limit=200)
    assert total == pytest.approx(0.15, rel=0.03)  # the molten half solidifies
    with pytest.raises(ValueError, match="ripple"):  # the PWM swing would cross the gap
        measure(Network(R4, C4, latent=(replace(band, node=0, gap_k=0.5),)),
                Bench((0.35,), 0.3, noise_k=0.0), 1)


def test_ripple_bound_is_the_swing_of_the_periodic_state():
    net = Network(R4, C4)
    f, d, p = 500.0, 0.3, 0.2
    x = periodic_start(net.with_(power_slope_per_k=1e-12), p, f, d, 25.0)
    t = np.linspace(0.0, 1.0 / f, 2001)
    _, on = net.integrate(x, d / f, p, 25.0, t_eval=t[t <= d / f])
    mid = on[-1]
    _, off = net.integrate(mid, (1 - d) / f, 0.0, 25.0,
                           t_eval=np.minimum(t[t > d / f] - d / f, (1 - d) / f))
    path = np.vstack([on, off])
    for node in (0, 1, 2):
        swing = float(np.ptp(path[:, node]))
        assert ripple_bound(net, p, [f], [d], node) == pytest.approx(swing, rel=1e-3, abs=1e-7)


# -- linear devices of other shapes and the linear-data suite ---------------------------------
def test_linear_networks_of_any_shape_are_exact():
    ladder = LinearNetwork(C4, [(i, i + 1 if i < 3 else -1, r) for i, r in enumerate(R4)])
    r, tau = ladder.foster()
    r0, tau0 = Network(R4, C4).foster()
    assert np.sort(tau) == pytest.approx(np.sort(tau0), rel=1e-10)
    assert ladder.steady(0.2, 25.0) == pytest.approx(Network(R4, C4).steady(0.2, 25.0))
    foster = FosterNetwork((1.0, 2.0), (1e-3, 1e-1))
    assert foster.steady(2.0, 25.0)[0] == 31.0
    assert pwm_reading(foster, 1.0, 1e3, 1.0, 25.0) == pytest.approx(28.0)


@pytest.mark.parametrize("shape", SHAPES)
def test_every_shape_on_every_class_is_a_linear_device_of_its_scale(shape):
    for dev in DEVICES.values():
        rth = sum(dev.r_k_per_w)
        net = shape_network(dev.r_k_per_w, dev.c_j_per_k, shape)
        r, tau = net.foster()
        assert net.is_linear and np.all(r > 0) and np.all(tau > 0)
        assert rth / 1.5 < r.sum() < rth * 1.5
        assert net.steady(1.0, 25.0)[0] == pytest.approx(25.0 + r.sum(), rel=1e-9)


def test_the_linear_suite_covers_shapes_classes_and_benches():
    cases = linear_cases()
    assert {(c.device, c.form, c.bench.steady) for c in cases} == {
        (d, s, st) for d in DEVICES for s in SHAPES for st in (True, False)}
    assert {c.bench.volts for c in cases} == {True, False}
    assert {len(c.bench.cooling_powers_w) for c in cases} == {1, 2, 3}
    assert {c.bench.dense_pwm for c in cases} == {True, False}
    assert all(c.family == "linear" and c.acceptable == ("none",) for c in cases)


def test_the_fast_linear_subset_simulates_in_about_a_second_each():
    import time

    fast = linear_fast()
    assert 4 <= len(fast) <= 8 and {c.bench.steady for c in fast} == {True, False}
    assert len({c.device for c in fast}) >= 4 and len({c.form for c in fast}) >= 5
    for c in fast:
        t0 = time.process_time()
        c.record()
        assert time.process_time() - t0 < 3.0
        rec = replace(c, bench=replace(c.bench, noise_k=0.0)).record()  # the exact line
        r, tau = c.network.foster()
        p = c.bench.cooling_powers_w[0]
        exact = c.bench.tref_c + p * (r * np.exp(-c.bench.times()[:, None] / tau)).sum(axis=1)
        assert rec.truth["cooling_1"] == pytest.approx(exact, abs=1e-9 + 1e-9 * exact.max())


# -- the draws ----------------------------------------------------------------------------------
def test_draws_are_repeatable_and_cover_every_kind():
    cases = draw(150, 3)
    assert [c.name for c in draw(150, 3)] == [c.name for c in cases]
    assert draw(40, 3)[39] == cases[39]  # a case does not depend on how many are drawn
    assert {c.kind.split("/")[0] for c in cases} == set(KINDS)
    assert set(DEVICES) == {c.device for c in cases}
    assert {c.family for c in cases} == {"effect", "pair", "clean", "linear", "uncatalogued"}
    for c in cases:
        assert set(c.acceptable) <= set(CATALOGUE_NAMES) | {"none"}
        if c.family == "uncatalogued":
            assert c.acceptable == tuple(sorted(ACCEPTABLE[c.truth["acceptable_because"]][0]))
        if c.family == "pair":
            assert len(c.parts) == 2 and c.acceptable == tuple(sorted(c.expected))
    assert {c.kind for c in draw(12, 4, "artefact")} <= {f"artefact/{a}" for a in (
        "trigger-delay", "adc-gain-offset", "reference-drift", "heater-sag", "remount",
        "convection-switch")}
    with pytest.raises(ValueError, match="kind"):
        draw(1, 1, "nonsense")


def test_acceptable_names_are_the_packages_catalogue():
    from spicethermal.effects import known_names

    assert set(CATALOGUE_NAMES) == set(known_names())
    assert all(accept for accept, why in ACCEPTABLE.values())


def test_drawn_bands_with_hysteresis_leave_the_pwm_ripple_within_their_gap():
    for c in draw(30, 5, "phase"):
        for band in c.network.hysteretic:
            f, d = c.bench.grid()
            assert ripple_bound(c.network, c.bench.pwm_power_w, f, d, band.node) < band.gap_k


def test_the_earlier_random_draws_still_draw_the_first_three_classes():
    from conftest import bench_script

    cases = bench_script("bench_validation_random").draw(30, 2)
    assert {c.device for c in cases} <= {"actuator", "mosfet", "diode"}


# -- the scorer ---------------------------------------------------------------------------------
def test_the_scorer_reads_both_formats_and_counts_as_the_issue_says():
    from conftest import bench_script

    bench = bench_script("bench_validation")
    v2 = {"format": "spicethermal-diagnosis/2", "verdict": {"effect": None, "effects": []}}
    assert bench.verdict_of(v2) == {"class": "none", "effects": [], "first": None}

    def doc(cls, *names):
        return {"doc": {"format": "spicethermal-diagnosis/3", "verdict": {
            "class": cls, "effects": list(names),
            "effect": names[0] if names and cls in ("named", "approximate") else None}},
            "cpu_s": 1.0}

    def meta(name, family, expected=(), acceptable=None, detectable=True, **extra):
        return {"case": name, "family": family, "kind": family, "device": "d",
                "expected": list(expected), "detectable": detectable,
                "acceptable": sorted(acceptable or expected or ["none"]), **extra}

    tc, pc, et = "temperature-coefficient", "phase-change", "electrical-transient"
    cases = {
        "a": (meta("a", "effect", [tc]), doc("approximate", tc)),
        "b": (meta("b", "effect", [tc]), doc("ambiguous", pc, tc)),
        "c": (meta("c", "effect", [tc]), {**doc("named", tc), "cpu_s": 61.0}),
        "d": (meta("d", "effect", [pc], detectable=False), doc("none")),
        "e": (meta("e", "pair", [tc, et], parts_detectable=[True, True]), doc("named", et, tc)),
        "f": (meta("f", "linear"), doc("ambiguous", pc, tc)),
        "g": (meta("g", "uncatalogued", acceptable=["none", et]), doc("named", et)),
        "h": (meta("h", "uncatalogued", acceptable=[tc]), doc("none")),
        "i": (meta("i", "clean"), {"killed": True, "cpu_s": 180.0}),
    }
    s = bench.score({k: m for k, (m, _) in cases.items()}, {k: r for k, (_, r) in cases.items()})
    assert (s["singles_right"], s["singles_n"], s["singles_ambiguous"]) == (1, 3, 1)
    assert s["over_limit"] == 1 and s["killed"] == 1 and s["crashes"] == 0
    assert (s["pairs_both"], s["pairs_n"]) == (1, 1)
    assert (s["null_wrong_bundles"], s["null_wrong_names"], s["null_n"]) == (1, 2, 4)
    assert (s["near_named"], s["near_n"]) == (0, 1)
    assert s["other_wrong_bundles"] == 1  # the ambiguous single names another effect
    assert "a" not in bench.report(s, 60.0).split("\n")[0]


def test_a_case_the_independent_simulator_cannot_simulate_is_counted_apart(tmp_path,
                                                                           monkeypatch):
    from types import SimpleNamespace

    from conftest import bench_script

    bench = bench_script("bench_validation")

    def generate(case, out, fresh=False):
        if case.name == "b":
            raise ArithmeticError("shooting at 2000 Hz, duty 0.8: no periodic state")
        return {"case": case.name}

    monkeypatch.setattr(bench, "generate", generate)
    cases = [SimpleNamespace(name=n) for n in "abc"]
    meta, unmade = bench.generate_all(cases, tmp_path)
    assert sorted(meta) == ["a", "c"] and list(unmade) == ["b"]
    assert "no periodic state" in unmade["b"]
