"""The fit of any catalogued effect by name: the fitters, the choice among an effect's forms,
the nested-model guarantee, and models with effects fitted (``spicethermal fit --effect``).

Each effect's catalogue entry names its fit (``EffectSpec.fit``, ``"module:function"``,
imported when first used, as an entry point is): :mod:`spicethermal.fit.tcfit`
(``temperature-coefficient``), :mod:`spicethermal.fit.pcfit` (``phase-change``) and
:mod:`spicethermal.fit.measfit` (the measurement effects); a plugin effect names its own.
"""

from __future__ import annotations

import importlib
import math
from collections.abc import Callable, Mapping, Sequence
from typing import TYPE_CHECKING, Any

from ..core.errors import FitError, SimulationError
from ..effects import Effect, spec
from ..model import ThermalModel
from .effectfit import (
    NUMERICAL_ERRORS,
    BundleData,
    EffectFit,
    as_foster,
    baseline_ladder,
    needs,
    others,
    sse,
    switched_off,
    unlimited,
)

if TYPE_CHECKING:  # pragma: no cover
    from ..core.ladder import Cauer, Foster
    from ..io.bundle import Bundle

__all__ = ["FORM_BIC_MARGIN", "choose_form", "fit_effect", "fit_effect_forms", "fitter",
           "fit_with_effects"]

#: A form other than an effect's default is kept only when it lowers the BIC by more than this.
FORM_BIC_MARGIN = 10.0



def fitter(name: str) -> Callable[..., list[EffectFit]] | None:
    """The function that fits effect ``name`` (its catalogue entry's ``fit``), ``None`` when
    the effect has none; an unknown name is the catalogue's error.

    Parameters
    ----------
    name : str
        A catalogue name.

    Returns
    -------
    callable or None
        ``fit(data, ladder, effects) -> list[EffectFit]``, one fit per form.

    >>> fitter("temperature-coefficient").__module__
    'spicethermal.fit.tcfit'
    """
    ref = spec(name).fit
    if not ref:
        return None
    module, _, function = ref.partition(":")
    return getattr(importlib.import_module(module), function)


def fit_effect_forms(data: BundleData, ladder: Foster | Cauer, name: str,
                     effects: Sequence[Effect] = ()) -> list[EffectFit]:
    """Every form of effect ``name`` fitted on top of ``ladder`` and ``effects``.

    A nested model never fits worse than the model it extends: a form whose fit leaves a
    larger squared error than ``ladder`` and ``effects`` alone is replaced by the effect
    switched off (:func:`switched_off`) on ``ladder`` (``facts["no_gain"]``; the fit itself
    is ``facts["tried"]``). Raises
    :class:`~spicethermal.core.errors.FitError` when the data cannot show the effect.
    """
    fit_forms = fitter(name)
    if fit_forms is None:
        raise FitError(f"effect {name!r} has no fit")
    why = needs(name, data)
    if why:
        raise FitError(f"cannot fit {name}: {why}")
    rest = others(effects, name)
    out = []
    fits = fit_forms(data, ladder, effects)
    with unlimited():
        off = sse(data, ladder, rest)
    for fit in fits:
        try:
            with unlimited():
                worse = sse(data, fit.ladder, [*rest, fit.effect]) > off
        except (SimulationError, *NUMERICAL_ERRORS):
            worse = True
        if worse:  # the fit itself is kept in the facts (a joint refit may still use it)
            fit = EffectFit(switched_off(name, fit.effect.form, data), as_foster(ladder),
                            fit.n_params, {**fit.facts, "no_gain": True, "tried": fit})
        out.append(fit)
    return out


def fit_effect(data: BundleData, ladder: Foster | Cauer, name: str,
               effects: Sequence[Effect] = ()) -> EffectFit:
    """Fit effect ``name`` (catalogue name) on top of ``ladder`` and ``effects``: the form
    with the lowest ``N ln(SSE/N) + k ln N`` over every point (see :func:`fit_effect_forms`).

    Raises :class:`~spicethermal.core.errors.FitError` when the data cannot show the effect.

    Examples
    --------
    >>> from spicethermal.analysis.scenarios import scenario_bundle
    >>> data = BundleData.from_bundle(scenario_bundle("temperature-coefficient", seed=0))
    >>> fit = fit_effect(data, baseline_ladder(data), "temperature-coefficient")
    >>> round(fit.effect.params["alpha_per_k"], 4), fit.n_params, fit.effect.form
    (-0.003, 1, 'junction')
    """
    fits = fit_effect_forms(data, ladder, name, effects)
    n = max(sum(data.measured(d).size for d in data.datasets), 2)
    rest = others(effects, name)

    def bic(fit: EffectFit) -> float:
        err = max(sse(data, fit.ladder, [*rest, fit.effect]), 1e-300)
        return n * math.log(err / n) + fit.n_params * math.log(n)

    return fits[choose_form([bic(f) for f in fits])]


def choose_form(bics: Sequence[float]) -> int:
    """Index of the form to keep among forms with criteria ``bics`` (first = the default
    form): the default unless another lowers the criterion by more than
    :data:`FORM_BIC_MARGIN`.

    >>> choose_form([100.0, 95.0]), choose_form([100.0, 80.0, 85.0])
    (0, 1)
    """
    low = min(range(len(bics)), key=lambda i: bics[i])
    return low if bics[low] < bics[0] - FORM_BIC_MARGIN else 0


def fit_with_effects(bundle: Bundle, names: Sequence[str], order: int | str = "auto",
                     provenance: Mapping[str, Any] | None = None,
                     base: ThermalModel | None = None) -> ThermalModel:
    """A model of ``bundle`` with the named effects fitted.

    Starts from ``base`` (its ladder and effects) or else from :func:`baseline_ladder` (the
    lowest-power cooling curve's ladder refitted to every cooling curve), then fits each
    named effect in turn (the ladder refitted where the effect needs it, see
    :func:`fit_effect`).

    Examples
    --------
    >>> from spicethermal.analysis.scenarios import scenario_bundle
    >>> m = fit_with_effects(scenario_bundle("sample-window", seed=0), ["sample-window"])
    >>> round(m.effect("sample-window").params["window_s"] * 1e6)
    99
    """
    data = BundleData.from_bundle(bundle)
    if base is not None:
        ladder: Foster = as_foster(base.ladder)
        effects: list[Effect] = list(base.effects)
        reference = base.reference
        prov = {**dict(base.provenance), **dict(provenance or {})}
    else:
        ladder = baseline_ladder(data, order)
        effects = []
        reference = bundle.reference
        prov = dict(provenance or {})
    for name in names:
        fitted = fit_effect(data, ladder, name, effects)
        ladder = fitted.ladder
        effects = [*others(effects, name), fitted.effect]
    prov["effects_fit"] = {"method": "spicethermal.fit.effectfit", "effects": list(names),
                           "params": {e.name: dict(e.params) for e in effects}}
    return ThermalModel(ladder, tuple(effects), reference, prov)
