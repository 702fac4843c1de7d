"""The joint refit of every effect of a model with its ladder.

Effects are found one at a time (:mod:`spicethermal.analysis.diagnose`): each is fitted on top
of the ladder and the effects found before it, whose parameters it holds. When two effects act
on the same readings, the first one fitted has taken up part of the second's signature (a TSP
bow fitted before a temperature coefficient bends to the curves' misfit), and the model of both
is only as good as the first effect's compromise. :func:`refit_effects` moves every effect's
parameters and the ladder together from where the one-at-a-time fits left them: the model
then is the best of its kind, not the best of its history.

Which parameters move is the catalogue's (:class:`~spicethermal.effects.catalogue.Param`): those
used by the effect's form, marked ``fitted`` (a reference temperature or a node is held), and
not at their default value (a parameter the effect's own fit held stays held, so the number of
parameters of the model is unchanged). Each is scaled by its own size (temperatures by 1 K) and
bounded by its range.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import partial
from typing import TYPE_CHECKING

import numpy as np

from ..core.errors import FitError, SimulationError
from ..effects import DEVICE, Effect, spec
from .budget import bounded
from .effectfit import NUMERICAL_ERRORS, BundleData, as_foster, joint_fit, sse, transient_spans

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

    from ..core.ladder import Cauer, Foster

__all__ = ["Free", "free_parameters", "refit_effects"]

#: Relative finite-difference step when a device effect is in the model (its forward model is
#: an adaptive integration, whose result is smooth only at this scale).
DEVICE_DIFF_STEP = 1e-3
#: Work (s, :mod:`.budget`) allowed to the first pass of :func:`refit_effects`, the effects alone
#: with the ladder held.
HELD_LADDER_S = 3.0
#: Temperatures (°C) are scaled by this (their size says nothing about their resolution).
TEMPERATURE_SCALE_K = 1.0


@dataclass(frozen=True)
class Free:
    """One parameter the joint refit moves.

    Attributes
    ----------
    effect : int
        Index of the effect in the model's list.
    name : str
        Parameter name.
    scale : float
        The refit moves ``value / scale``.
    low, high : float
        The parameter's range.
    """

    effect: int
    name: str
    scale: float
    low: float
    high: float


def free_parameters(effects: Sequence[Effect]) -> list[Free]:
    """The parameters of ``effects`` that a joint refit moves (see the module docstring).

    Parameters
    ----------
    effects : sequence of Effect
        The model's effects.

    Returns
    -------
    list of Free

    >>> e = Effect.create("temperature-coefficient", "local", alpha_per_k=0.002)
    >>> [(f.name, f.scale) for f in free_parameters([e])]
    [('alpha_per_k', 0.002)]
    """
    out = []
    for i, effect in enumerate(effects):
        for name, p in spec(effect.name).params.items():
            value = float(effect.params[name])
            if not p.fitted or (p.forms and effect.form not in p.forms) or value == p.default:
                continue
            scale = TEMPERATURE_SCALE_K if p.unit == "°C" else abs(value)
            out.append(Free(i, name, scale, p.low, p.high))
    return out


def refit_effects(data: BundleData, ladder: Foster | Cauer, effects: Sequence[Effect],
                  held_first: bool = False) -> tuple[Foster, list[Effect]]:
    """Every effect's free parameters (:func:`free_parameters`) and the ladder refitted jointly
    to every data set of ``data``, from their present values; within the caller's
    :func:`~spicethermal.fit.budget.time_limit` (past it, the best point so far).

    Never worse than the start: when the refit fails or ends with a larger squared error, the
    start is returned.

    Parameters
    ----------
    data : BundleData
        The measurements (weighted by ``data.scales``).
    ladder : Foster or Cauer
        The ladder the effects were fitted with.
    effects : sequence of Effect
        The model's effects, with the parameters of their one-at-a-time fits.
    held_first : bool
        Refit the effects alone first, the ladder held, within :data:`HELD_LADDER_S` of work,
        then everything from there: with a local coefficient's integration per evaluation, a
        Jacobian over every stage leaves a tight budget no iteration (seed 79's draw 002 of
        the random validation set: a TSP's bow beside a coefficient, rescued at 8 s of work
        only so).

    Returns
    -------
    (Foster, list of Effect)
        The refitted ladder and effects.
    """
    start = (as_foster(ladder), list(effects))
    free = free_parameters(effects)
    if not free or not data.datasets:
        return start

    def build(x: NDArray) -> list[Effect]:
        params = [dict(e.params) for e in effects]
        for f, v in zip(free, x, strict=True):
            params[f.effect][f.name] = float(np.clip(v * f.scale, f.low, f.high))
        return [Effect.create(e.name, e.form, **p) for e, p in zip(effects, params, strict=True)]

    lo = [min(f.low / f.scale, f.high / f.scale) for f in free]
    hi = [max(f.low / f.scale, f.high / f.scale) for f in free]
    names = [e.name for e in effects]
    exclude = None if "electrical-transient" in names else transient_spans(data)
    device = any(spec(e.name).kind == DEVICE for e in effects)
    step = DEVICE_DIFF_STEP if device else None

    def refit(start: tuple[Foster, list[Effect]], fit_ladder: bool) -> tuple:
        x = [float(start[1][f.effect].params[f.name]) / f.scale for f in free]
        return joint_fit(data, list(data.datasets), start[0], fit_ladder, x, lo, hi, build,
                         exclude=exclude, diff_step=step)

    # the ladder is fitted to cooling curves only; held_first: the effects alone first, the
    # ladder held, within HELD_LADDER_S, then everything from there
    passes: list[tuple[bool, float | None]] = [(bool(data.cooling), None)]
    if held_first and data.cooling:
        passes.insert(0, (False, HELD_LADDER_S))
    best = start
    for fit_ladder, limit in passes:
        try:
            out = refit(best, fit_ladder) if limit is None else \
                bounded(partial(refit, best, fit_ladder), limit, None)
            if out is not None and sse(data, out[0], out[1]) < sse(data, *best):
                best = (as_foster(out[0]), out[1])
        except (FitError, SimulationError, *NUMERICAL_ERRORS):
            continue
    return best
