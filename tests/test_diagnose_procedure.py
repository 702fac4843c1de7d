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
    """Runs the procedure with the candidates of each step given in order (and ``lighter``
    as the model without each earlier effect, when given)."""
    def run(*steps: tuple[ModelFit, float], lighter: ModelFit | None = None):
        base = _fit((), 40.0)
        monkeypatch.setattr(procedure, "_baseline", lambda data, model: (base, NOISE))
        monkeypatch.setattr(procedure, "fit_effect", lambda *a, **k: [])
        monkeypatch.setattr(procedure, "refit", lambda data, noise, fit, rounds: fit)

        def without(*a, **k):  # the model without an earlier effect: none, or ``lighter``
            if lighter is None:
                raise FitError("scripted")
            return lighter

        monkeypatch.setattr(procedure, "without", without)
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
