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

__all__ = ["SCREEN_TOL_REL", "VARIANTS_KEPT", "evidence", "fit_effect", "refit", "without"]

#: A screen only ranks starts: its transients may be coarser than the network's own tolerance
#: (a few mK on tens of K); every model it returns is evaluated at the network's tolerance.
SCREEN_TOL_REL = 1e-4
#: The first form of an effect locates its discrete variants (a node, a subset of layers);
#: the other forms that take the same variants are screened on this many of the best only.
VARIANTS_KEPT = 2


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
                    in_volts=data.in_volts)


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
    got = fit_starts(data, noise, layout, [Start(model.ladder, _values(model))], rounds)[0]
    return got if got is not None and got.chi2_total <= model.chi2_total else model


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
                     [Start(model.ladder, tuple(dict(e.params) for e in keep))], rounds)[0]
    if got is None:
        raise ValueError(f"the model without {name} does not fit")
    return got


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
    slots, values = _slots(model), _values(model)
    defaults = {k: p.default for k, p in plugin.params.items()}
    ranked: dict[frozenset[str], list[Mapping[str, float]]] = {}
    out = []
    for form in forms or plugin.forms:
        variants = list(plugin.variants(form, ev))
        keys = frozenset().union(*(v.keys() for v in variants))
        if keys and keys in ranked:
            variants = [v for v in ranked[keys] if v in variants][:VARIANTS_KEPT] or variants
        pairs = [(v, s) for v in variants for s in plugin.guess(form, v, ev)]
        if not pairs:
            continue
        starts = [Start(model.ladder, (*values, _clip(plugin, {**defaults, **v, **s})))
                  for v, s in pairs]
        screen = Layout((*slots, (plugin, form)), model.ladder.order, hold_ladder=True,
                        move=(False,) * len(slots) + (True,))
        got = fit_starts(data, noise, screen, starts, screen_rounds, tol_rel=SCREEN_TOL_REL)
        done = [i for i, m in enumerate(got) if m is not None]
        if not done:
            continue
        done.sort(key=lambda i: got[i].chi2_total)  # type: ignore[union-attr]
        if keys and keys not in ranked:
            ranked[keys] = [dict(v) for v in dict.fromkeys(
                tuple(sorted(pairs[i][0].items())) for i in done)]
        best = got[done[0]]
        assert best is not None
        full = Layout((*slots, (plugin, form)), model.ladder.order)
        refined = fit_starts(data, noise, full,
                             [Start(best.ladder, tuple(dict(e.params) for e in best.effects))],
                             refine_rounds)[0]
        work = sum(m.work for m in got if m is not None) + (refined.work if refined else 0)
        pick = refined if refined is not None and refined.chi2_total <= best.chi2_total \
            else best
        out.append(ModelFit(pick.ladder, pick.effects, pick.predictions, pick.chi2,
                            pick.n_params, work, pick.converged))
    return out
