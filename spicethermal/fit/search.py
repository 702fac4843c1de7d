"""Fitting an effect onto a model: every form, every discrete variant, a few starts.

:func:`fit_effect` adds one effect (a plugin) to a fitted model. For each form it fits the
effect's own parameters from every start that the plugin's ``guess()`` gives for each of its
variants (a node, a subset of layers), the ladder and the model's other effects held (a
*screen*, all side by side); the best screened point of each form is then refitted jointly
with the ladder and every other effect. :func:`refit` refits a model's every parameter;
:func:`without` drops one effect and refits the rest.

The work is counted in rounds (:mod:`spicethermal.fit.lm`), never timed.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np

from ..effects.base import CurveEvidence, EffectPlugin, Evidence
from ..engines.network import NetworkBatch
from .joint import Layout, ModelFit, Start, fit_starts
from .measurement import BundleData

if TYPE_CHECKING:  # pragma: no cover
    pass

__all__ = ["evidence", "fit_effect", "refit", "without"]


def evidence(data: BundleData, model: ModelFit, noise: Mapping[str, float]) -> Evidence:
    """What ``model`` leaves unexplained, as the plugins' ``guess()`` reads it.

    Parameters
    ----------
    data : BundleData
    model : ModelFit
    noise : mapping of data set name to noise (K)

    Returns
    -------
    Evidence
    """
    net = NetworkBatch.of(model.ladder, model.effects)
    curves = []
    for c in data.cooling:
        nodes = net.steady(c.power_w, c.tref_steady_c)[0] + c.tref_steady_c
        curves.append(CurveEvidence(c.t_s, c.tj_c, model.predictions[c.name], c.power_w,
                                    c.tref_steady_c, nodes))
    pwm = None
    if data.pwm is not None:
        p = data.pwm
        pwm = (p.freq_hz, p.duty, p.power_w, p.tj_c, model.predictions["pwm"])
    cal = None
    if data.calibration is not None:
        cal = (data.calibration.temp_c, data.calibration.read_c)
    foster = model.foster
    return Evidence(cooling=tuple(curves), pwm=pwm,
                    declared_window_s=data.pwm.window_s if data.pwm is not None else 0.0,
                    calibration=cal, rth_k_per_w=foster.rth, n_nodes=model.ladder.order,
                    node_c_j_per_k=tuple(model.ladder.c), tau_s=tuple(sorted(foster.tau)),
                    reference_c=data.reference_c, noise_k=dict(noise),
                    in_volts=data.line_temps_c is not None)


def _slots(model: ModelFit) -> tuple[tuple[EffectPlugin, str], ...]:
    return tuple((e.plugin, e.form) for e in model.effects)


def _values(model: ModelFit) -> tuple[dict[str, float], ...]:
    return tuple(dict(e.params) for e in model.effects)


def refit(data: BundleData, noise: Mapping[str, float], model: ModelFit,
          rounds: int) -> ModelFit:
    """``model`` with its ladder and every effect refitted jointly (kept as it was when the
    refit does not lower χ²).

    Parameters
    ----------
    data : BundleData
    noise : mapping of data set name to noise (K)
    model : ModelFit
    rounds : int

    Returns
    -------
    ModelFit
    """
    layout = Layout(_slots(model), model.ladder.order)
    got = fit_starts(data, noise, layout, [Start(model.ladder, _values(model))], rounds)
    if got and got[0].chi2_total <= model.chi2_total:
        return got[0]
    return model


def without(data: BundleData, noise: Mapping[str, float], model: ModelFit, name: str,
            rounds: int) -> ModelFit:
    """``model`` without effect ``name``, the rest refitted.

    Parameters
    ----------
    data : BundleData
    noise : mapping of data set name to noise (K)
    model : ModelFit
    name : str
    rounds : int

    Returns
    -------
    ModelFit
    """
    keep = tuple(e for e in model.effects if e.name != name)
    slots = tuple((e.plugin, e.form) for e in keep)
    got = fit_starts(data, noise, Layout(slots, model.ladder.order),
                     [Start(model.ladder, tuple(dict(e.params) for e in keep))], rounds)
    if not got:
        raise ValueError(f"the model without {name} does not fit")
    return got[0]


def _clip(plugin: EffectPlugin, values: Mapping[str, float]) -> dict[str, float]:
    return {k: float(np.clip(v, plugin.params[k].low, plugin.params[k].high))
            for k, v in values.items()}


def fit_effect(data: BundleData, noise: Mapping[str, float], model: ModelFit,
               plugin: EffectPlugin, screen_rounds: int, refine_rounds: int,
               forms: Sequence[str] | None = None) -> list[ModelFit]:
    """``model`` with ``plugin``'s effect added, the best fit of each form (see the module
    docstring); forms whose guess gives no start are left out.

    Parameters
    ----------
    data : BundleData
    noise : mapping of data set name to noise (K)
    model : ModelFit
        The model so far (the effect must not be in it).
    plugin : EffectPlugin
    screen_rounds, refine_rounds : int
        Rounds of the screen and of the joint refit.
    forms : sequence of str, optional
        The forms to fit (default: all).

    Returns
    -------
    list of ModelFit
        One per form fitted, in the plugin's order of forms.
    """
    ev = evidence(data, model, noise)
    n = model.ladder.order
    slots, values = _slots(model), _values(model)
    defaults = {k: p.default for k, p in plugin.params.items()}
    out = []
    for form in forms or plugin.forms:
        starts = [Start(model.ladder, (*values, _clip(plugin, {**defaults, **v, **s})))
                  for v in plugin.variants(form, ev) for s in plugin.guess(form, v, ev)]
        if not starts:
            continue
        screen = Layout((*slots, (plugin, form)), n, hold_ladder=True,
                        move=(False,) * len(slots) + (True,))
        screened = fit_starts(data, noise, screen, starts, screen_rounds)
        if not screened:
            continue
        best = min(screened, key=lambda m: m.chi2_total)
        full = Layout((*slots, (plugin, form)), n)
        refined = fit_starts(data, noise, full,
                             [Start(best.ladder, tuple(dict(e.params) for e in best.effects))],
                             refine_rounds)
        work = sum(m.work for m in screened)
        pick = refined[0] if refined and refined[0].chi2_total <= best.chi2_total else best
        out.append(ModelFit(pick.ladder, pick.effects, pick.predictions, pick.chi2,
                            pick.n_params, work + (refined[0].work if refined else 0),
                            pick.converged))
    return out
