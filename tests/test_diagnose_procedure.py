"""The diagnosis's procedure on scripted candidates (the fits replaced by fixed models whose
residuals are either at the noise or structured, each step spending a given number of network
solves): which effects it adds and when it stops."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import spicethermal.analysis.diagnose as procedure
import spicethermal.fit.search as search
from spicethermal.analysis.compare import comparison_of
from spicethermal.analysis.diagnose import diagnose
from spicethermal.analysis.diagnosis import Candidate
from spicethermal.analysis.noise import calibration_degree
from spicethermal.analysis.rules import CLOSED_FORM_COST
from spicethermal.core.errors import FitError
from spicethermal.core.ladder import Cauer
from spicethermal.effects import CATALOGUE, Effect
from spicethermal.effects.base import MeasurementEffect
from spicethermal.effects.registry import plugin
from spicethermal.engines.meter import STEP_SOLVES, metered
from spicethermal.engines.network import NetworkBatch
from spicethermal.fit.joint import ModelFit, bic
from spicethermal.fit.measurement import BundleData
from spicethermal.fit.search import FormFit
from spicethermal.io.bundle import Bundle, CoolingTable
from spicethermal.io.datasets import CalibrationTable

T = np.geomspace(1e-4, 10.0, 40)
BUNDLE = Bundle(ambient_c=25.0, cooling=(CoolingTable(
    T, 0.5, tj_c=25.0 + 10.0 * np.exp(-T), tj_steady_c=35.0, tref_steady_c=25.0),))
DATA = BundleData.from_bundle(BUNDLE)
CALIBRATED = replace(BUNDLE, calibration=CalibrationTable(
    np.arange(20.0, 80.1, 10.0), 0.65 - 2e-3 * (np.arange(20.0, 80.1, 10.0) - 25.0)))
WITH_CAL = BundleData.from_bundle(CALIBRATED)
NOISE = {n: 0.01 for n in WITH_CAL.datasets}
CAL_T = np.arange(20.0, 80.1, 5.0)
#: A calibration whose own points show a bow: 3 mK/K² off the line, 0.1 mK of scatter.
BOWED = replace(BUNDLE, calibration=CalibrationTable(
    CAL_T, 0.65 - 2e-3 * (CAL_T - 25.0) + 6e-6 * (CAL_T - 50.0) ** 2
    + 2e-7 * (-1.0) ** np.arange(CAL_T.size)))
FIRST = Effect.create("temperature-coefficient", alpha_per_k=-3e-3)
SECOND = Effect.create("phase-change", t_c=30.0, width_k=2.0, latent_j=1e-3)


def _fit(effects: tuple, structured: float, data: BundleData = DATA,
         **per_set: float) -> ModelFit:
    """A model whose residual on every data set of ``data`` is the noise alternating in sign
    plus, when ``structured`` (or ``per_set[name]``) > 0, a trend of that many noises (a
    misfit the data set shows)."""
    preds, chi2 = {}, {}
    for n in data.datasets:
        size, trend = data.measured(n).size, per_set.get(n, structured)
        res = NOISE[n] * ((-1.0) ** np.arange(size) + trend * np.linspace(-1, 1, size))
        preds[n], chi2[n] = data.measured(n) - res, float(np.sum((res / NOISE[n]) ** 2))
    return ModelFit(Cauer([20.0], [1e-2]), effects, preds, chi2, 2 + 2 * len(effects), 10, True)


def _candidate(data: BundleData, current: ModelFit, fit: ModelFit,
               delta_bic: float) -> Candidate:
    cmp, after = comparison_of(data, current.predictions), comparison_of(data, fit.predictions)
    return Candidate(fit.effects[-1], fit, after, delta_bic, 0.9, cmp.rms_k / after.rms_k)


def _spend(solves: int) -> None:
    """Spend ``solves`` network solves (the modes of as many one-node networks)."""
    if solves:
        NetworkBatch(np.ones((solves, 1)), np.ones((solves, 1))).foster()


@pytest.fixture
def scripted(monkeypatch):
    """Runs the procedure with the candidates of each step given in order (and ``lighter``
    as the model without each earlier effect, when given); each step spends ``cost``
    network solves. With ``cut_after``, each step fits that many effects and the budget
    is spent before the next ones."""
    def run(*steps: tuple[ModelFit, float], lighter: ModelFit | None = None,
            bundle: Bundle = BUNDLE, cost: int = 0, budget: int = 10**9,
            after: dict | None = None, weighed: list | None = None,
            cut_after: int | None = None, asked: list | None = None,
            held: ModelFit | None = None, held_asked: list | None = None,
            refits: dict | None = None, noise_after: dict | None = None,
            noises: list | None = None, refitted: list | None = None):
        base = _fit((), 40.0, BundleData.from_bundle(bundle))
        monkeypatch.setattr(procedure, "_baseline", lambda data, model: (base, NOISE))
        # the noise estimated again from each step's model: ``noise_after``, else the
        # baseline's
        monkeypatch.setattr(procedure, "noise_estimates",
                            lambda data, pred: dict(noise_after or NOISE))
        fitted = []

        def screen_held(data, noise, model, plugins, rounds):  # ``held``, each
            plugins = list(plugins)
            if held_asked is not None:
                held_asked.extend(p.name for p in plugins)
            return {p.name: [FormFit(held, ())] for p in plugins
                    if held is not None and isinstance(p, MeasurementEffect)}

        monkeypatch.setattr(procedure, "screen_held", screen_held)

        def fit_effect(data, noise, model, plugin, *a, **k):
            if asked is not None:  # the effects each step fitted, in order
                asked.append((tuple(e.name for e in model.effects), plugin.name))
            if cut_after is None:
                return [], True
            fitted.append(plugin.name)
            if len(fitted) > cut_after:
                _spend(budget)
                return [], False
            return [FormFit(_fit((FIRST,), 0.0), ())], True

        monkeypatch.setattr(procedure, "fit_effect", fit_effect)
        def refit(data, noise, fit, rounds):  # the model as it is, or ``refits[id(model)]``
            if refitted is not None:  # the noise of each refit
                refitted.append(dict(noise))
            return (refits or {}).get(id(fit), fit)

        monkeypatch.setattr(procedure, "refit", refit)

        def without(*a, **k):  # the model without an earlier effect: none, or ``lighter``
            if lighter is None:
                raise FitError("scripted")
            return lighter

        monkeypatch.setattr(procedure, "without", without)
        script = list(steps)

        def weigh(data, noise, model, cmp, fitted, n_points, sizes, work_left):
            _spend(cost)
            if weighed is not None:  # the data each step's candidates were weighed on
                weighed.append(data.source)
            if noises is not None:  # and the noise
                noises.append(dict(noise))
            if after is not None:  # the candidates after the model's effects, best first
                got = after.get(tuple(e.name for e in model.effects), ())
                return [_candidate(data, model, fit, gain) for fit, gain in got], 0
            if not script:
                return [], 0
            fit, gain = script.pop(0)
            return [_candidate(data, model, fit, gain)], 0

        monkeypatch.setattr(procedure, "_weigh", weigh)
        return diagnose(bundle, budget=budget)
    return run


def test_a_further_effect_whose_fall_does_not_stand_out_of_the_misfit_it_leaves_is_not_added(
        scripted):
    """The second effect takes the trend left from 8 noises to 6: a fall of χ² by 388, but
    the residual it leaves is that trend still, and the fall weighed under its correlation
    is below the criterion's two parameters (rules.correlated_gain)."""
    d = scripted((_fit((FIRST,), 8.0), 5000.0), (_fit((FIRST, SECOND), 6.0), 200.0))
    assert d.effects == [FIRST.name]
    assert d.verdict.cls == "approximate"
    # the verdict says what the refused effect would do, and why it is not named
    assert (f"{SECOND.name} would lower the criterion by a further 200.0 and remove 90 % of "
            "the misfit left, but it leaves a structured residual too, and weighed under that "
            "residual's correlation by -0.2 only: not named, since any flexible effect takes "
            f"part of what the approximate form of {FIRST.name} leaves" in d.verdict.reason)
    refused = d.to_dict()["refused"]  # and the document holds its numbers
    assert refused["effect"] == SECOND.name and refused["delta_bic"] == 200.0
    assert round(refused["weighed_delta_bic"], 1) == -0.2


def test_a_further_effect_whose_fall_stands_out_of_the_misfit_it_leaves_is_added(scripted):
    """From a trend of 8 noises to one of 2: beyond the noise still, but the fall weighed
    under the correlation of what is left is decisive (270)."""
    d = scripted((_fit((FIRST,), 8.0), 5000.0), (_fit((FIRST, SECOND), 2.0), 200.0))
    assert d.effects == [FIRST.name, SECOND.name]
    assert d.verdict.cls == "approximate" and d.to_dict()["refused"] is None


def test_a_further_effect_that_brings_every_data_set_to_its_noise_is_added(scripted):
    d = scripted((_fit((FIRST,), 8.0), 5000.0), (_fit((FIRST, SECOND), 0.0), 200.0))
    assert d.effects == [FIRST.name, SECOND.name]
    assert d.verdict.cls == "named"
    assert d.to_dict()["refused"] is None


def test_what_a_model_leaves_is_built_only_for_a_plugin_that_judges_it(scripted, monkeypatch):
    # the default ``unshown`` needs no evidence (a network simulation of the model); a
    # plugin that overrides it gets the evidence of the model with its effect
    built = []
    real = search.evidence
    monkeypatch.setattr(search, "evidence",
                        lambda data, fit, noise: built.append(fit) or real(data, fit, noise))
    d = scripted((_fit((FIRST,), 8.0), 5000.0), (_fit((FIRST, SECOND), 0.0), 200.0))
    assert d.effects == [FIRST.name, SECOND.name]
    assert [[e.name for e in f.effects] for f in built] == [[FIRST.name, SECOND.name]]


def test_each_chosen_model_is_settled_and_the_next_step_weighed_from_there(scripted,
                                                                          monkeypatch):
    settled, weighed = [], []

    def settle(data, noise, fit, rounds):  # the data then hold the settled model's correction
        settled.append([e.name for e in fit.effects])
        return replace(data, source=f"settled at {fit.effects[-1].name}"), fit

    monkeypatch.setattr(procedure, "settle", settle)
    d = scripted((_fit((FIRST,), 8.0), 5000.0), (_fit((FIRST, SECOND), 0.0), 200.0),
                 weighed=weighed)
    assert d.effects == [FIRST.name, SECOND.name]
    assert settled == [[FIRST.name], [FIRST.name, SECOND.name]]
    assert weighed == [DATA.source, f"settled at {FIRST.name}"]


def test_the_noise_is_estimated_again_after_each_step_and_the_next_step_weighed_under_it(
        scripted):
    """The first step's model gives lower estimates than the baseline's (whose residual
    inflated them): each data set keeps the lower, the model is refitted under it, the next
    step is weighed under it, and the document's χ² are under the last estimate."""
    lower = {n: v / 2 for n, v in NOISE.items()}
    after = {**lower, "cooling_1": 2 * NOISE["cooling_1"]}  # this one rose: kept as it was
    kept = {**lower, "cooling_1": NOISE["cooling_1"]}
    noises, refitted = [], []
    d = scripted((_fit((FIRST,), 8.0), 5000.0), (_fit((FIRST, SECOND), 0.0), 200.0),
                 noise_after=after, noises=noises, refitted=refitted)
    assert d.effects == [FIRST.name, SECOND.name]
    assert noises == [NOISE, kept] and kept in refitted
    doc = d.to_dict()
    assert doc["noise_k"] == kept and doc["baseline"]["noise_k"] == NOISE
    assert [s["noise_k"] for s in doc["steps"]] == [kept, kept]
    residual = DATA.measured("steady") - d.baseline_fit.predictions["steady"]
    assert doc["baseline"]["chi2"]["steady"] == pytest.approx(
        float(np.sum((residual / kept["steady"]) ** 2)))


def test_a_misfit_no_local_quadratic_follows_inflates_the_noise_until_a_model_explains_it(
        monkeypatch):
    """A misfit that swings over less than a decade (a band crossed on a sparse curve) is no
    quadratic over 7 readings: the curve's estimate is several times its noise; estimated
    again from a model that follows it, it falls to the noise, and the model is refitted."""
    rng = np.random.default_rng(1)
    swing = 0.3 * np.sin(2 * np.pi * np.log10(T) / 0.8)
    truth = 25.0 + 10.0 * np.exp(-T) + swing
    data = BundleData.from_bundle(Bundle(ambient_c=25.0, cooling=(CoolingTable(
        T, 0.5, tj_c=truth + rng.normal(0, 0.01, T.size), tref_steady_c=25.0),)))
    inflated = procedure.noise_estimates(data, {"cooling_1": truth - swing})
    assert inflated["cooling_1"] > 5 * 0.01
    refitted = []
    monkeypatch.setattr(procedure, "refit",
                        lambda data, noise, fit, rounds: refitted.append(noise) or fit)
    fit = ModelFit(Cauer([20.0], [1e-2]), (SECOND,), {"cooling_1": truth}, {}, 4, 0, True)
    noise, _, spent = procedure._renoise(data, inflated, fit)
    assert 0.005 < noise["cooling_1"] < 0.015 and refitted == [noise]
    assert spent == 0  # the refit kept the model: no work of its own
    assert procedure._renoise(data, noise, fit)[0] is noise  # no lower estimate: as it was


def test_a_first_effect_is_added_even_when_it_leaves_a_residual(scripted):
    d = scripted((_fit((FIRST,), 8.0), 5000.0))
    assert d.effects == [FIRST.name] and d.verdict.cls == "approximate"


RIVAL = Effect.create("power-error", gamma_per_w=0.1)


def test_a_rival_left_in_the_model_makes_the_verdict_none(scripted):
    d = scripted((_fit((RIVAL,), 8.0), 5000.0), (_fit((RIVAL, FIRST), 0.0), 900.0))
    assert [s.chosen.name for s in d.steps] == [RIVAL.name, FIRST.name]
    assert d.verdict.cls == "none" and not d.effects


def test_a_rival_the_backward_check_drops_leaves_the_effects_named(scripted):
    d = scripted((_fit((RIVAL,), 8.0), 5000.0), (_fit((RIVAL, FIRST), 0.0), 900.0),
                 lighter=_fit((FIRST,), 0.0))
    assert d.steps[-1].dropped == (RIVAL.name,)
    assert d.effects == [FIRST.name] and d.verdict.cls == "named"


SENSOR = Effect.create("tsp-nonlinearity", quad_k_per_k2=4e-4)


@pytest.mark.parametrize(("bundle", "calibration", "status"), [
    (BOWED, 40.0, "unshown"), (BOWED, 0.0, "named"), (CALIBRATED, 0.0, "unshown")])
def test_an_effect_is_named_alone_only_when_the_data_it_needs_show_it(scripted, bundle,
                                                                      calibration, status):
    """A TSP that brings the cooling curves to their noise while its calibration keeps its
    misfit (the calibration does not show it) is unshown: the verdict names nothing and
    says why; with the calibration's misfit gone too, it is named, when the calibration's
    own points show a bow (without one, what the model took there was its shared line's)."""
    data = BundleData.from_bundle(bundle)
    d = scripted((_fit((SENSOR,), 0.0, data, calibration=calibration), 5000.0), bundle=bundle)
    assert [s.status for s in d.steps] == [status]
    if status == "unshown":
        assert d.verdict.cls == "none" and not d.effects
        assert "the calibration data do not show it themselves" in d.verdict.reason
    else:
        assert d.effects == [SENSOR.name] and d.verdict.cls == "named"


@pytest.mark.parametrize(("bundle", "calibration", "named"), [
    (BOWED, 40.0, [FIRST.name]), (BOWED, 0.0, [FIRST.name, SENSOR.name]),
    (CALIBRATED, 0.0, [FIRST.name]), (BUNDLE, 0.0, [FIRST.name, SENSOR.name])])
def test_an_effect_its_own_data_do_not_show_is_not_tied(scripted, bundle, calibration, named):
    """A TSP within the margin of a temperature coefficient: tied when its calibration shows
    it, or when the bundle holds no calibration (nothing can tell them apart); not named at
    all when the calibration is there and keeps its misfit, or shows no bow on its own (the
    curvature is the device's)."""
    data = BundleData.from_bundle(bundle)
    after = {(): [(_fit((FIRST,), 0.0, data), 5000.0),
                  (_fit((SENSOR,), 0.0, data, calibration=calibration), 4995.0)]}
    d = scripted(after=after, bundle=bundle)
    assert list(d.verdict.effects) == named
    assert d.verdict.cls == ("named" if len(named) == 1 else "ambiguous")


@pytest.mark.parametrize(("first", "second", "named"), [
    (0.0, 0.0, [FIRST.name, SECOND.name]), (0.0, 8.0, [FIRST.name]),
    (8.0, 8.0, [FIRST.name, SECOND.name]), (8.0, 0.0, [SECOND.name])])
def test_an_effect_beyond_the_noise_is_not_tied_with_one_at_it(scripted, first, second, named):
    """Two effects within the margin of the criterion are tied when both bring every data
    set to the noise, or neither does; not when the one chosen does and the other leaves a
    structured residual: the noise test tells them apart. (One at the noise behind one
    beyond it is named alone: the selection from the next best first effect ends at the
    noise.)"""
    after = {(): [(_fit((FIRST,), first), 5000.0), (_fit((SECOND,), second), 4995.0)]}
    d = scripted(after=after)
    assert list(d.verdict.effects) == named


#: Transients of the reading on the scripted model (one stage of 0.2 s): one over in a tenth
#: of a millisecond, and one masking the first second, over which the junction gives up
#: 99 % of its rise (electrical_transient.MAX_MASKED_SHARE).
BRIEF = Effect.create("electrical-transient", "fixed", amplitude_k=0.3, masked_s=1e-4)
LONG = Effect.create("electrical-transient", "fixed", amplitude_k=0.3, masked_s=1.0)


def test_the_selection_from_the_next_best_first_effect_keeps_its_tie_with_the_best(scripted):
    """Two first effects within the margin, both beyond the noise: after the best no further
    effect reaches the noise, after the next best a third does. The selection from the next
    best is kept, and its first step is still tied with the best (the margin holds either
    way): both are named, then the third."""
    after = {(): [(_fit((FIRST,), 8.0), 5000.0), (_fit((SECOND,), 8.0), 4995.0)],
             (SECOND.name,): [(_fit((SECOND, BRIEF), 0.0), 200.0)]}
    d = scripted(after=after)
    assert list(d.verdict.effects) == [SECOND.name, FIRST.name, BRIEF.name]
    assert d.verdict.cls == "ambiguous" and d.steps[0].chosen.name == SECOND.name


OUTSIDE = Effect.create("phase-change", t_c=80.0, width_k=2.0, latent_j=1e-3)


def test_a_further_effect_the_data_do_not_show_is_not_added(scripted):
    """A band centred at 80 °C on curves that cool from 35 °C: only its tail would show."""
    d = scripted((_fit((FIRST,), 8.0), 5000.0), (_fit((FIRST, OUTSIDE), 0.0), 200.0))
    assert d.effects == [FIRST.name] and d.verdict.cls == "approximate"


def test_a_first_effect_the_data_do_not_show_is_not_named(scripted):
    d = scripted((_fit((OUTSIDE,), 0.0), 5000.0))
    assert [s.status for s in d.steps] == ["unshown"]
    assert d.verdict.cls == "none" and not d.effects
    assert "outside the 25–35 °C that the junction reaches" in d.verdict.reason
    assert "outside the 25–35 °C" in d.to_dict()["steps"][0]["why"]  # the document says why


def test_a_transient_masking_most_of_the_cooling_is_not_named(scripted):
    d = scripted((_fit((LONG,), 0.0), 5000.0))
    assert [s.status for s in d.steps] == ["unshown"] and not d.effects
    assert "over which the junction gives up 99 % of its rise" in d.verdict.reason
    assert d.verdict.separate_by == ("electrical-transient: a cut from a small heating power "
                                     "(the switching transient with little cooling)")


@pytest.mark.parametrize(("effect", "named"), [(BRIEF, [FIRST.name, BRIEF.name]),
                                                (LONG, [FIRST.name])])
def test_a_tie_its_plugin_says_the_data_cannot_show_is_no_alternative(scripted, effect, named):
    after = {(): [(_fit((FIRST,), 0.0), 5000.0), (_fit((effect,), 0.0), 4995.0)]}
    d = scripted(after=after)
    assert list(d.verdict.effects) == named
    assert d.verdict.cls == ("ambiguous" if len(named) == 2 else "named")


def test_a_step_starts_only_while_work_is_left(scripted):
    """Each step spends about 1,000 solves: with 1,000 to spend, the second step does not
    start; with 1,500, it does (and overruns the budget)."""
    two = ((_fit((FIRST,), 8.0), 5000.0), (_fit((FIRST, SECOND), 0.0), 200.0))
    d = scripted(*two, cost=1000, budget=1000)
    assert d.effects == [FIRST.name] and d.verdict.cls == "approximate"
    assert 1000 <= d.spent.solves < 2000 and d.spent.budget == 1000
    assert d.spent.stopped == "the work budget (a cost of 1,000) was spent after step 1"
    assert d.verdict.reason.endswith(d.spent.stopped)
    # the budget bounds the cost: the solves and a fixed cost for each batched step
    assert d.spent.cost == d.spent.solves + STEP_SOLVES * d.spent.steps > d.spent.solves
    assert d.to_dict()["work"] == {"rows": d.work, "solves": d.spent.solves,
                                   "steps": d.spent.steps, "cost": d.spent.cost,
                                   "budget": 1000, "stopped": d.spent.stopped}
    d = scripted(*two, cost=1000, budget=1500)
    assert d.effects == [FIRST.name, SECOND.name] and not d.spent.stopped
    assert d.spent.solves >= 2000


def test_the_rest_is_outside_the_catalogue_only_when_the_search_ended(scripted):
    """An effect that leaves too much for an approximate name is not named; what is left is
    said to be outside the catalogue when the search ended, not when the budget stopped it
    before a further effect was weighed."""
    two = ((_fit((FIRST,), 20.0), 5000.0), (_fit((FIRST, SECOND), 18.0), 200.0))
    ended, stopped = scripted(two[0]), scripted(*two, cost=1000, budget=1000)
    assert ended.verdict.cls == stopped.verdict.cls == "none"
    assert ended.verdict.reason.startswith(f"{FIRST.name} would remove only 75 %")
    assert ended.verdict.reason.endswith("; not in the catalogue")
    assert stopped.verdict.reason.startswith(f"{FIRST.name} would remove only 75 %")
    assert "catalogue" not in stopped.verdict.reason
    assert stopped.verdict.reason.endswith(stopped.spent.stopped)


def test_once_the_work_is_spent_a_later_step_screens_the_measurement_effects_held(scripted):
    """The budget is spent by the first step: the second screens the effects the model lacks
    on the model held (no joint refit) and takes the best when it brings every data set to
    its noise, and not otherwise."""
    transient = Effect.create("electrical-transient")
    for left, verdict in ((0.0, "named"), (8.0, "approximate")):
        at = _fit((FIRST, transient), left)
        after = {(): [(_fit((FIRST,), 8.0), 5000.0)], (FIRST.name,): [(at, 300.0)]}
        screened: list = []
        d = scripted(after=after, cost=1000, budget=1000, held=at, held_asked=screened)
        assert d.verdict.cls == verdict
        assert sorted(screened) == sorted(n for n in CATALOGUE
                                          if n != FIRST.name and n not in d.skipped)
        assert d.spent.stopped.startswith("the work budget (a cost of 1,000) was spent after "
                                          "step 1 (")
        assert "screened on the model held)" in d.spent.stopped
        assert SECOND.name not in d.spent.stopped.split("(")[1]  # a device effect: not held
        if left:
            assert d.effects == [FIRST.name]
        else:
            assert d.effects == [FIRST.name, transient.name]
            assert d.steps[-1].model is at  # not refitted
            assert d.spent.stopped.endswith(f"could at most tie with {transient.name}, which "
                                            "brings every data set to its noise")


OWN = [(BOWED, 0.0, True), (BOWED, 8.0, False), (CALIBRATED, 0.0, False)]


def test_the_bowed_calibration_shows_its_bow_on_its_own():
    cal = BundleData.from_bundle(BOWED).calibration
    degree, _, bow = calibration_degree(cal.temp_c, cal.read_c)
    assert degree == 2 and bow > 10
    cal = WITH_CAL.calibration
    assert calibration_degree(cal.temp_c, cal.read_c)[::2] == (1, 0.0)


@pytest.mark.parametrize(("bundle", "calibration", "added"), OWN)
def test_an_effect_its_own_data_show_is_added_where_the_best_is_refused(scripted, bundle,
                                                                        calibration, added):
    """After an approximate first effect, the best second one only bends its misfit (refused,
    weighed under the correlation of what it leaves); a TSP that leaves a trend elsewhere too
    but takes the calibration's misfit, data no other effect changes that show a bow on their
    own, is added in its place; not when the calibration keeps its misfit in the model, nor
    when its own points show no bow (what the model took there was the shared line's)."""
    data = BundleData.from_bundle(bundle)
    sensor = _fit((FIRST, SENSOR), 8.0, data, calibration=calibration)
    after = {(): [(_fit((FIRST,), 8.0, data), 5000.0)],
             (FIRST.name,): [(_fit((FIRST, SECOND), 6.0, data), 200.0), (sensor, 150.0)]}
    d = scripted(after=after, bundle=bundle)
    refused = d.to_dict()["refused"]
    assert (refused is None) if added else (refused["effect"] == SECOND.name)
    assert d.effects == ([FIRST.name, SENSOR.name] if added else [FIRST.name])
    assert d.verdict.cls == "approximate" and not d.steps[-1].tied


@pytest.mark.parametrize(("bundle", "calibration", "added"), OWN)
def test_a_step_cut_by_the_budget_takes_an_effect_its_own_data_show(scripted, bundle,
                                                                    calibration, added):
    """The budget is spent by the first step and the best screened on the model held leaves a
    trend: a TSP that takes the calibration's bow (data no candidate left unweighed could
    change) is taken, and the verdict says where the budget stopped the search; not when the
    calibration keeps its misfit, nor when its own points show no bow."""
    data = BundleData.from_bundle(bundle)
    at = _fit((FIRST, SENSOR), 8.0, data, calibration=calibration)
    after = {(): [(_fit((FIRST,), 8.0, data), 5000.0)], (FIRST.name,): [(at, 300.0)]}
    d = scripted(after=after, cost=1000, budget=1000, held=at, bundle=bundle)
    assert d.effects == ([FIRST.name, SENSOR.name] if added else [FIRST.name])
    if added:
        assert d.steps[-1].model is at and d.verdict.cls == "approximate"
        assert "was spent after step 2" in d.spent.stopped and d.spent.stopped in d.verdict.reason
        assert d.verdict.reason.endswith(f"{SENSOR.name} screened on the model held): "
                                         f"{SENSOR.name} is shown by data none of them changes")


@pytest.mark.parametrize("left", [0.0, 8.0])
def test_the_best_screened_on_the_model_held_is_refitted_jointly_once(scripted, left):
    """The screen on the model held leaves a trend (the ladder and the first effect took part
    of its misfit): that candidate alone is refitted jointly, and the step is taken when the
    refit brings every data set to its noise, as refitted; not when it leaves the trend."""
    transient = Effect.create("electrical-transient")
    at, joint = _fit((FIRST, transient), 8.0), _fit((FIRST, transient), left)
    after = {(): [(_fit((FIRST,), 8.0), 5000.0)], (FIRST.name,): [(at, 300.0)]}
    d = scripted(after=after, cost=1000, budget=1000, held=at, refits={id(at): joint})
    if left:
        assert d.effects == [FIRST.name] and d.verdict.cls == "approximate"
    else:
        assert d.effects == [FIRST.name, transient.name] and d.verdict.cls == "named"
        assert d.steps[-1].model is joint
        # the criterion's fall is the refit's, not the screen's
        n = d.n_points
        assert d.steps[-1].chosen.delta_bic == pytest.approx(
            bic(d.steps[0].model, n) - bic(joint, n))


def test_once_the_work_is_spent_the_ladders_stop_growing(monkeypatch):
    """A candidate that leaves a structured residual grows while work is left, not after."""
    asked = []

    def grow(data, noise, form, rounds, short, affords, last):
        asked.append(short(form.fit) and affords(0))
        return form.fit, 0, last

    monkeypatch.setattr(procedure, "grow", grow)
    base, form = _fit((), 40.0), FormFit(_fit((FIRST,), 8.0), ())
    for left in (True, False):
        procedure._weigh(DATA, NOISE, base, comparison_of(DATA, base.predictions),
                         {FIRST.name: [form]}, sum(DATA.sizes().values()), DATA.sizes(),
                         lambda cost, left=left: left)
    assert asked == [True, False]


def test_a_longer_ladder_starts_only_when_the_work_left_affords_one_like_the_last(
        monkeypatch):
    """Each longer ladder costs 1,000 and lowers the criterion: with 2,500 to spend, a
    third is not started (1,000 more after 2,000 spent does not fit); the first needs only
    some work left."""
    calls = []

    def longer(data, noise, fit, rounds, seeds, go_on):
        calls.append(fit.ladder.order)
        _spend(1000 - STEP_SOLVES)
        more = Cauer([*fit.ladder.r, 1.0], [*fit.ladder.c, 1.0])
        return replace(fit, ladder=more, chi2={n: v / 2 for n, v in fit.chi2.items()})

    monkeypatch.setattr(search, "_longer", longer)
    form = FormFit(_fit((FIRST,), 8.0), ())
    with metered() as meter:
        grown, _, last = search.grow(DATA, NOISE, form, 3, lambda m: True,
                                     lambda cost: meter.cost + cost < 2500)
    assert calls == [1, 2] and grown.ladder.order == 3 and meter.cost == 2000
    assert last == 1000
    calls.clear()
    search.grow(DATA, NOISE, form, 3, lambda m: True, lambda cost: False)
    assert calls == []


def test_a_longer_ladder_stops_fitting_once_the_work_left_affords_nothing(monkeypatch):
    """A longer ladder's fit asks whether to go on, counting what it spent so far: with
    1,500 to spend, it goes on after 600 and 1,200, not after 1,800."""
    answers = []

    def longer(data, noise, fit, rounds, seeds, go_on):
        for _ in range(3):
            _spend(600 - STEP_SOLVES)
            answers.append(go_on())

    monkeypatch.setattr(search, "_longer", longer)
    with metered() as meter:
        search.grow(DATA, NOISE, FormFit(_fit((FIRST,), 8.0), ()), 3, lambda m: True,
                    lambda cost: meter.cost + cost < 1500)
    assert answers == [True, True, False]


def test_a_candidate_grows_only_when_the_work_left_affords_a_ladder_like_the_last(
        monkeypatch):
    """The growth of a step's candidates shares the last longer ladder's cost: with 2,500
    to spend and each candidate's first longer ladder costing 1,000 (its last), the first
    candidate grows one from nothing spent, the second one from 1,000 spent (2,000 fits),
    and the third none (3,000 does not fit, though some budget is left)."""
    calls = []

    def longer(data, noise, fit, rounds, seeds, go_on):
        calls.append(fit.effects[-1].name)
        _spend(1000 - STEP_SOLVES)

    monkeypatch.setattr(search, "_longer", longer)
    monkeypatch.setattr(procedure, "short", lambda data, fit: True)
    base = _fit((), 40.0)
    third = Effect.create("reference-drift", rate_k_per_s=1e-3)
    fitted = {e.name: [FormFit(_fit((e,), 8.0), ())] for e in (FIRST, SECOND, third)}
    with metered() as meter:
        procedure._weigh(DATA, NOISE, base, comparison_of(DATA, base.predictions), fitted,
                         sum(DATA.sizes().values()), DATA.sizes(),
                         lambda cost: meter.cost + cost < 2500)
    assert calls == [FIRST.name, SECOND.name] and meter.cost == 2000


def test_a_step_that_could_not_fit_any_candidate_is_not_taken(scripted):
    d = scripted((_fit((FIRST,), 0.0), 5000.0), budget=0)
    assert not d.steps and d.verdict.cls == "none" and not d.effects
    assert d.spent.stopped.startswith("the work budget (a cost of 0) was spent in step 1 "
                                      "before ")
    assert d.verdict.reason.startswith(d.spent.stopped + ": nothing is named")


def test_a_step_cut_by_the_budget_is_taken_only_when_its_best_is_at_the_noise(scripted):
    """The budget is spent after two effects were fitted: their best, at the noise, is
    added (the others could at most tie with it) and the verdict says which were not
    weighed; a best that leaves a structured residual is not."""
    d = scripted((_fit((FIRST,), 8.0), 5000.0), cut_after=2, budget=20_000)
    assert not d.steps and d.verdict.cls == "none"
    assert d.spent.stopped.startswith("the work budget (a cost of 20,000) was spent in step 1 "
                                      "before ")
    d = scripted((_fit((FIRST,), 8.0), 5000.0))  # uncut: named, an approximate form
    assert d.effects == [FIRST.name] and d.verdict.cls == "approximate"
    d = scripted((_fit((FIRST,), 0.0), 5000.0), cut_after=2, budget=20_000)
    assert d.effects == [FIRST.name] and d.verdict.cls == "named"
    assert d.spent.stopped.startswith("the work budget (a cost of 20,000) was spent in step 1 "
                                      "before ")
    assert d.spent.stopped.endswith(f"could at most tie with {FIRST.name}, which brings every "
                                    "data set to its noise")
    assert d.verdict.reason.endswith(d.spent.stopped)
    d = scripted((_fit((FIRST,), 0.0), 5000.0), cut_after=0, budget=20_000)  # none fitted
    assert not d.steps and d.verdict.cls == "none"


def test_a_later_step_fits_the_effects_in_closed_form_first(scripted):
    """Each step fits the effects in closed form first, then the simulated ones: the first
    step each group in the registry's order, the next one in the order of the first step's
    candidates (each effect's gain alone), then the effects that had none."""
    transient = Effect.create("electrical-transient")
    after = {(): [(_fit((SECOND,), 8.0), 5000.0), (_fit((FIRST,), 9.0), 900.0),
                  (_fit((transient,), 9.0), 400.0)],
             (SECOND.name,): [(_fit((SECOND, FIRST), 0.0), 300.0)]}
    asked: list = []
    d = scripted(after=after, asked=asked)
    assert d.effects == [SECOND.name, FIRST.name]
    step1 = [name for model, name in asked if not model]
    step2 = [name for model, name in asked if model == (SECOND.name,)]
    def costly(n: str) -> bool:
        return plugin(n).traits.cost > CLOSED_FORM_COST

    assert step1 == sorted(step1, key=lambda n: (costly(n), list(CATALOGUE).index(n)))
    assert len(step1) > 3 and costly(step1[-1]) and not costly(step1[0])
    closed = [n for n in step1 if not costly(n)]
    assert FIRST.name not in closed and transient.name in closed and len(closed) > 1
    assert step2[0] == transient.name  # ranked, behind the costly FIRST
    assert step2[1:len(closed)] == [n for n in closed if n != transient.name]
    assert step2[len(closed):] == [n for n in step1 if n not in closed and n != SECOND.name]
    assert FIRST.name in step2[len(closed):]


def test_the_next_best_first_effect_replaces_steps_that_end_beyond_the_noise(scripted):
    """The best effect alone (a temperature coefficient) leaves no second effect a way to
    the noise; with the next best (a phase change) first, a sample window brings every data
    set to it: those steps are taken, and the verdict says why."""
    window = Effect.create("sample-window", window_s=1e-4)
    after = {(): [(_fit((FIRST,), 8.0), 5000.0), (_fit((SECOND,), 9.0), 4000.0)],
             (FIRST.name,): [(_fit((FIRST, window), 6.0), 300.0)],
             (SECOND.name,): [(_fit((SECOND, window), 0.0), 900.0)]}
    d = scripted(after=after)
    assert d.effects == [SECOND.name, window.name] and d.verdict.cls == "named"
    assert [c.name for c in d.candidates] == [FIRST.name, SECOND.name]
    assert not d.steps[0].tied
    assert (f"{SECOND.name} is added first although {FIRST.name} alone lowers the criterion "
            f"more (by 1000.0)") in d.verdict.reason
    # when the next best's steps end beyond the noise too, the lower criterion at the end
    # decides: the best's stand when the next best's end no lower ...
    after[(SECOND.name,)] = [(_fit((SECOND, window), 8.0), 900.0)]
    d = scripted(after=after)
    assert d.effects == [FIRST.name] and d.verdict.cls == "approximate"
    # ... and the next best's replace them when it is lower by 10 or more
    after[(SECOND.name,)] = [(_fit((SECOND, window), 2.0), 900.0)]
    d = scripted(after=after)
    assert d.effects == [SECOND.name, window.name] and d.verdict.cls == "approximate"
    assert f"{SECOND.name} is added first although {FIRST.name}" in d.verdict.reason


def test_a_screen_on_the_model_held_fits_the_measurement_effects_only(monkeypatch):
    """Each measurement effect's every form, screened on the model's ladder and effects held:
    the ladder as it was, χ² no higher than the model's (noiseless data), its work that of
    its screens, counted once; a device effect is not screened."""
    base, noise = procedure._baseline(DATA, None)
    plugins = [plugin(n) for n in CATALOGUE]
    screens, fit_starts = [], search.fit_starts

    def counted(*a, **k):
        got = fit_starts(*a, **k)
        screens.append(sum(m.work for m in got if m is not None))
        return got

    monkeypatch.setattr(search, "fit_starts", counted)
    got = search.screen_held(DATA, noise, base, plugins, 3)
    assert sum(f.fit.work for forms in got.values() for f in forms) == sum(screens) > 0
    measured = [p.name for p in plugins if isinstance(p, MeasurementEffect)
                and p.traits.shown_by & DATA.kinds]
    assert sorted(got) == sorted(measured) and FIRST.name not in got
    for name, forms in got.items():
        assert [f.fit.effect(name).form for f in forms] == list(plugin(name).forms)
        for f in forms:
            assert np.allclose(f.fit.ladder.r, base.ladder.r, rtol=1e-9, atol=0)
            assert np.allclose(f.fit.ladder.c, base.ladder.c, rtol=1e-9, atol=0)
            assert f.fit.chi2_total <= base.chi2_total + 1e-6


def test_the_budget_stops_an_effect_between_its_forms():
    """``left()`` is asked before each form's screen and before its joint refits: once it
    says no, no further form is fitted and the fits say they were cut short."""
    base, noise = procedure._baseline(DATA, None)
    plugin = Effect.create("electrical-transient").plugin
    whole, done = procedure.fit_effect(DATA, noise, base, plugin, 3, 3)
    assert done and len(whole) == len(plugin.forms) > 1
    asked = []
    cut, done = procedure.fit_effect(DATA, noise, base, plugin, 3, 3,
                                     left=lambda: asked.append(1) or len(asked) < 3)
    assert not done and len(asked) == 3 and len(cut) == 1
    assert cut[0].fit.chi2 == whole[0].fit.chi2  # the first form, fitted alike


def test_a_candidate_cut_between_its_forms_stops_the_step(scripted, monkeypatch):
    """A step in which the budget cut a candidate's forms short is not taken."""
    scripted((_fit((FIRST,), 0.0), 5000.0))  # the procedure scripted, then every fit cut
    monkeypatch.setattr(procedure, "fit_effect", lambda *a, **k: ([], False))
    d = diagnose(BUNDLE)
    assert not d.steps and d.verdict.cls == "none"
    assert d.spent.stopped.startswith(f"the work budget (a cost of {d.spent.budget:,}) was "
                                      "spent in step 1 before ")
