"""The diagnosis's procedure on scripted candidates (the fits replaced by fixed models whose
residuals are either at the noise or structured): which effects it adds and when it stops."""

from __future__ import annotations

import numpy as np
import pytest

import spicethermal.analysis.diagnose as procedure
from spicethermal.analysis.diagnose import comparison_of, diagnose
from spicethermal.analysis.diagnosis import Candidate
from spicethermal.core.errors import FitError
from spicethermal.core.ladder import Cauer
from spicethermal.effects import Effect
from spicethermal.fit.joint import ModelFit
from spicethermal.fit.measurement import BundleData
from spicethermal.io.bundle import Bundle, CoolingTable

T = np.geomspace(1e-4, 10.0, 40)
BUNDLE = Bundle(ambient_c=25.0, cooling=(CoolingTable(
    T, 0.5, tj_c=25.0 + 10.0 * np.exp(-T), tj_steady_c=35.0, tref_steady_c=25.0),))
DATA = BundleData.from_bundle(BUNDLE)
NOISE = {n: 0.01 for n in DATA.datasets}
FIRST = Effect.create("temperature-coefficient", alpha_per_k=-3e-3)
SECOND = Effect.create("phase-change", t_c=30.0, width_k=2.0, latent_j=1e-3)


def _fit(effects: tuple, structured: float) -> ModelFit:
    """A model whose residual on every data set is the noise alternating in sign plus, when
    ``structured`` > 0, a trend of that many noises (a misfit the data set shows)."""
    preds, chi2 = {}, {}
    for n in DATA.datasets:
        size = DATA.measured(n).size
        res = NOISE[n] * ((-1.0) ** np.arange(size) + structured * np.linspace(-1, 1, size))
        preds[n], chi2[n] = DATA.measured(n) - res, float(np.sum((res / NOISE[n]) ** 2))
    return ModelFit(Cauer([20.0], [1e-2]), effects, preds, chi2, 2 + 2 * len(effects), 10, True)


def _candidate(current: ModelFit, fit: ModelFit, delta_bic: float) -> Candidate:
    cmp, after = comparison_of(DATA, current.predictions), comparison_of(DATA, fit.predictions)
    return Candidate(fit.effects[-1], fit, after, delta_bic, 0.9, cmp.rms_k / after.rms_k)


@pytest.fixture
def scripted(monkeypatch):
    """Runs the procedure with the candidates of each step given in order."""
    def run(*steps: tuple[ModelFit, float]):
        base = _fit((), 40.0)
        monkeypatch.setattr(procedure, "_baseline", lambda data, model: (base, NOISE))
        monkeypatch.setattr(procedure, "fit_effect", lambda *a, **k: [])
        monkeypatch.setattr(procedure, "refit", lambda data, noise, fit, rounds: fit)

        def no_lighter(*a, **k):
            raise FitError("scripted")

        monkeypatch.setattr(procedure, "without", no_lighter)
        script = list(steps)

        def weigh(data, noise, model, cmp, fitted, n_points, sizes):
            if not script:
                return [], 0
            fit, gain = script.pop(0)
            return [_candidate(model, fit, gain)], 0

        monkeypatch.setattr(procedure, "_weigh", weigh)
        return diagnose(BUNDLE)
    return run


def test_a_further_effect_that_leaves_a_structured_residual_too_is_not_added(scripted):
    d = scripted((_fit((FIRST,), 8.0), 5000.0), (_fit((FIRST, SECOND), 3.0), 200.0))
    assert d.effects == [FIRST.name]
    assert d.verdict.cls == "approximate"


def test_a_further_effect_that_brings_every_data_set_to_its_noise_is_added(scripted):
    d = scripted((_fit((FIRST,), 8.0), 5000.0), (_fit((FIRST, SECOND), 0.0), 200.0))
    assert d.effects == [FIRST.name, SECOND.name]
    assert d.verdict.cls == "named"


def test_a_first_effect_is_added_even_when_it_leaves_a_residual(scripted):
    d = scripted((_fit((FIRST,), 8.0), 5000.0))
    assert d.effects == [FIRST.name] and d.verdict.cls == "approximate"


def test_a_rival_chosen_stops_the_steps_and_nothing_is_named(scripted):
    rival = Effect.create("power-error", gamma_per_w=0.1)
    d = scripted((_fit((rival,), 8.0), 5000.0), (_fit((rival, FIRST), 0.0), 900.0))
    assert [s.chosen.name for s in d.steps] == [rival.name]
    assert d.verdict.cls == "none" and not d.effects


def test_a_candidate_grows_two_stages_at_most(monkeypatch):
    from spicethermal.fit import search
    from spicethermal.fit.search import MAX_GROWTH, FormFit, grow

    def longer(data, noise, fit, rounds, seeds):  # every stage more lowers χ² a lot
        n = fit.ladder.order + 1
        return ModelFit(Cauer([20.0 / n] * n, [1e-2] * n), fit.effects, fit.predictions,
                        {k: v / 2 for k, v in fit.chi2.items()}, fit.n_params + 2, fit.work + 1,
                        True)

    monkeypatch.setattr(search, "_longer", longer)
    start = _fit((FIRST,), 40.0)
    grown, _ = grow(DATA, NOISE, FormFit(start, ()), 30, lambda fit: True)
    assert grown.ladder.order == start.ladder.order + MAX_GROWTH
