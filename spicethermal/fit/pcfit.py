"""Fitting ``phase-change``: latent heat, band centre, width, node and band shape from the
cooling curves (the forward model, an integration of the nodal network with the band's heat
capacity, is :func:`spicethermal.fit.effectfit.pc_cooling_rise`).

The band sits at one node of the ladder, and each node runs at its own temperatures: in the
steady state before the cut node ``k`` is at ``Tref + f_k (Tj − Tref)`` with ``f_k`` the
fraction of the junction's rise across the layers beyond it. A band is sought, at each node,
between that node's hottest temperature on the lowest-power curve (a band that curve crossed
would be in its ladder) and its hottest on the hottest curve, so a latent heat in an outer
layer (an actuator's cavity fluid, a solder that melts) is found where it is, not at the
junction's temperatures.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from ..core.errors import DataFormatError, FitError, SimulationError
from ..effects import CATALOGUE, Effect
from ..model import Network
from .budget import cpu_time
from .effectfit import (
    NUMERICAL_ERRORS,
    BundleData,
    EffectFit,
    TimeLimitError,
    as_foster,
    bounded,
    cooling_true_c,
    joint_fit,
    others,
    reference_ladder,
    sse,
    subset,
    switched_off,
    time_limit,
    unlimited,
)

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

    from ..core.ladder import Cauer, Foster

__all__ = ["PC_FIT_TOL", "band_start", "fit_phase_change", "node_fractions"]

#: The phase-change fit (an integration per evaluation) stops at this looser tolerance.
PC_FIT_TOL = 1e-5
#: CPU time (s) allowed to one evaluation of the phase-change grid (a band that makes the
#: integration crawl is not the start point).
PC_EVAL_S = 0.3
#: CPU time (s) allowed to the whole grid (one point per node comes first).
PC_GRID_S = 2.0
#: Iterations allowed to the band's own fit (3 parameters, the ladder held; each also evaluates
#: the forward model 3 times for its Jacobian).
PC_NFEV = 15
#: CPU time (s) allowed to the joint refit of the ladder with a phase-change band (each
#: evaluation integrates the curves that cross the band); past it the best point so far is kept.
PC_JOINT_BUDGET_S = 1.5
#: CPU time (s) allowed to the fit of each other band shape (started from the logistic fit).
PC_FORM_BUDGET_S = 1.0
#: The other shapes are fitted only when the logistic band lowers the noise-weighted squared
#: error this much (twice the decision's BIC drop: a band that is not clearly there has no
#: shape to tell).
SHAPE_GAIN = 20.0


def node_fractions(ladder: Foster | Cauer) -> NDArray:
    """Steady rise of every node of the ladder's nodal network as a fraction of the junction's.

    Parameters
    ----------
    ladder : Foster or Cauer
        The ladder.

    Returns
    -------
    ndarray
        ``f_k``, junction (1.0) first, falling outwards.

    >>> from spicethermal.core.ladder import Cauer
    >>> [round(float(x), 6) for x in node_fractions(Cauer([1.0, 3.0], [1.0, 1.0]))]
    [1.0, 0.75]
    """
    net = Network.of(ladder)
    b = np.zeros(net.n)
    b[0] = 1.0
    theta = np.linalg.solve(net.conductance(), b)
    return theta / theta[0]


def band_start(data: BundleData, ladder: Foster | Cauer, base: Sequence[Effect]) -> float:
    """Where a latent-heat band most likely sits (junction temperature, °C): the model
    temperature of the hottest curve where its residual grows fastest in log time.

    Parameters
    ----------
    data : BundleData
        The bundle's arrays (at least one cooling curve).
    ladder : Foster or Cauer
        The linear ladder.
    base : sequence of Effect
        Effects already in the model.

    Returns
    -------
    float
        The temperature, °C.
    """
    c = max(data.cooling, key=lambda c: c.power_w)
    model = cooling_true_c(c, ladder, base)
    resid = c.tj_c - model
    smooth = np.convolve(resid, np.ones(3) / 3, mode="same")
    grow = np.gradient(smooth, np.log(c.t_s))
    return float(model[int(np.argmax(grow[1:-1])) + 1])


def fit_phase_change(data: BundleData, ladder: Foster | Cauer,
                     effects: Sequence[Effect] = ()) -> list[EffectFit]:
    """Latent heat, band centre, width and node from the cooling curves, then the other band
    shapes from that fit: one :class:`~spicethermal.fit.effectfit.EffectFit` per form (logistic,
    gaussian, plateau).

    The ladder of the lowest-power curve is held for the search: at every node the band is
    sought between the node's hottest temperature on that curve and on the hottest curve
    (module docstring). Start: the best point of a grid of nodes × latent heats × centres
    (where the hottest curve's residual grows fastest in log time, the catalogue's 64.7 °C for
    methanol when it lies in range, and three across it); least squares from the best point at
    the junction and the best elsewhere; then the ladder jointly with the band. When no band
    fits better than ``ladder`` without one, the result has no latent heat and keeps
    ``ladder``.

    Parameters
    ----------
    data : BundleData
        The bundle's arrays.
    ladder : Foster or Cauer
        The linear ladder the diagnosis compares with.
    effects : sequence of Effect
        Effects already in the model (kept in every fit).

    Returns
    -------
    list of EffectFit
        The logistic fit first.
    """
    if not data.cooling:
        raise FitError("phase-change needs cooling curves")
    names = [c.name for c in data.cooling]
    base = others(effects, "phase-change")
    refs = [as_foster(ladder)]
    try:
        refs.insert(0, reference_ladder(data, as_foster(ladder).order))
    except (FitError, DataFormatError):
        pass
    if base and len(refs) > 1:
        # the reference curve's own ladder reads it without the effects found before (a TSP
        # bow, a transient): keep the one that fits it better through them
        cold_only = subset(data, [data.reference_curve.name])
        with unlimited():
            refs.sort(key=lambda r: sse(cold_only, r, base))
    ref = refs[0]
    hot = max(data.cooling, key=lambda c: float(np.max(c.tj_c)))
    cold = data.reference_curve
    fractions = node_fractions(ref)
    t_hi = float(np.max(hot.tj_c))
    t_lo = float(np.max(cold.tj_c)) if len(data.cooling) > 1 else float(np.min(hot.tj_c))
    if t_hi - t_lo < 1.0:
        raise FitError("phase-change: no curve reaches temperatures the lowest-power curve "
                       "does not")

    def node_range(k: int) -> tuple[float, float]:
        f = float(fractions[k])
        lo_ref = cold.tref_steady_c if len(data.cooling) > 1 else hot.tref_steady_c
        return (lo_ref + f * (t_lo - lo_ref), hot.tref_steady_c + f * (t_hi - hot.tref_steady_c))

    ranges = [node_range(k) for k in range(ref.order)]
    ranges = [(a, b) for a, b in ranges if b - a >= 0.5] or ranges[:1]
    c_scale = float(max(ref.c))
    start = band_start(data, ref, base)
    default = CATALOGUE["phase-change"].params["t_c"].default
    sub = subset(data, names)
    node = 0

    def build(x: NDArray) -> list[Effect]:
        return [*base, Effect.create("phase-change", latent_j=math.exp(x[0]) * c_scale,
                                     t_c=float(x[1]), width_k=float(x[2]), node=node)]

    def bounds(k: int) -> tuple[list[float], list[float]]:
        a, b = ranges[k]
        return [math.log(1e-6), a, 0.2], [math.log(100.0), b, max(0.3, (b - a) / 4)]

    def cost(x: Sequence[float]) -> float:
        try:
            return bounded(lambda: sse(sub, ref, build(np.asarray(x, dtype=float))),
                           PC_EVAL_S, math.inf)
        except TimeLimitError:
            raise
        except (SimulationError, *NUMERICAL_ERRORS):
            return math.inf

    # coarse grid over (node, centre, latent heat): first one point per node (the mapped start
    # centre), then the rest; least squares from the best points
    first, rest = [], []
    for k, (a, b) in enumerate(ranges):
        span = b - a
        f = float(fractions[k])
        mapped = hot.tref_steady_c + f * (start - hot.tref_steady_c)
        centres = [float(np.clip(mapped, a + 0.02 * span, b - 0.02 * span))]
        if k == 0 and a < default < b:
            centres.append(default)
        centres += list(np.linspace(a + 0.15 * span, b - 0.15 * span, 3))
        levels = (1e-3, 1e-2, 1e-1, 1.0) if k == 0 else (0.1, 1.0, 10.0)
        width0 = float(np.clip(1.5 * f, bounds(k)[0][2] * 1.01, bounds(k)[1][2] * 0.99))
        pts = [(k, [math.log(fr), tc, width0]) for tc in centres for fr in levels]
        first.append(pts[len(levels) // 2])
        rest += [p for p in pts if p is not pts[len(levels) // 2]]
    grid = []
    stop = cpu_time() + PC_GRID_S
    for node, x0 in first + rest:  # noqa: B007 (build reads node)
        if len(grid) >= len(first) and cpu_time() > stop:
            break
        grid.append((cost(x0), node, x0))
    no_band = sse(sub, ref, base)
    if min(g[0] for g in grid) >= no_band:  # no band anywhere helps: nothing to refine
        return [EffectFit(switched_off("phase-change", "logistic", data), as_foster(ladder), 4,
                          {"t_range_c": (t_lo, t_hi), "no_gain": True})]
    junction = min((g for g in grid if g[1] == 0), key=lambda g: g[0])
    outer = min(grid, key=lambda g: g[0])
    # the junction's best point is refined too unless it gains less than half the best's
    starts = [outer] + ([junction] if outer[1] != 0
                        and no_band - junction[0] >= 0.5 * (no_band - outer[0]) else [])
    fits = []
    for _, node, x0 in starts:  # noqa: B007 (build reads node)
        lo, hi = bounds(node)
        fits.append(joint_fit(data, names, ref, False, x0, lo, hi, build, diff_step=1e-3,
                              tol=PC_FIT_TOL, max_nfev=PC_NFEV) + (node,))
    lad, effs, res, node = min(fits, key=lambda r: r[2].cost)
    # then the ladder with the band, jointly (the reference curve alone fixes it poorly)
    lo, hi = bounds(node)
    try:
        with time_limit(PC_JOINT_BUDGET_S):
            lad2, effs2, _ = joint_fit(data, names, lad, True, res.x, lo, hi, build,
                                       diff_step=1e-3, tol=PC_FIT_TOL)
        with unlimited():
            if sse(data, lad2, effs2) < sse(data, lad, effs):
                lad, effs = lad2, effs2
    except (FitError, TimeLimitError):
        pass
    with unlimited():
        gain = sse(sub, ladder, base) - sse(sub, lad, [*base, effs[-1]])
    if gain <= 0:  # no band does better than the given ladder without one
        p = effs[-1].params
        return [EffectFit(Effect.create("phase-change", latent_j=0.0, t_c=p["t_c"],
                                        width_k=p["width_k"], node=0), as_foster(ladder), 4,
                          {"t_range_c": (t_lo, t_hi), "no_gain": True})]
    facts = {"t_range_c": ranges[node]}
    out = [EffectFit(effs[-1], lad, 4, facts)]
    with unlimited():
        left = sse(sub, lad, [*base, effs[-1]]) - sum(c.t_s.size for c in sub.cooling)
    # a band this weak does not show its shape, nor can another shape gain on a fit at the noise
    if gain < SHAPE_GAIN or left < SHAPE_GAIN:
        return out
    for form in ("gaussian", "plateau"):
        fit = _other_shape(data, names, lad, base, effs[-1], form, (lo, hi), c_scale)
        if fit is not None:
            out.append(EffectFit(fit, lad, 5 if form == "plateau" else 4, facts))
    return out


def _other_shape(data: BundleData, names: Sequence[str], ladder: Foster, base: Sequence[Effect],
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
