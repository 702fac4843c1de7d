"""The forms of ``temperature-coefficient``: closed forms, the fast forward models against the
model's own integration and the independent validation network, SPICE against Python, the
fit's recovery of known parameters from independently generated bundles, and the files."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from scipy.optimize import brentq

from spicethermal.core.errors import DataFormatError
from spicethermal.core.ladder import Cauer, Foster
from spicethermal.effects import Effect
from spicethermal.fit import tcfit
from spicethermal.fit.effectfit import BundleData, baseline_ladder, sse, subset
from spicethermal.fit.fitters import fit_effect_forms
from spicethermal.fit.tcforward import (
    local_cooling_rise,
    local_frozen_ladder,
    local_steady_nodes,
    tc_cooling,
)
from spicethermal.io.bundle import Bundle
from spicethermal.model import Schedule, ThermalModel
from spicethermal.spice import lib as spice
from spicethermal.validation.cases import case
from spicethermal.validation.network import Network, ResistanceLaw

#: full diagnoses: the slow tier (`make test` runs it, `make check` does not)
pytestmark = pytest.mark.slow

TC = "temperature-coefficient"
R4, C4 = (4.0, 12.0, 40.0, 90.0), (2e-5, 4e-4, 8e-3, 0.3)


def local(**p) -> Effect:
    return Effect.create(TC, "local", **p)


def power(**p) -> Effect:
    return Effect.create(TC, "power-law", **p)


# -- closed forms ----------------------------------------------------------------------------
def test_one_layer_local_linear_steady_state_in_closed_form():
    """θ = P R0 (1 + α (Tref + θ/2 − T0)) is linear in θ:
    θ = P R0 (1 + α(Tref − T0))/(1 − α P R0/2)."""
    r0, p, alpha, tref = 10.0, 3.0, 4e-3, 40.0
    e = local(alpha_per_k=alpha, t0_c=25.0)
    exact = p * r0 * (1 + alpha * (tref - 25.0)) / (1 - alpha * p * r0 / 2)
    assert local_steady_nodes(Cauer([r0], [1.0]), e, tref, p)[0] == pytest.approx(exact, rel=1e-13)
    model = ThermalModel(Cauer([r0], [1.0]), (e,))
    assert model.steady_nodes(p, tref)[0] == pytest.approx(exact, rel=1e-10)


@pytest.mark.parametrize("n", [-1.0, 1.3, 2.5])
def test_one_layer_power_law_steady_state_solves_its_scalar_equation(n):
    """θ = P R0 ((Tref + θ/2 + 273.15)/(T0 + 273.15))^n, solved by bracketing."""
    r0, p, tref = 10.0, 5.0, 25.0
    e = power(exponent=n, t0_c=25.0)

    def g(theta):
        return theta - p * r0 * ((tref + theta / 2 + 273.15) / 298.15) ** n

    exact = brentq(g, 1e-6, 500.0, xtol=1e-14)
    assert local_steady_nodes(Cauer([r0], [1.0]), e, tref, p)[0] == pytest.approx(exact, rel=1e-12)
    assert ThermalModel(Cauer([r0], [1.0]), (e,)).steady_nodes(p, tref)[0] == \
        pytest.approx(exact, rel=1e-10)


def test_one_layer_local_cooling_follows_lambert_w():
    """One layer, Tref = T0: ln(θ/θ0) + (α/2)(θ − θ0) = −t/τ (as in the validation tests);
    within the integration's relative tolerance of the rise."""
    from scipy.special import lambertw

    r0, c0, alpha, p = 10.0, 0.05, -4e-3, 4.0
    e = local(alpha_per_k=alpha)
    a = alpha / 2
    theta0 = p * r0 / (1 - a * p * r0)
    t = np.linspace(0.0, 3.0, 31)[1:]
    exact = np.real(lambertw(a * theta0 * np.exp(a * theta0 - t / (r0 * c0)))) / a
    fast = local_cooling_rise(Cauer([r0], [c0]), e, 25.0, p, t)
    assert np.max(np.abs(fast - exact)) < 1e-5 * theta0


# -- the forward models against the model's integration and the independent network ----------
@pytest.mark.parametrize("effect, laws, slope", [
    (local(alpha_per_k=6e-3), (ResistanceLaw("linear", 6e-3),) * 4, None),
    (power(exponent=2.5, c_slope_per_k=3e-3), (ResistanceLaw("power", exponent=2.5),) * 4,
     (3e-3,) * 4),
    (local(alpha_per_k=-1e-2, first_layer=2),
     (None, None, ResistanceLaw("linear", -1e-2), ResistanceLaw("linear", -1e-2)), None),
    (local(alpha_per_k=5e-3, last_layer=1),
     (ResistanceLaw("linear", 5e-3), ResistanceLaw("linear", 5e-3), None, None), None),
])
def test_local_cooling_matches_the_model_and_the_validation_network(effect, laws, slope):
    cauer, p = Cauer(R4, C4), 0.3
    t = np.logspace(-6, 2, 60)
    fast = local_cooling_rise(cauer, effect, 25.0, p, t)
    model = ThermalModel(cauer, (effect,))
    theta0 = model.steady_nodes(p, 25.0)
    assert theta0 == pytest.approx(local_steady_nodes(cauer, effect, 25.0, p), rel=1e-10)
    ours = model.simulate(t, Schedule((0.0,), (0.0,)), 25.0, theta0).tj_k
    assert np.max(np.abs(fast - ours)) < 2e-3
    net = Network(R4, C4, laws=laws, **({"c_slope_per_k": slope} if slope else {}))
    start = net.steady(p, 25.0)
    _, path = net.integrate(start, t[-1], 0.0, 25.0, t_eval=t)
    assert np.max(np.abs(fast - (path[:, 0] - 25.0))) < 2e-3
    assert np.max(np.abs(fast - p * Cauer(R4, C4).to_foster().cooling(t))) > 0.5  # it matters


def test_a_foster_ladder_is_simulated_on_its_cauer_equivalent():
    foster = Cauer(R4, C4).to_foster()
    e = local(alpha_per_k=6e-3)
    t = np.logspace(-5, 2, 20)
    a = ThermalModel(foster, (e,)).simulate(t, Schedule.step(0.3)).tj_k
    b = ThermalModel(Cauer(R4, C4), (e,)).simulate(t, Schedule.step(0.3)).tj_k
    assert np.max(np.abs(a - b)) < 1e-5
    assert tc_cooling(foster, e, 25.0, 0.3, t) == pytest.approx(
        local_cooling_rise(Cauer(R4, C4), e, 25.0, 0.3, t), abs=1e-5)


@pytest.mark.parametrize("effect", [local(alpha_per_k=6e-3),
                                    power(exponent=2.5, c_slope_per_k=3e-3)])
def test_frozen_ladder_pwm_reading_is_close_to_the_shooting_solution(effect):
    """Quasi-static PWM: every layer frozen at its mean temperature, against the exact
    periodic state (shooting). The error grows with the ripple (the resistance ripple times
    the temperature ripple): a few mK at 1 kHz, a few % of the effect at 10 Hz (4 K ripple)."""
    from spicethermal.engines.pwm import steady_state

    model = ThermalModel(Cauer(R4, C4), (effect,))
    for f, d, share in ((10.0, 0.5, 0.05), (1e3, 0.3, 0.01)):
        exact = model.pwm(0.3, f, d, 1e-4).reading_k
        frozen = steady_state(local_frozen_ladder(Cauer(R4, C4), effect, 25.0, 0.3 * d), 0.3, f,
                              d, 1e-4).reading_k
        linear = steady_state(Cauer(R4, C4).to_foster(), 0.3, f, d, 1e-4).reading_k
        assert abs(frozen - exact) < share * abs(linear - exact)


# -- SPICE against Python --------------------------------------------------------------------
@pytest.mark.ngspice
@pytest.mark.parametrize("dialect", spice.DIALECTS)
@pytest.mark.parametrize("effect", [local(alpha_per_k=-6e-3),
                                    power(exponent=1.3, c_slope_per_k=3e-3),
                                    local(alpha_per_k=8e-3, first_layer=1)],
                         ids=["local", "power-law", "outer"])
def test_each_form_in_ngspice_matches_python(tmp_path, dialect, effect):
    model = ThermalModel(Foster.from_tau([20.0, 80.0], [1e-3, 0.5]), (effect,))
    lib = spice.export(model, tmp_path / "m.lib", dialect, None, "TC")  # Cauer by itself
    assert f"{TC} ({effect.form}):" in lib.read_text()
    tref, toffset = spice.reference_drive(model, 25.0)
    net = spice.render_bench(lib, "TC", power_w=0.3, tstop_s=4.0, tmax_s=4e-3, tref_c=tref,
                             toffset_c=toffset)
    w = spice.NgspiceBatch().run(net, ["V(TJ)"], dialect)
    keep = w.t_s > 1e-3
    t = w.t_s[keep]
    py = model.simulate(t, Schedule((0.0, 2e-8), (0.0, 0.3)), tref_c=25.0).tj_k
    assert np.max(np.abs(w["V(TJ)"][keep] - py)) < 0.01  # K, of a rise of about 25 K
    lin = ThermalModel(model.ladder).simulate(t, Schedule.step(0.3)).tj_k
    assert np.max(np.abs(lin - py)) > 0.3  # the effect matters at this strength


def test_local_forms_refuse_a_foster_export_in_one_line():
    model = ThermalModel(Foster.from_tau([1.0], [1.0]), (local(alpha_per_k=1e-3),))
    with pytest.raises(DataFormatError, match="--topology cauer"):
        spice.render_lib(model, "ngspice", "foster", "D")
    assert "cauer" in spice.render_lib(model, "ngspice", None, "D").lower()


def test_spice_expressions_of_each_form():
    e = power(exponent=1.3, c_slope_per_k=2e-3, first_layer=1)
    assert e.spice_resistance_scale(0, "T", "TJ") is None
    assert e.spice_resistance_scale(1, "T", "TJ") == "PWR(MAX(T+273.15,1)/(298.15),1.3)"
    assert e.spice_stored_heat(1, "T", 0.5) == "(0.0005)*(T-(25.0))*(T-(25.0))"
    assert e.spice_stored_heat(0, "T", 0.5) is None
    assert local(alpha_per_k=1e-3).spice_resistance_scale(0, "T", "TJ") == \
        "MAX(0.05,1+(0.001)*(T-(25.0)))"
    # the stored heat is the integral of the extra capacity
    q = [e.latent_heat(2, t, 0.5) for t in (40.0, 40.001)]
    assert (q[1] - q[0]) / 1e-3 == pytest.approx(e.extra_capacitance(2, 40.0005, 0.5), rel=1e-6)


# -- files -----------------------------------------------------------------------------------
@pytest.mark.parametrize("effect", [Effect.create(TC, alpha_per_k=-2e-3),
                                    local(alpha_per_k=1e-3, last_layer=2),
                                    power(exponent=1.3, c_slope_per_k=1e-3, first_layer=1)])
def test_model_file_round_trip_of_every_form(tmp_path, effect):
    model = ThermalModel(Cauer(R4, C4), (effect,))
    back = ThermalModel.load(model.save(tmp_path / "m.json"))
    assert back.effects == (effect,)
    d = effect.to_dict()
    assert ("form" in d) == (effect.form != "junction")
    assert set(d["params"]) == set(effect.form_params)


def test_junction_form_files_are_unchanged_and_bad_combinations_are_refused():
    assert Effect.create(TC, alpha_per_k=1e-3).to_dict() == {
        "name": TC, "params": {"alpha_per_k": 1e-3, "t0_c": 25.0}}
    with pytest.raises(DataFormatError, match="local form"):
        Effect.create(TC, alpha_per_k=1e-3, first_layer=1)
    with pytest.raises(DataFormatError, match="first_layer 3 > last_layer 1"):
        local(first_layer=3, last_layer=1)
    with pytest.raises(DataFormatError, match="not a layer index"):
        local(first_layer=1.5)


# -- fits on independent bundles ----------------------------------------------------------
def _data(name: str, tmp_path) -> tuple[BundleData, Foster, dict]:
    from dataclasses import replace

    from spicethermal.analysis.diagnose import comparison_of, noise_estimates

    c = case(name)
    c.record().bundle.write(tmp_path / "b")
    data = BundleData.from_bundle(Bundle.read(tmp_path / "b"))
    ladder = baseline_ladder(data)
    data = replace(data, scales=noise_estimates(comparison_of(data, ladder)))
    return data, ladder, c.truth


def _best(data, fits):
    n = sum(data.measured(d).size for d in data.datasets)
    return min(fits, key=lambda f: n * math.log(sse(data, f.ladder, [f.effect]) / n)
               + f.n_params * math.log(n))


@pytest.fixture
def converged(monkeypatch):
    """Joint refits run to their tolerance (the diagnosis bounds them in work: the fit is under
    test here, not its budget)."""
    monkeypatch.setattr(tcfit, "JOINT_BUDGET_S", 600.0)


def test_local_linear_alpha_is_recovered_from_an_independent_bundle(tmp_path, converged):
    data, ladder, truth = _data("temperature-coefficient/local-linear/strong", tmp_path)
    fits = fit_effect_forms(data, ladder, TC)
    by_form = {f.effect.form: f for f in fits if not f.effect.params["first_layer"]}
    assert by_form["local"].effect.params["alpha_per_k"] == pytest.approx(
        truth["alpha_per_k"], rel=0.1)
    assert _best(data, fits).effect.form != "junction"  # a local form fits decisively better


def test_power_law_exponent_is_recovered_from_an_independent_bundle(tmp_path, converged):
    data, ladder, truth = _data("temperature-coefficient/power-law/strong", tmp_path)
    fits = fit_effect_forms(data, ladder, TC)
    best = _best(data, fits)
    assert best.effect.form == "power-law"
    assert best.effect.params["exponent"] == pytest.approx(truth["exponent"], abs=0.3)


def test_a_local_coefficient_gets_the_joint_iterations_it_needs():
    """Draw 023 of ``bench/bench_validation_random.py 40 --seed 23`` (independent generator): a
    diode whose layers each follow their own temperature at α = 6.2e-3/K, three cooling
    curves up to 22 W. The local form's joint refit with the ladder needs about five
    iterations, each a Jacobian over every stage (about 1 s of work here). Cut at 1 s, within
    its first iteration, it never moved the ladder: the junction form stayed the best and a
    power error per curve explained the curves better, so the diagnosis named nothing. At the
    diagnosis's own budgets it is now found, α within 2 %, the error 60× lower."""
    from conftest import bench_script

    from spicethermal.analysis.diagnose import diagnose

    c = bench_script("bench_validation_random").draw(24, 23)[23]
    assert c.name.startswith("023 temperature-coefficient/local")
    alpha = c.network.laws[0].alpha_per_k
    d = diagnose(c.record().bundle)
    assert d.effects == ["temperature-coefficient"], d.verdict_reason
    found = d.steps[0].chosen
    assert found.effect.form == "local"
    assert found.effect.params["alpha_per_k"] == pytest.approx(alpha, rel=0.02)
    assert found.improvement > 30


def test_the_held_share_of_an_integrated_coefficient_is_exact_at_its_ladder(tmp_path):
    """A measurement effect's refit of the ladder on top of an integrated coefficient takes
    the coefficient as its share of each cooling curve (``held_share``): at the ladder the
    share was computed on, the readings are the integrated model's, every data set and the
    steady reading; on a ladder 2 % off they miss by about what the share itself changes
    (it grows as ``α (P R)²``: 4 %), a small part of the coefficient's share."""
    from spicethermal.fit.effectfit import held_share, predict

    data, ladder, truth = _data("temperature-coefficient/local-linear/strong", tmp_path)
    held = [local(alpha_per_k=truth["alpha_per_k"])]
    effects = [*held, Effect.create("electrical-transient", "power", k_per_w=-0.1,
                                    masked_s=2e-5)]
    share = held_share(data, ladder, held)
    exact, lin = predict(data, ladder, effects), predict(data, ladder, effects, share)
    assert set(lin) == set(exact)
    for name in exact:
        np.testing.assert_allclose(lin[name], exact[name], rtol=0, atol=1e-9)
    for c in data.cooling:  # just before the cut: the exact steady state
        steady = local_steady_nodes(ladder, held[0], c.tref_steady_c, c.power_w)[0]
        assert share[c.name][0] == pytest.approx(steady - c.power_w * ladder.rth, abs=1e-9)
    near = Foster(tuple(r * 1.02 for r in ladder.r), ladder.c)
    exact, lin = predict(data, near, effects), predict(data, near, effects, share)
    for c in data.cooling:
        own = np.max(np.abs(share[c.name]))
        assert own > 0.5  # the coefficient matters here
        assert np.max(np.abs(lin[c.name] - exact[c.name])) < 0.05 * own


def test_a_transient_on_top_of_an_integrated_coefficient_is_refitted_within_its_budget():
    """Draw 010 of ``bench/bench_validation_random.py 40 --seed 1`` (independent generator):
    a diode's outer layers at α = −1.7e-3/K and a transient proportional to the power cut
    (−0.12 K/W). The coefficient is found first (power-law form, integrated); the transient's
    refit of the ladder on top of it integrated both cooling curves at every evaluation, 70 s
    of work against its 8 s, and failed, so only the coefficient was named. Refitted on the
    coefficient's held share, it costs about 1 s and both are named (the other effects are
    left out to keep the test short: the full diagnosis names the same two)."""
    from conftest import bench_script

    from spicethermal.analysis.diagnose import diagnose

    c = bench_script("bench_validation_random").draw(11, 1)[10]
    assert c.name == "010 pair/electrical-transient:power+temperature-coefficient:outer"
    d = diagnose(c.record().bundle, effects=["temperature-coefficient", "electrical-transient"])
    assert d.effects == ["temperature-coefficient", "electrical-transient"], d.verdict_reason
    assert d.steps[1].chosen.effect.form == "power"
    assert d.steps[1].chosen.improvement > 1.3


def test_heater_sag_is_an_amplitude_not_a_temperature_coefficient(tmp_path):
    """A heater whose power falls as it warms (the independent generator's uncatalogued case)
    scales each cooling curve without changing its shape: the diagnosis, with every form of
    the temperature coefficient available, names nothing and says why."""
    from spicethermal.analysis.diagnose import diagnose

    bundle = case("uncatalogued/heater-sag").record().bundle
    d = diagnose(bundle)
    assert d.effects == [] and d.verdict_effect is None
    assert "scaled per curve" in d.verdict_reason


def test_local_fits_never_end_worse_than_the_linear_ladder(tmp_path, monkeypatch):
    """Forced onto a clean bundle (the gate lifted), every form still fits at least as well
    as the linear ladder it extends (its nested start)."""
    monkeypatch.setattr(tcfit, "GATE_BIC", -math.inf)
    monkeypatch.setattr(tcfit, "GATE_SSE_RATIO", 0.0)
    monkeypatch.setattr(tcfit, "GATE_NOISE_SIGMAS", -math.inf)
    data, ladder, _ = _data("clean/mosfet-2", tmp_path)
    fits = tcfit.fit_temperature_coefficient(data, ladder)
    assert {f.effect.form for f in fits} >= {"junction", "local", "power-law"}
    linear = sse(data, ladder, [])
    for f in fits:
        assert sse(data, f.ladder, [f.effect]) <= linear * (1 + 1e-9)


def test_local_ratio_of_a_chain():
    # two equal layers: node rises 2, 1, 0; layer means 1.5, 0.5; R-weighted mean 1; θj = 2
    assert tcfit.local_ratio(Cauer([1.0, 1.0], [1.0, 1.0]).to_foster()) == pytest.approx(2.0)


def test_the_local_forms_are_gated_on_the_curves_they_are_fitted_to():
    """Draw 000 of ``bench/bench_validation_random.py 40 --seed 5`` (independent generator): a
    diode whose layers follow their own temperature at α = −2.5e-3/K, read through a window
    averaged over 0.22 ms, cut from 9 and 22 W. With the window fitted first (on the linear
    ladder) and held, the junction form takes the cooling curves from χ² 13 500 to 190, but the
    held window misreads the PWM grid with it, so the bundle's whole error rises: gated on
    it, the local forms were never tried. With an effect held, the gate looks at the cooling
    curves (what every form is fitted to): the local form is tried and finds the truth's α."""
    from conftest import bench_script

    from spicethermal.analysis.residuals import comparison_of, noise_estimates

    c = bench_script("bench_validation_random").draw(1, 5)[0]
    assert c.name == "000 pair/sample-window:average+temperature-coefficient:local"
    data = BundleData.from_bundle(c.record().bundle)
    ladder = baseline_ladder(data)
    data = replace(data, scales=noise_estimates(comparison_of(data, ladder, [])))
    window = next(f for f in fit_effect_forms(data, ladder, "sample-window")
                  if f.effect.form == "average")
    fits = tcfit.fit_temperature_coefficient(data, window.ladder, [window.effect])
    names = [cv.name for cv in data.cooling]
    cooling = {f.effect.form: sse(subset(data, names), f.ladder, [window.effect, f.effect])
               for f in fits if not f.effect.params["first_layer"]}
    assert "local" in cooling and cooling["local"] < 0.5 * cooling["junction"]
    local = next(f for f in fits if f.effect.form == "local")
    assert local.effect.params["alpha_per_k"] == pytest.approx(-2.5e-3, rel=0.1)
