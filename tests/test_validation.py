"""The independent validation generator against closed forms, and its bundles through the
project's reader."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.special import lambertw

from spicethermal.io.bundle import Bundle
from spicethermal.validation.cases import FORMS, case, catalogue
from spicethermal.validation.detect import detectability
from spicethermal.validation.measure import Bench, Transient, Tsp, measure
from spicethermal.validation.network import LatentHeat, Network, ResistanceLaw
from spicethermal.validation.periodic import periodic_start, pwm_reading

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


@pytest.mark.parametrize("shape", ["gaussian", "logistic", "plateau"])
def test_latent_heat_bands_hold_the_latent_heat(shape):
    h = LatentHeat(0, 0.3, 60.0, 2.5, shape)
    total, _ = quad(h.capacity, 0.0, 120.0, points=[57.5, 60.0, 62.5], limit=200)
    assert total == pytest.approx(0.3, rel=1e-7)
    step = 1e-4
    for t_c in (55.0, 58.9, 60.3, 62.2):
        numeric = (h.capacity(t_c + step) - h.capacity(t_c - step)) / (2 * step)
        assert h.capacity_slope(t_c) == pytest.approx(numeric, rel=1e-5, abs=1e-9)


@pytest.mark.parametrize("net", [
    Network(R4, C4, laws=(ResistanceLaw("linear", -3e-3),) * 4, control="junction"),
    Network(R4, C4, laws=(ResistanceLaw("power", exponent=1.3),) * 4, c_slope_per_k=(2e-3,) * 4),
    Network(R4, C4, latent=(LatentHeat(2, 0.1, 45.0, 2.0, "logistic"),
                            LatentHeat(0, 0.01, 55.0, 1.0, "gaussian")), power_slope_per_k=3e-3),
    Network(R4, C4, laws=(None, None, None, ResistanceLaw("switch", t0_c=40, drop=0.3))),
], ids=["junction-linear", "power-law", "latent-sag", "switch"])
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
    assert back.cooling_tj_c(1) == pytest.approx(rec.truth["cooling_2"], abs=1e-4)
    assert back.pwm.tj_c == pytest.approx(rec.truth["pwm"], abs=1e-5)
    assert back.extra == {}


def test_case_bundles_read_back_and_keep_their_truth_to_themselves(tmp_path):
    c = case("tsp-nonlinearity/quadratic/strong")
    back = Bundle.read(c.record().bundle.write(tmp_path / "b"))
    assert back.extra == {} and "tsp" not in back.device
    assert len(back.cooling) == len(c.bench.cooling_powers_w)
    assert c.describe()["truth"]["quad_per_k2"] == pytest.approx(8e-4)


def test_catalogue_covers_every_form_strength_pairs_clean_and_uncatalogued():
    cases = catalogue()
    families = {c.family for c in cases}
    assert families == {"effect", "pair", "clean", "uncatalogued"}
    singles = {(c.expected[0], c.form, c.strength) for c in cases if c.family == "effect"}
    assert len(singles) == sum(len(f) for f in FORMS.values()) * 3
    assert sum(c.family == "pair" for c in cases) == 6
    assert {c.device for c in cases} == {"actuator", "mosfet", "diode"}
    assert all(not c.expected for c in cases if c.family in ("clean", "uncatalogued"))


def test_cases_are_repeatable_and_seeds_differ():
    a, b = case("clean/actuator-1").record(), case("clean/actuator-1").record()
    assert all(np.array_equal(a.measured[k], b.measured[k]) for k in a.measured)
    other = case("clean/actuator-4").record()
    assert not np.array_equal(a.measured["pwm"] - a.truth["pwm"],
                              other.measured["pwm"] - other.truth["pwm"])


def test_detectability_separates_clean_from_a_strong_effect():
    assert not detectability(case("clean/actuator-1").record()).detectable
    strong = detectability(case("electrical-transient/fixed/strong").record())
    assert strong.detectable and strong.max_gain > 10
