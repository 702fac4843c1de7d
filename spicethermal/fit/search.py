"""Fitting an effect onto a model: every form, every discrete variant, a few starts.

:func:`fit_effect` adds one effect (a plugin) to a fitted model. For each form it fits the
effect's own parameters from every start that the plugin's ``guess()`` gives for each of its
variants (a node, a subset of layers), the ladder and the model's other effects held (a
*screen*, all side by side, on the model's ladder); the best screened point of each form (of
its two best variants for the first form, which ranks the variants for the forms that share
them) is then refitted jointly with the ladder and every other effect, every form alike.
:func:`screen_held` only screens the measurement effects, on the model held (a fit keeps its
last simulation, so each costs one simulation of the device). :func:`grow` refits a form's
fit on longer ladders; :func:`refit` refits a model's every parameter; :func:`without` drops
one effect and refits the rest.

The work is counted in rounds (:mod:`spicethermal.fit.lm`), never timed.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np

from ..core.errors import SimulationError
from ..core.ladder import Cauer
from ..effects.base import CurveEvidence, EffectPlugin, Evidence, MeasurementEffect, overrides
from ..engines.meter import metered
from ..engines.network import NetworkBatch
from .forward import predict_model, pwm_correction
from .joint import (
    MAX_ORDER,
    ORDER_PATIENCE,
    Layout,
    ModelFit,
    Start,
    bic,
    chi2_by_set,
    fit_starts,
    reference_order,
    stage_more,
    start_ladders,
)
from .measurement import BundleData

__all__ = ["SCREEN_TOL_REL", "VARIANTS_KEPT", "FormFit", "evidence", "fit_effect", "grow", "refit",
           "screen_held", "settle", "unshown", "without"]

#: A screen only ranks starts: its transients may be coarser than the network's own tolerance
#: (a few mK on tens of K); every model it returns is evaluated at the network's tolerance.
SCREEN_TOL_REL = 3e-4
#: The first form of an effect locates its discrete variants (a node, a subset of layers);
#: the other forms that take the same variants are screened on this many of the best only.
VARIANTS_KEPT = 2


@dataclass(frozen=True, eq=False)
class FormFit:
    """One form of an effect fitted onto a model: the joint ``fit`` and the ``screened``
    values of the effect it was refitted from (:func:`grow` starts from them too)."""

    fit: ModelFit
    screened: tuple[Mapping[str, float], ...]


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
        theta = net.steady(c.power_w, c.tref_steady_c)
        paths = net.response(theta, c.t_s, 0.0, c.tref_steady_c)[0] + c.tref_steady_c
        curves.append(CurveEvidence(c.t_s, c.tj_c, model.predictions[c.name], c.power_w,
                                    c.tref_steady_c, theta[0] + c.tref_steady_c, paths))
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
                    node_c_j_per_k=tuple(model.ladder.c),
                    layer_r_k_per_w=tuple(model.ladder.r), tau_s=tuple(sorted(foster.tau)),
                    reference_c=data.reference_c, noise_k=dict(noise),
                    in_volts=data.in_volts)


def unshown(data: BundleData, model: ModelFit, name: str, noise: Mapping[str, float]) -> str:
    """Why the plugin of ``model``'s effect ``name`` says the data cannot show it as fitted
    (:meth:`~spicethermal.effects.base.EffectPlugin.unshown`), or "". A plugin that keeps the
    default (shown) gets no evidence: none is built, a simulation of the model saved."""
    effect = model.effect(name)
    assert effect is not None
    if not overrides(effect.plugin, EffectPlugin.unshown):
        return ""
    return effect.plugin.unshown(effect, evidence(data, model, noise))


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


def settle(data: BundleData, noise: Mapping[str, float], model: ModelFit,
           rounds: int) -> tuple[BundleData, ModelFit]:
    """``model`` refitted with exact PWM readings. The fits evaluate a nonlinear model's
    periodic states in closed form (:func:`~.forward.pwm_correction`); the exact ones at
    ``model`` give each reading's correction, held while the model is refitted (a deferred
    correction: it changes slowly with the parameters), and computed again at the refit,
    which is evaluated with it.

    Parameters
    ----------
    data : BundleData
    noise : mapping of data set name to noise (K)
    model : ModelFit
    rounds : int

    Returns
    -------
    BundleData
        ``data`` with the last correction, held for the model's device effects: the fits of
        models that keep those effects (and may add others) evaluate their PWM readings
        with it.
    ModelFit
        The refit, evaluated exactly; ``data`` and ``model`` as they are without a PWM grid
        or a device effect, or when no periodic state is found (the closed form stands).
    """
    layout = Layout(_slots(model), model.ladder.order)
    fit, held, work = model, data, 0
    for refine in (rounds, 0):
        try:
            correction = pwm_correction(data, fit.ladder, fit.effects)
        except SimulationError:
            return data, model
        if correction is None:
            return data, model
        held = data.with_pwm_correction(correction, fit.effects)
        got = fit_starts(held, noise, layout, [Start(fit.ladder, _values(fit))], 0)[0]
        if got is None:
            return data, model
        fit = refit(held, noise, got, refine) if refine else got
        work += got.work + (fit.work if fit is not got else 0)
    return held, replace(fit, work=work)


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
               forms: Sequence[str] | None = None,
               left: Callable[[], bool] = lambda: True,
               joint: bool = True) -> tuple[list[FormFit], bool]:
    """``model`` with ``plugin``'s effect added, the best fit of each form (see the module
    docstring); forms whose guess gives no start are left out. Every form is screened on the
    model's ladder from the plugin's starts (for every variant in the first form, for the
    best variants in the forms that share them) and refitted jointly from its best screened
    point; a form after the first is also screened on the best joint refit's ladder from
    that refit's own values, and refitted from there when that screen is better.

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
    left : callable, optional
        Whether work is left: asked before each form's screen and before its joint refits,
        which are not started once it says no.
    joint : bool
        False: screened on the model's ladder only and not refitted jointly: each form's
        fit is its best screened point (the ladder and the other effects as they are in
        ``model``, the device simulated once).

    Returns
    -------
    list of FormFit
        One per form fitted, in the plugin's order of forms.
    bool
        False when ``left()`` cut the fits short (the list then lacks forms).
    """
    ev = evidence(data, model, noise)
    slots = _slots(model)
    defaults = {k: p.default for k, p in plugin.params.items()}
    n_points = sum(data.sizes().values())
    ranked: dict[frozenset[str], list[Mapping[str, float]]] = {}
    out: list[ModelFit] = []
    lead: ModelFit | None = None  # the best joint refit so far
    others = tuple(dict(e.params) for e in model.effects)
    seeds: list[list[dict[str, float]]] = []  # each form's screened values that were refitted

    def screen(base: ModelFit, form: str, pairs: list) -> tuple[list[ModelFit | None], int]:
        starts = [Start(base.ladder, (*others, _clip(plugin, {**defaults, **v, **s})))
                  for v, s in pairs]
        layout = Layout((*slots, (plugin, form)), base.ladder.order, hold_ladder=True,
                        move=(False,) * len(slots) + (True,))
        got = fit_starts(data, noise, layout, starts, screen_rounds, tol_rel=SCREEN_TOL_REL)
        return got, sum(m.work for m in got if m is not None)

    # the model's ladder took some of the effect into its own values (a band's heat into its
    # capacities, a coefficient's rise into its resistances): the effect is also screened on
    # the linear ladder of the least heated curve, which the effects change least
    ref = start_ladders(data, [model.ladder.order]).get(model.ladder.order) if joint else None
    at_ref = _evaluated(data, noise, ref, model) if ref is not None else None
    ev_ref = evidence(data, at_ref, noise) if at_ref is not None else None

    for form in forms or plugin.forms:
        if not left():
            return _form_fits(out, seeds), False
        variants = list(plugin.variants(form, ev))
        keys = frozenset().union(*(v.keys() for v in variants))
        if keys and keys in ranked:
            variants = [v for v in ranked[keys] if v in variants][:VARIANTS_KEPT] or variants
        pairs = [(v, s) for v in variants for s in plugin.guess(form, v, ev)]
        if not pairs:
            continue
        got, work = screen(model, form, pairs)
        if at_ref is not None and ev_ref is not None:
            more = [(v, s) for v in variants for s in plugin.guess(form, v, ev_ref)]
            if more:
                got_ref, spent = screen(at_ref, form, more)
                pairs, got, work = pairs + more, got + got_ref, work + spent
        done = sorted((i for i, m in enumerate(got) if m is not None),
                      key=lambda i: got[i].chi2_total)  # type: ignore[union-attr]
        if keys and keys not in ranked and done:
            ranked[keys] = [dict(v) for v in dict.fromkeys(
                tuple(sorted(pairs[i][0].items())) for i in done)]
        # the best screened point of each of the best variants (of the first form; one for
        # the others: their variants are ranked already), refitted jointly
        firsts = list({tuple(sorted(pairs[i][0].items())): i for i in reversed(done)}.values())
        kept = VARIANTS_KEPT if lead is None else 1
        heads = [got[i] for i in sorted(firsts, key=lambda i: got[i].chi2_total)[:kept]]
        if lead is not None:
            # and the lead's own values, as far as this form shares them, on its ladder (a
            # screen holds the ladder, which favours a variant that needs no ladder to move)
            mine = lead.effect(plugin.name)
            shared = {k: v for k, v in mine.params.items() if plugin.params[k].used_by(form)}
            there, spent = screen(lead, form, [({k: v for k, v in shared.items() if k in keys},
                                               shared)])
            work += spent
            if there[0] is not None and (not heads or
                                         there[0].chi2_total < heads[0].chi2_total):
                heads = [there[0]]
        if not heads:
            continue
        if not left():
            return _form_fits(out, seeds), False
        seeds.append([dict(m.effect(plugin.name).params) for m in heads])  # type: ignore
        # the work of a head is its share of the screens, counted in ``work`` already
        refits = [_refine(data, noise, m, refine_rounds, 0) for m in heads] if joint else []
        fit = min(refits or heads, key=lambda m: bic(m, n_points))
        fit = ModelFit(fit.ladder, fit.effects, fit.predictions, fit.chi2, fit.n_params,
                       work + sum(m.work for m in refits), fit.converged)
        if lead is None or bic(fit, n_points) < bic(lead, n_points):
            lead = fit
        out.append(fit)
    return _form_fits(out, seeds), True


def screen_held(data: BundleData, noise: Mapping[str, float], model: ModelFit,
                plugins: Iterable[EffectPlugin], rounds: int) -> dict[str, list[FormFit]]:
    """The measurement effects among ``plugins`` fitted onto ``model`` held: every form
    screened, none refitted jointly (:func:`fit_effect` with ``joint=False``). Each costs one
    simulation of the model's device (a fit keeps its last simulation), and its criterion is
    one that a joint refit could only lower.

    Parameters
    ----------
    data : BundleData
    noise : mapping of data set name to noise (K)
    model : ModelFit
    plugins : iterable of EffectPlugin
    rounds : int
        Rounds of each screen.

    Returns
    -------
    dict of str to list of FormFit
        By effect name, those with a screen.
    """
    out = {}
    for p in plugins:
        if isinstance(p, MeasurementEffect):
            forms, _ = fit_effect(data, noise, model, p, rounds, 0, joint=False)
            if forms:
                out[p.name] = forms
    return out


def _form_fits(fits: Sequence[ModelFit], seeds: Sequence[Sequence[Mapping[str, float]]]
               ) -> list[FormFit]:
    return [FormFit(f, tuple(v)) for f, v in zip(fits, seeds, strict=True)]


def grow(data: BundleData, noise: Mapping[str, float], form: FormFit, rounds: int,
         short: Callable[[ModelFit], bool],
         affords: Callable[[int], bool] = lambda cost: True,
         last: int = 0) -> tuple[ModelFit, int, int]:
    """``form``'s fit on longer ladders while ``short(fit)`` holds of the best (it leaves a
    data set beyond its noise): one stage more, then another (:func:`_longer`), until
    :data:`~spicethermal.fit.joint.ORDER_PATIENCE` stages in a row lower nothing, or until
    the work left does not afford (``affords(cost)``) one more as costly as the last (the
    first as costly as ``last``, the last one grown before, of another fit: with none, the
    first needs only some work left); a longer ladder's fit stops where it is once the
    work left affords nothing. The model's order was chosen without the effect, whose
    misfit may have taken or hidden stages. A longer ladder replaces the fit when its
    criterion (two parameters a stage) is lower.

    Parameters
    ----------
    data : BundleData
    noise : mapping of data set name to noise (K)
    form : FormFit
    rounds : int
    short : callable
    affords : callable, optional
        Whether the work left affords a simulator cost (``engines.meter.Meter.cost``).
    last : int, optional
        The cost of the last longer ladder grown before (0: none).

    Returns
    -------
    ModelFit
        ``form.fit`` itself when no longer ladder is better.
    int
        The work spent growing.
    int
        The cost of the last longer ladder (``last`` when none was grown).
    """
    n_points = sum(data.sizes().values())
    best = current = form.fit
    misses = 0
    while short(best) and misses < ORDER_PATIENCE and affords(last):
        with metered() as meter:
            longer = _longer(data, noise, current, rounds, form.screened,
                             lambda m=meter: affords(m.cost))
        last = meter.cost
        if longer is None:
            break
        current = longer
        if bic(longer, n_points) < bic(best, n_points):
            best, misses = longer, 0
        else:
            misses += 1
    return best, current.work - form.fit.work, last


def _evaluated(data: BundleData, noise: Mapping[str, float], ladder: Cauer,
               model: ModelFit) -> ModelFit:
    """``model``'s effects on ``ladder``, evaluated (nothing fitted)."""
    pred = predict_model(data, ladder, model.effects)
    return ModelFit(ladder, model.effects, pred, chi2_by_set(data, pred, noise),
                    model.n_params, 0, True)


def _refine(data: BundleData, noise: Mapping[str, float], fit: ModelFit, rounds: int,
            work: int) -> ModelFit:
    """``fit`` refitted jointly (ladder and every effect) from its own ladder and from the
    linear ladder of the least heated curve of the same order, side by side, and from that
    curve's ladder of its own order (:func:`~spicethermal.fit.joint.reference_order`: the
    model's order may have grown with the misfit the effect explains); the one with the
    lowest criterion (``fit`` itself when none lowers χ²)."""
    n = fit.ladder.order
    values = tuple(dict(e.params) for e in fit.effects)
    starts = [Start(fit.ladder, values)]
    ref = start_ladders(data, [n]).get(n)
    if ref is not None:
        starts.append(Start(ref, values))
    got = [m for m in fit_starts(data, noise, Layout(_slots(fit), n), starts, rounds)
           if m is not None]
    m_ref = reference_order(data)
    other = start_ladders(data, [m_ref]).get(m_ref) if 0 < m_ref != n else None
    if other is not None:
        got += [m for m in fit_starts(data, noise, Layout(_slots(fit), m_ref),
                                      [Start(other, values)], rounds) if m is not None]
    spent = work + sum(m.work for m in got)
    n_points = sum(data.sizes().values())
    pick = min([*got, fit], key=lambda m: bic(m, n_points))
    return ModelFit(pick.ladder, pick.effects, pick.predictions, pick.chi2, pick.n_params,
                    spent, pick.converged)


def _longer(data: BundleData, noise: Mapping[str, float], fit: ModelFit,
            rounds: int, seeds: Sequence[Mapping[str, float]],
            go_on: Callable[[], bool] | None = None) -> ModelFit | None:
    """``fit`` refitted on a ladder one stage longer, side by side from: the linear ladder of
    that order, with the last effect's values as they are and as each of ``seeds`` (its
    screened values: a short ladder may have pulled the effect far from them); and the fit's
    own ladder with a stage more in each place it may go (:func:`~.joint.stage_more`: a
    stage the effect's misfit hid is often outside the linear ladder's span, as a fast
    stage under a masked electrical transient). The best; the fit stops where it is when
    ``go_on()`` says no (:func:`~.joint.fit_starts`)."""
    n = fit.ladder.order + 1
    if n > MAX_ORDER:
        return None
    values = tuple(dict(e.params) for e in fit.effects)
    starts = [Start(more, values) for more in stage_more(fit.ladder) if more.order == n]
    ladder = start_ladders(data, [n]).get(n)
    if ladder is not None:
        starts += [Start(ladder, values)] + [Start(ladder, (*values[:-1], dict(s)))
                                             for s in seeds]
    got = [m for m in fit_starts(data, noise, Layout(_slots(fit), n), starts, rounds,
                                 go_on=go_on) if m is not None]
    if not got:
        return None
    best = min(got, key=lambda m: m.chi2_total)
    return ModelFit(best.ladder, best.effects, best.predictions, best.chi2, best.n_params,
                    fit.work + sum(m.work for m in got), best.converged)
