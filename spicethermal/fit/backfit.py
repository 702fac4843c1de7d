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
from typing import TYPE_CHECKING

import numpy as np

from ..core.errors import FitError, SimulationError
from ..effects import DEVICE, Effect, spec
from .effectfit import NUMERICAL_ERRORS, BundleData, as_foster, joint_fit, sse, transient_spans

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

    from ..core.ladder import Cauer, Foster

__all__ = ["Free", "free_parameters", "refit_effects"]

#: Relative finite-difference step when a device effect is in the model (its forward model is
#: an adaptive integration, whose result is smooth only at this scale).
DEVICE_DIFF_STEP = 1e-3
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


def refit_effects(data: BundleData, ladder: Foster | Cauer,
                  effects: Sequence[Effect]) -> tuple[Foster, list[Effect]]:
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

    x0 = [float(effects[f.effect].params[f.name]) / f.scale for f in free]
    lo = [min(f.low / f.scale, f.high / f.scale) for f in free]
    hi = [max(f.low / f.scale, f.high / f.scale) for f in free]
    names = [e.name for e in effects]
    exclude = None if "electrical-transient" in names else transient_spans(data)
    device = any(spec(e.name).kind == DEVICE for e in effects)
    try:
        lad, fitted, _ = joint_fit(data, list(data.datasets), ladder, bool(data.cooling), x0,
                                   lo, hi, build, exclude=exclude,
                                   diff_step=DEVICE_DIFF_STEP if device else None)
        better = sse(data, lad, fitted) < sse(data, *start)
    except (FitError, SimulationError, *NUMERICAL_ERRORS):
        return start
    return (as_foster(lad), fitted) if better else start
