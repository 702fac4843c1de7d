"""The greedy duty profile: bang-bang under the junction-peak and no-overshoot constraints.

On a grid of whole PWM periods (fine at first, growing in proportion to the elapsed time)
each step takes the largest duty such that (1) the junction peak at the step's end stays at
or below the limit and (2) the node, even if power were cut after this step, never rises
above the target (its free response, a look-ahead). The profile ends as soon as the hold
duty keeps the node within the band forever. :func:`smooth` damps the ringing of the ride
along the target and :func:`compress` merges steps of nearly equal duty (energy kept).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from .dynamics import Dynamics, PeriodMap, Steps

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray


def _largest_duty(dyn: Dynamics, z_sw: NDArray, j: NDArray, lim_k: float) -> float:
    """Largest duty (to 1e-4) whose exact junction peaks over periods ``j`` stay <= lim_k."""
    if PeriodMap(dyn, 1.0).peaks(z_sw, j).max() <= lim_k:
        return 1.0
    lo, hi = 0.0, 1.0
    for _ in range(2):
        grid = np.linspace(lo, hi, 101)
        ok = PeriodMap(dyn, grid).peaks(z_sw, j).max(axis=1) <= lim_k
        if not ok.any():
            return lo if lo > 0 else 0.0
        k = int(np.nonzero(ok)[0].max())
        if k == grid.size - 1:
            return float(grid[k])
        lo, hi = float(grid[k]), float(grid[k + 1])
    return lo


def greedy(dyn: Dynamics, node: int, lim_k: float, tgt_k: float, hold_duty: float,
           x_hold: NDArray, tol_switch: float, growth: float, t_end: float, sustain: int = 5
           ) -> tuple[Steps, float, int]:
    """Bang-bang duty profile under the junction-peak and no-overshoot constraints.

    The junction constraint is exact for a linear model (switched state, sampled periods of
    the step), and a duty is accepted only if it could be kept ``sustain`` periods (this stops
    the ride along the limit from chattering between duty 1 and a low duty); with device
    effects it is the mean plus the ripple at the step's end.

    Parameters
    ----------
    dyn : Dynamics
        Advances the averaged state step by step (exact switched map when linear).
    node : int
        The node brought to the target without overshoot.
    lim_k, tgt_k : float
        Junction-peak limit and node target, K over the ambient.
    hold_duty : float
        The duty that holds the target.
    x_hold : NDArray
        Node rises of the steady hold, K.
    tol_switch : float
        The node must stay this close to the target under the hold to switch to it, K.
    growth : float
        Step length as a fraction of the elapsed periods (at least one period).
    t_end : float
        Give up after this time, s.
    sustain : int
        Periods a duty must be sustainable for (linear model).

    Returns
    -------
    steps : list of (int, int, float)
        ``(first_period, periods, duty)``; the hold follows the last one.
    worst_k : float
        The largest junction peak rise met.
    arrival : int
        Index of the step in which the node arrived within ``tol_switch`` of the target
        (``len(steps)`` if never).
    """
    period = dyn.period
    dgrid = np.linspace(0.0, 1.0, 2001)
    look = np.concatenate([[0.0], np.geomspace(period / 10, 10 * dyn.tau.max(), 160)])
    ripple_hold = float(dyn.ripple(hold_duty, x_hold[0]))
    linear = dyn.linear
    z_sw = np.zeros(dyn.n)  # exact switched modal state at the start of the next period
    x = np.zeros(dyn.n)
    k = 0
    steps: Steps = []
    worst = 0.0
    arrival = -1
    while k * period < t_end:
        m = max(1, int(growth * k))
        h = m * period
        modes = dyn.modes(x)
        lam, v, vinv = modes
        z_free = (vinv @ x) * np.exp(-lam * h)
        z_in = dyn.p * v[0] / lam * -np.expm1(-lam * h)
        # (1) junction peak: exact over sampled periods of the step (linear), else mean +
        # ripple at the step's end
        j = np.unique(np.round(np.linspace(0, m - 1, min(m, 8))))
        if linear:  # exact; a duty must be sustainable for `sustain` periods
            span = max(m, sustain)
            d_j = _largest_duty(dyn, z_sw, np.unique(np.round(np.linspace(0, span - 1,
                                                                         min(span, 8)))), lim_k)
        else:
            aj, bj = float(v[0] @ z_free), float(v[0] @ z_in)
            ok = aj + dgrid * bj + dyn.ripple(dgrid, aj) <= lim_k
            d_j = float(dgrid[ok].max()) if ok.any() else 0.0
        # (2) no overshoot: the node's free response after this step stays <= target
        decay = v[node] * np.exp(-np.outer(look, lam))
        a_n, b_n = decay @ z_free, decay @ z_in
        pos = b_n > 1e-12 * np.abs(b_n).max()
        d_n = float(np.min((tgt_k - a_n[pos]) / b_n[pos])) if pos.any() else 1.0
        d = min(1.0, max(0.0, min(d_j, d_n)))
        x = dyn.advance(x, h, d, modes)
        if linear:
            one = PeriodMap(dyn, d)
            worst = max(worst, float(one.peaks(z_sw, j).max()))
            z_sw = one.start(z_sw, m)
        else:
            worst = max(worst, float(x[0] + dyn.ripple(d, x[0])))
        steps.append((k, m, d))
        k += m
        if arrival < 0 and x[node] >= tgt_k - tol_switch:
            arrival = len(steps)
        # switch to the hold once it keeps the node in the band and the junction safe
        lam, v, vinv = dyn.modes(x)
        dz = (vinv @ (x - x_hold)) * np.exp(-np.outer(look, lam))
        if (np.max(np.abs(dz @ v[node])) <= tol_switch
                and np.max(dz @ v[0]) + x_hold[0] + ripple_hold <= lim_k):
            break
    return steps, worst, (arrival if arrival >= 0 else len(steps))


def smooth(steps: Steps, first: int, passes: int = 8) -> Steps:
    """Damp the period-2 ringing of the greedy once the node has arrived (steps >= first).

    Riding the target, a duty that is a local extremum between two partial-duty neighbours
    is replaced, with them, by their time-weighted mean over the three steps (energy kept).

    Parameters
    ----------
    steps : list of (int, int, float)
        ``(first_period, periods, duty)``.
    first : int
        The step in which the node arrived; earlier steps are left alone.
    passes : int
        Most passes over the steps.

    Returns
    -------
    list of (int, int, float)
        The same steps with smoothed duties.

    Examples
    --------
    >>> smooth([(0, 1, 1.0), (1, 1, 0.25), (2, 2, 0.75), (4, 1, 0.25)], first=1)
    [(0, 1, 1.0), (1, 1, 0.5), (2, 2, 0.5), (4, 1, 0.5)]
    """
    d = np.array([s[2] for s in steps])
    n = np.array([s[1] for s in steps], dtype=float)
    for _ in range(passes):
        changed = False
        for i in range(max(first, 0) + 1, len(d) - 1):
            if d[i - 1] >= 1 or d[i + 1] >= 1 or d[i] >= 1:
                continue
            if (d[i] - d[i - 1]) * (d[i + 1] - d[i]) < 0:
                w = n[i - 1:i + 2]
                mean = float(w @ d[i - 1:i + 2] / w.sum())
                d[i - 1:i + 2] = mean
                changed = True
        if not changed:
            break
    return [(k, m, float(x)) for (k, m, _), x in zip(steps, d, strict=True)]


def compress(steps: Steps, duty_step: float) -> Steps:
    """Merge consecutive steps whose duties span at most ``duty_step`` (energy kept).

    A step's duty may also be a tuple, one duty per heater of an array: steps merge when every
    heater's duties span at most ``duty_step``, each heater keeping its energy.

    Parameters
    ----------
    steps : list of (int, int, float)
        ``(first_period, periods, duty)``.
    duty_step : float
        Largest span of duties merged into one step (duty 1 is never merged with less).

    Returns
    -------
    list of (int, int, float)
        Fewer steps, each at the period-weighted mean duty of those it replaces.

    Examples
    --------
    >>> compress([(0, 2, 1.0), (2, 1, 0.5), (3, 3, 0.502), (6, 1, 0.3)], 0.005)
    [(0, 2, 1.0), (2, 4, 0.5015), (6, 1, 0.3)]
    >>> compress([(0, 1, (1.0, 0.2)), (1, 1, (1.0, 0.204)), (2, 1, (0.9, 0.2))], 0.005)
    [(0, 2, (1.0, 0.202)), (2, 1, (0.9, 0.2))]
    """
    out: Steps = []
    group: Steps = []

    def flush() -> None:
        if group:
            n = sum(g[1] for g in group)
            d = np.round(sum(g[1] * np.asarray(g[2], dtype=float) for g in group) / n, 6)
            out.append((group[0][0], n, float(d) if d.ndim == 0 else tuple(map(float, d))))
            group.clear()

    lo = hi = np.zeros(0)
    for s in steps:
        d = np.asarray(s[2], dtype=float)
        if group and (np.max(np.maximum(hi, d) - np.minimum(lo, d)) > duty_step
                      or np.any((d >= 1) != (lo >= 1))):
            flush()
        if not group:
            lo = hi = d
        lo, hi = np.minimum(lo, d), np.maximum(hi, d)
        group.append(s)
    flush()
    return out
