"""What a duty schedule does: temperatures on a time grid, junction peak, time to target.

A *schedule* is ``((t_s, duty), ...)`` (each duty from its time until the next, the last
forever); the search works on *steps* ``(first_period, periods, duty)`` and
:func:`schedule_of` turns them into a schedule. The node temperature is the period average
(the averaged simulation of the model), the junction peak the mean plus the periodic ripple,
or the exact switched peak of a linear model (:func:`junction_peak`). The time to target is
when the node enters the band and stays in it (:func:`settle_rows`, refined by bisection on
the exact response in :func:`settle_time`).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from ..model import Schedule
from .dynamics import Dynamics, Steps, switched_peaks

if TYPE_CHECKING:  # pragma: no cover
    from collections.abc import Callable

    from numpy.typing import NDArray

#: ``((t_s, duty), ...)``: each duty from its time on, the last one forever.
DutySchedule = tuple[tuple[float, float], ...]


def time_grid(period: float, horizon: float, marks: tuple[float, ...] = (), n: int = 1500
              ) -> NDArray:
    """A logarithmic grid from a quarter period to ``horizon``, with 0 and the ``marks``.

    Parameters
    ----------
    period, horizon : float
        PWM period and the end of the grid, s.
    marks : tuple of float
        Times to include (the schedule's switching times).
    n : int
        Points of the logarithmic part.

    Returns
    -------
    NDArray
        Sorted unique times, s.

    Examples
    --------
    >>> time_grid(4e-3, 1.0, (0.5,), n=4).round(9).tolist()
    [0.0, 0.001, 0.01, 0.1, 0.5, 1.0]
    """
    t = np.geomspace(period / 4, horizon, n)
    return np.unique(np.concatenate([[0.0], t, np.asarray(marks, dtype=float)]))


def schedule_of(intervals: Steps, hold_duty: float, period: float) -> DutySchedule:
    """The schedule of duty steps followed by the hold (equal neighbours merged).

    Parameters
    ----------
    intervals : list of (int, int, float)
        ``(first_period, periods, duty)`` steps.
    hold_duty : float
        The duty after the last step.
    period : float
        PWM period, s.

    Returns
    -------
    tuple of (float, float)
        ``(t_s, duty)`` pieces.

    Examples
    --------
    >>> schedule_of([(0, 3, 1.0), (3, 2, 1.0), (5, 1, 0.5)], 0.25, 1e-3)
    ((0.0, 1.0), (0.005, 0.5), (0.006, 0.25))
    """
    out = [(first * period, float(d)) for first, n, d in intervals if n > 0]
    end = intervals[-1][0] + intervals[-1][1] if intervals else 0
    merged: list[tuple[float, float]] = []
    for t, d in [*out, (end * period, float(hold_duty))]:
        if merged and merged[-1][1] == d:
            continue
        merged.append((t, d))
    return tuple(merged)


def predict(dyn: Dynamics, node: int, schedule: DutySchedule, t: NDArray
            ) -> tuple[NDArray, NDArray, NDArray]:
    """Node rise, junction mean rise and junction peak (mean + ripple) on ``t``, K.

    Parameters
    ----------
    dyn : Dynamics
        Simulates the averaged power and gives the ripple.
    node : int
        Whose rise comes first in the result.
    schedule : tuple of (float, float)
        The duties to simulate.
    t : NDArray
        Times, s.

    Returns
    -------
    node_k, junction_mean_k, junction_peak_k : NDArray
        Rises over the ambient at ``t``.
    """
    sched = Schedule(tuple(s[0] for s in schedule), tuple(dyn.p * s[1] for s in schedule))
    tr = dyn.model.simulate(t, sched, dyn.tref)
    times = np.array([s[0] for s in schedule])
    duties = np.array([s[1] for s in schedule])
    # the ripple of a new duty builds up over its first period: until then the previous one's
    lag = t - dyn.period
    d = duties[np.clip(np.searchsorted(times, lag, side="left") - 1, 0, None)]
    if dyn.linear:
        rip = dyn.ripple(d)
    else:
        rip = np.array([float(dyn.ripple(di, j)) for di, j in zip(d, tr.tj_k, strict=True)])
    return tr.theta_k[:, node], tr.tj_k, tr.tj_k + rip


def junction_peak(dyn: Dynamics, intervals: Steps, hold_duty: float, horizon: float
                  ) -> tuple[float, NDArray, NDArray]:
    """Max junction peak rise of a profile: exact switched (linear) or averaged + ripple.

    Parameters
    ----------
    dyn : Dynamics
        Linear: the exact period map; else the averaged simulation and ripple.
    intervals : list of (int, int, float)
        Steps ``(first_period, periods, duty)`` before the hold.
    hold_duty : float
        What follows them forever.
    horizon : float
        How long to follow the hold, s.

    Returns
    -------
    peak_k : float
        The largest junction peak rise, K.
    t_s, exact_k : NDArray
        The exact switched peaks (linear model; empty otherwise).
    """
    if dyn.linear:
        t, pk = switched_peaks(dyn, intervals, hold_duty, int(horizon / dyn.period) + 1)
        return float(pk.max()), t, pk
    sched = schedule_of(intervals, hold_duty, dyn.period)
    t = time_grid(dyn.period, horizon, tuple(s[0] for s in sched), 1200)
    _, _, jp = predict(dyn, 0, sched, t)
    return float(jp.max()), np.empty(0), np.empty(0)


def settle_rows(t: NDArray, y: NDArray, target: float, tol: float) -> tuple[NDArray, NDArray]:
    """When each curve enters the band ``target ± tol`` for good.

    Parameters
    ----------
    t : NDArray
        Times, s.
    y : NDArray
        One curve per row, on ``t``.
    target, tol : float
        The band.

    Returns
    -------
    t_s : NDArray
        Per row, the first time after which ``|y - target| <= tol`` for good (interpolated;
        ``inf`` if still outside at the end).
    last : NDArray
        The index of the last grid point outside the band (-1 when none).

    Examples
    --------
    >>> t = np.array([0.0, 1.0, 2.0, 3.0])
    >>> ts, last = settle_rows(t, np.array([[0.0, 2.0, 0.8, 1.0]]), 1.0, 0.5)
    >>> ts.tolist(), last.tolist()  # leaves the band at 1.5 above, back at 1 + 0.5/0.8
    ([1.625], [1])
    """
    y = np.atleast_2d(y)
    err = np.abs(y - target) - tol
    out = err > 0
    last = np.where(out.any(axis=1), y.shape[1] - 1 - np.argmax(out[:, ::-1], axis=1), -1)
    i = np.clip(last, 0, y.shape[1] - 2)
    rows = np.arange(y.shape[0])
    e0, e1 = err[rows, i], err[rows, i + 1]
    with np.errstate(invalid="ignore", divide="ignore"):
        w = np.where(e0 != e1, e0 / (e0 - e1), 1.0)
    ts = t[i] + w * (t[i + 1] - t[i])
    ts = np.where(last < 0, t[0], ts)
    ts = np.where(out[:, -1], np.inf, ts)
    return ts, last


def settle_time(dyn: Dynamics, node: int, schedule: DutySchedule, t: NDArray, y: NDArray,
                tgt_k: float, tol: float) -> float:
    """Time to target of the node curve ``y`` on ``t``, refined on the exact response.

    Parameters
    ----------
    dyn : Dynamics
        Its model's exact response refines the time (linear model).
    node : int
        The node ``y`` belongs to.
    schedule : tuple of (float, float)
        The duty schedule that gave ``y``.
    t, y : NDArray
        Times (s) and the node's rise (K).
    tgt_k, tol : float
        Target rise and half-width of the band, K.

    Returns
    -------
    float
        Seconds from switch-on (bisected on the exact response of a linear model, else
        interpolated on the grid; ``inf`` if the node does not settle).
    """
    ts, last = settle_rows(t, y, tgt_k, tol)
    i = int(last[0])
    if not dyn.linear or i < 0 or not math.isfinite(ts[0]):
        return float(ts[0])
    sched = Schedule(tuple(s[0] for s in schedule), tuple(dyn.p * s[1] for s in schedule))

    def f(tt: float) -> float:
        val = dyn.model.simulate([tt], sched, dyn.tref).theta_k[0, node]
        return abs(val - tgt_k) - tol

    return bisect(f, float(t[i]), float(t[i + 1]))


def bisect(f: Callable[[float], float], a: float, b: float, iters: int = 60) -> float:
    """Root of ``f`` in ``[a, b]`` with ``f(a) > 0 >= f(b)`` (``b`` when not bracketed).

    Parameters
    ----------
    f : callable
        A function of one float.
    a, b : float
        The bracket.
    iters : int
        Most iterations.

    Returns
    -------
    float
        The root.

    Examples
    --------
    >>> round(bisect(lambda x: 2.0 - x, 0.0, 3.0), 12)
    2.0
    """
    from scipy.optimize import brentq

    fa, fb = f(a), f(b)
    if not (fa > 0 >= fb):
        return b
    return float(brentq(f, a, b, xtol=1e-12, rtol=1e-10, maxiter=iters))
