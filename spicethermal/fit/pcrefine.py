"""A fitted ``phase-change`` band refined (:func:`spicethermal.fit.pcfit.fit_phase_change`):
on a ladder of one more stage when it sits at the junction, and in the other band shapes."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from ..core.errors import DataFormatError, FitError, SimulationError
from ..core.ladder import Foster
from ..effects import Effect
from .effectfit import (
    MAX_BASELINE_ORDER,
    NUMERICAL_ERRORS,
    BundleData,
    TimeLimitError,
    baseline_ladder,
    joint_fit,
    sse,
    subset,
    time_limit,
    unlimited,
)

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

__all__ = ["PC_FIT_TOL", "PC_JOINT_BUDGET_S", "PC_NFEV", "SHAPE_GAIN", "junction_stage",
           "other_shape", "split_fastest"]

#: The phase-change fit (an integration per evaluation) stops at this looser tolerance.
PC_FIT_TOL = 1e-5
#: Iterations allowed to the band's own fit (3 parameters, the ladder held; each also evaluates
#: the forward model 3 times for its Jacobian).
PC_NFEV = 15
#: Work (s, :mod:`.budget`) allowed to the joint refit of the ladder with a phase-change band (each
#: evaluation integrates the curves that cross the band); past it the best point so far is kept.
PC_JOINT_BUDGET_S = 3.0
#: Work (s, :mod:`.budget`) allowed to the joint refit of a band on a ladder of one more stage
#: started from the fitted ladder with its fastest stage split (:func:`junction_stage`), and the
#: share of that stage's resistance given to the faster half (:func:`split_fastest`).
PC_STAGE_BUDGET_S = 4.0
SPLIT_SHARE = 0.25
#: Work (s, :mod:`.budget`) allowed to the fit of each other band shape (started from the logistic
#: fit).
PC_FORM_BUDGET_S = 0.6
#: The other shapes are fitted only when the logistic band lowers the noise-weighted squared
#: error this much (twice the decision's BIC drop: a band that is not clearly there has no
#: shape to tell).
SHAPE_GAIN = 20.0


def split_fastest(ladder: Foster, t_first_s: float) -> Foster:
    """``ladder`` with its fastest stage split in two: :data:`SPLIT_SHARE` of its resistance
    and the rest, at time constants a third and two thirds of the way (in log time) from the
    first reading ``t_first_s`` to the next stage's time constant. The start of a ladder of one
    more stage that keeps the fitted one's shape; a fastest stage that a fit had collapsed
    below the first reading (a junction with no heat capacity of its own) comes back where
    the readings see it.

    >>> from spicethermal.core.ladder import Foster
    >>> [round(t, 9) for t in split_fastest(Foster.from_tau([8.0, 2.0], [1.0, 1e-9]), 1e-6).tau]
    [0.0001, 0.01, 1.0]
    """
    order = np.argsort(ladder.tau)
    i = int(order[0])
    r = ladder.r[i]
    t_next = ladder.tau[int(order[1])] if ladder.order > 1 else 100.0 * ladder.tau[i]
    t_first_s = min(t_first_s, t_next / 100.0)
    taus = [t_first_s ** (1 - k / 3) * t_next ** (k / 3) for k in (1, 2)]
    rest = [k for k in range(ladder.order) if k != i]
    return Foster.from_tau([SPLIT_SHARE * r, (1 - SPLIT_SHARE) * r, *(ladder.r[k] for k in rest)],
                           [*taus, *(ladder.tau[k] for k in rest)])


def junction_stage(data: BundleData, cooling: list[str], lad: Foster, effs: list[Effect],
                 build, limits: tuple[list[float], list[float]], c_scale: float
                 ) -> tuple[Foster, list[Effect], int]:
    """A band at the junction refitted with its ladder on one more stage, when that lowers
    the noise-weighted squared error by more than the stage's two parameters cost (BIC);
    returns the ladder, the effects and the parameters added (0 or 2).

    The linear ladder of curves that all cross a junction band lumps the junction with the
    next layer (their first milliseconds bend too little to ask for another stage): the
    band's heat then spreads over too large a capacity, and the cooling curves' first
    milliseconds stay beyond their noise whatever the band. Tried only while they do
    (:data:`SHAPE_GAIN` above their number of points), from two starts while they stay so:
    the linear ladder of one more stage, within :data:`PC_JOINT_BUDGET_S`, then the fitted
    ladder with its fastest stage split (:func:`split_fastest`: a heater's thin junction
    layer in front of a band much larger than its own capacity), within
    :data:`PC_STAGE_BUDGET_S`. (A band further out gets no stage: a fast stage would absorb
    an electrical transient that the next step must see.)"""
    n_cool = sum(data.measured(n).size for n in cooling)

    def beyond(lad: Foster, effs: list[Effect]) -> float:
        with unlimited():
            return sse(subset(data, cooling), lad, effs) - n_cool

    if effs[-1].params["node"] != 0 or beyond(lad, effs) < SHAPE_GAIN \
            or lad.order >= MAX_BASELINE_ORDER:
        return lad, effs, 0
    n = sum(data.measured(d).size for d in data.datasets)
    with unlimited():
        best = (sse(data, lad, effs) - 2 * math.log(n), lad, effs, 0)
    p = effs[-1].params
    x0 = [math.log(p["latent_j"] / c_scale), p["t_c"], p["width_k"]]
    t_first = min(float(c.t_s[0]) for c in data.cooling)
    for budget, start in ((PC_JOINT_BUDGET_S, lambda: baseline_ladder(data, lad.order + 1)),
                          (PC_STAGE_BUDGET_S, lambda: split_fastest(lad, t_first))):
        if best[3] and beyond(best[1], best[2]) < SHAPE_GAIN:
            break
        try:
            with time_limit(budget):
                lad2, effs2, _ = joint_fit(data, cooling, start(), True, x0, *limits, build,
                                           diff_step=1e-3, tol=PC_FIT_TOL)
        except (FitError, DataFormatError, SimulationError, TimeLimitError,
                *NUMERICAL_ERRORS):
            continue
        with unlimited():
            cost = sse(data, lad2, effs2)
        if cost < best[0]:
            best = (cost, lad2, effs2, 2)
    return best[1:]


def other_shape(data: BundleData, names: Sequence[str], ladder: Foster, base: Sequence[Effect],
                 logistic: Effect, form: str, limits: tuple[list[float], list[float]],
                 c_scale: float) -> Effect | None:
    """The band of shape ``form`` fitted from the logistic fit (the ladder held); None when its
    fit fails or runs out of time before any step."""
    p = logistic.params
    node = int(p["node"])
    lo, hi = list(limits[0]), list(limits[1])
    # a plateau of full width W has the standard deviation W/√12; its edges start at W/10
    width0 = p["width_k"] * (math.sqrt(12.0) if form == "plateau" else 1.0)
    x0 = [math.log(max(p["latent_j"], 1e-12) / c_scale), p["t_c"],
          float(np.clip(width0, lo[2] * 1.01, 2 * hi[2]))]
    hi[2] = 2 * hi[2] if form == "plateau" else hi[2]
    if form == "plateau":
        x0.append(math.log(x0[2] / 10))
        lo.append(math.log(0.005))
        hi.append(math.log(max(x0[2], 0.01)))

    def build(x: NDArray) -> list[Effect]:
        extra = {"edge_k": math.exp(x[3])} if form == "plateau" else {}
        return [*base, Effect.create("phase-change", form, latent_j=math.exp(x[0]) * c_scale,
                                     t_c=float(x[1]), width_k=float(x[2]), node=node, **extra)]

    try:
        with time_limit(PC_FORM_BUDGET_S):
            _, effs, _ = joint_fit(data, names, ladder, False, x0, lo, hi, build,
                                   diff_step=1e-3, tol=PC_FIT_TOL, max_nfev=PC_NFEV)
    except (FitError, TimeLimitError):
        return None
    return effs[-1]
