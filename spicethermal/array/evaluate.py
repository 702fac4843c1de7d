"""What a duty schedule does to an array: temperatures, refresh times, violations.

A *duty schedule* is ``((t_s, duties), ...)``: every cell's duty from each time until the next
(the last forever), all on whole PWM periods. Whatever made it — the crosstalk-aware drive,
the naive one, a constant hold — :func:`evaluate` judges it the same way on the coupled
network against a sequence of patterns:

* the *refresh time* of a pattern is from its start until every raised dot is in the band
  ``target ± tol`` and every lowered dot below ``actuation − margin``, both for good (until the
  next pattern), on the period averages; ``inf`` if that never happens;
* the *raise time* of a pattern is from its start until every raised dot has reached its
  actuation temperature (the dots are up, whatever happens after); ``inf`` if one never does;
* a *violation* is a cell whose junction peak exceeds ``t_max`` during a pattern (exact
  switched peaks), or a dot that must be down reaching its actuation temperature although it
  was below it (its neighbours lifted it).

Peaks come from the exact switched map (:func:`.drive.exact_peaks`); averages from the exact
response of the network to the mean powers.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..drive.trajectory import settle_rows
from .drive import Limits, exact_peaks
from .dynamics import ArrayDynamics
from .modal import ArraySchedule

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

__all__ = ["DutySchedule", "Evaluation", "Violation", "evaluate", "steps_of"]

#: ``((t_s, duties), ...)``: every cell's duty from each time on, the last forever.
DutySchedule = tuple[tuple[float, tuple[float, ...]], ...]
#: Grid points per pattern window (logarithmic from a quarter period).
GRID_POINTS = 600


@dataclass(frozen=True)
class Violation:
    """A limit broken during one pattern.

    Attributes
    ----------
    kind : str
        ``t_max`` (a junction peak above it) or ``actuation`` (a dot that must stay down
        reached its actuation temperature).
    pattern : int
        Index of the pattern.
    cell : int
        The cell (port index).
    t_s : float
        When the worst value occurred, s from the schedule's start.
    value_c : float
        That worst temperature, °C.
    """

    kind: str
    pattern: int
    cell: int
    t_s: float
    value_c: float


@dataclass(frozen=True, eq=False)
class Evaluation:
    """How a schedule does (see the module docstring).

    Attributes
    ----------
    refresh_s : tuple of float
        Per pattern, its refresh time, s (``inf``: never complete).
    violations : tuple of Violation
        Every (pattern, cell, kind) whose limit was broken.
    peak_c : NDArray
        Per cell, the largest junction peak, °C.
    t_s : NDArray
        The time grid of the trajectories, s.
    mean_c : NDArray
        ``(len(t_s), N)`` period-average heater temperatures, °C.
    raised_s : tuple of float
        Per pattern, its raise time, s (``inf``: a raised dot never reaches actuation).
    """

    refresh_s: tuple[float, ...]
    violations: tuple[Violation, ...]
    peak_c: NDArray
    t_s: NDArray
    mean_c: NDArray
    raised_s: tuple[float, ...] = ()

    def count(self, kind: str | None = None) -> int:
        """Number of violations (of one kind).

        Parameters
        ----------
        kind : str, optional
            ``t_max`` or ``actuation``; None counts both.

        Returns
        -------
        int
        """
        return sum(1 for v in self.violations if kind is None or v.kind == kind)


def steps_of(schedule: DutySchedule, period: float, t_end: float
             ) -> tuple[list[tuple[int, int, tuple[float, ...]]], tuple[float, ...]]:
    """A duty schedule as profile steps up to ``t_end`` and the duties that follow.

    Parameters
    ----------
    schedule : DutySchedule
        The schedule (times on period starts).
    period : float
        PWM period, s.
    t_end : float
        Where the steps end, s.

    Returns
    -------
    steps : list of (int, int, tuple of float)
        ``(first_period, periods, duties)``.
    after : tuple of float
        The duties in force at ``t_end``.

    Examples
    --------
    >>> steps_of(((0.0, (1.0,)), (0.003, (0.5,))), 1e-3, 0.005)
    ([(0, 3, (1.0,)), (3, 2, (0.5,))], (0.5,))
    """
    end = round(t_end / period)
    firsts = [round(t / period) for t, _ in schedule] + [math.inf]
    steps = []
    for (_, d), a, b in zip(schedule, firsts, firsts[1:], strict=False):
        stop = min(b, end)
        if stop > a:
            steps.append((int(a), int(stop - a), tuple(d)))
    k = max(0, int(np.searchsorted(firsts[:-1], end, side="right")) - 1)
    return steps, tuple(schedule[k][1])


def _grid(period: float, starts: list[float], t_end: float, marks: list[float]) -> NDArray:
    parts = [np.array(marks + [t_end])]
    for a, b in zip(starts, [*starts[1:], t_end], strict=True):
        if b > a:
            parts.append(a + np.geomspace(period / 4, b - a, GRID_POINTS))
            parts.append([a])
    t = np.unique(np.concatenate(parts))
    return t[t <= t_end]


def evaluate(dyn: ArrayDynamics, schedule: DutySchedule, starts: list[float],
             ups: list[tuple[bool, ...]], lim: Limits, t_end: float) -> Evaluation:
    """Judge a duty schedule against a sequence of patterns (see the module docstring).

    Parameters
    ----------
    dyn : ArrayDynamics
        The array under PWM.
    schedule : DutySchedule
        The duties.
    starts : list of float
        When each pattern begins, s (the first at 0).
    ups : list of tuple of bool
        Each pattern's raised cells.
    lim : Limits
        The limits.
    t_end : float
        The end of the last pattern's window, s.

    Returns
    -------
    Evaluation
    """
    period, n = dyn.period, dyn.n
    t = _grid(period, starts, t_end, [s for s, _ in schedule])
    power = ArraySchedule.of([s for s, _ in schedule], [np.asarray(d) * dyn.p for _, d in schedule])
    mean_k = dyn.ports(dyn.modes.response(power, t))
    steps, after = steps_of(schedule, period, t_end)
    pk_t, pk = exact_peaks(dyn, np.zeros(dyn.modes.lam.size), steps, np.asarray(after), 1)
    refresh, raised, violations = [], [], []
    act = lim.actuation_c - lim.ambient_c
    ends = [*starts[1:], t_end]
    for k, (a, b, up) in enumerate(zip(starts, ends, ups, strict=True)):
        up_a = np.asarray(up, dtype=bool)
        sel = (t >= a) & (t <= b)
        tw, yw = t[sel] - a, mean_k[sel]
        done = 0.0
        if up_a.any():
            ts, _ = settle_rows(tw, yw[:, up_a].T, lim.tgt_k, lim.tol_k)
            done = max(done, float(ts.max()))
        if (~up_a).any():  # the last time a lowered dot is above its limit
            above = yw[:, ~up_a] > lim.down_k
            last = np.where(above.any(axis=0), tw.size - 1 - np.argmax(above[::-1], axis=0), -1)
            if np.any(last == tw.size - 1):
                done = math.inf
            elif np.any(last >= 0):
                done = max(done, float(tw[int(last.max()) + 1]))
        refresh.append(done)
        reached = yw[:, up_a] >= act
        raised.append(0.0 if not up_a.any() else math.inf if not reached.any(axis=0).all()
                      else float(tw[int(np.argmax(reached, axis=0).max())]))
        psel = (pk_t >= a - 0.5 * period) & (pk_t < b - 0.5 * period)
        for i in range(n):
            if psel.any() and pk[psel, i].max() > lim.lim_k + 1e-6:
                j = int(np.argmax(pk[psel, i]))
                violations.append(Violation("t_max", k, i, float(pk_t[psel][j]),
                                            lim.ambient_c + float(pk[psel, i][j])))
            if up_a[i]:
                continue
            below = np.flatnonzero(yw[:, i] < act)
            if below.size:  # reached again after having been below it
                later = yw[below[0]:, i]
                if later.max() >= act:
                    j = below[0] + int(np.argmax(later))
                    violations.append(Violation("actuation", k, i, float(a + tw[j]),
                                                lim.ambient_c + float(yw[j, i])))
    peak_c = lim.ambient_c + (pk.max(axis=0) if pk.size else np.zeros(n))
    return Evaluation(tuple(refresh), tuple(violations), peak_c, t, lim.ambient_c + mean_k,
                      tuple(raised))
