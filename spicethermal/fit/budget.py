"""Budgets for fits and integrations: deadlines in counted work, so that the same input stops
at the same point on every run, with a CPU-time backstop that a numerical hang cannot escape.

:func:`time_limit` sets a budget for the block inside it; the inner loops call
:func:`check_time` with the cost of what they are about to do, which raises
:class:`TimeLimitError` past the budget; :func:`unlimited` lifts every budget for checks that
must complete; :func:`bounded` runs a function within a budget and falls back to a default.

The budgets' clock is the thread's **work** (:func:`spent`, summed exactly in integer
nanoseconds): the costs passed to :func:`check_time` (:data:`EVALUATION_S` per evaluation of a
fit's residuals, :data:`PC_STEP_S` and :data:`TC_STEP_S` per right-hand side of the integrated
forward models, :data:`FROZEN_ROW_S` per PWM row frozen under one), in seconds of CPU time of
the machine they were calibrated on. Where a fit stops, and so which effect a diagnosis names,
then depends on the input only, not on the machine's load or speed: a CPU-time clock made the
same bundle's verdict change from one run to the next when a fit ended near its budget. CPU
time is only the backstop: past :data:`HANG_FACTOR` times a budget in CPU seconds (work the
costs do not count), :func:`check_time` raises too.
"""

from __future__ import annotations

import contextvars
import math
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

from ..core.errors import SimulationError

__all__ = ["EVALUATION_S", "FROZEN_ROW_S", "HANG_FACTOR", "PC_STEP_S", "TC_STEP_S",
           "TimeLimitError", "bounded", "check_time", "cpu_time", "left", "mark", "reached",
           "spent", "time_limit", "unlimited"]

#: Work (s) of one evaluation of a fit's residuals (closed-form forward models and the least
#: squares' own algebra), of one right-hand side of the phase-change integration, and of one of
#: the local temperature coefficient's (with its share of Jacobians and factorisations).
#: Calibrated (session 11) by regressing the CPU time of the 69 diagnoses of the validation set
#: (``bench/bench_validation.py``, 2 at a time on the project's 2-core machine) on the counts
#: of each: the diagnoses that reach their budgets are predicted within 0.84-1.11×. The
#: phase-change integration has since left ``solve_ivp``'s step loop for ODEPACK's own
#: (:mod:`~spicethermal.fit.lsoda`): the same right-hand sides, so the same work and the same
#: stopping points, at about half the CPU time each.
EVALUATION_S = 3.0e-4
PC_STEP_S = 2.5e-5
TC_STEP_S = 8.4e-5

#: Work (s) of freezing one PWM row's ladder under an integrated device effect (a local or
#: power-law coefficient's, at every node's mean temperature; a band's secant capacity): 0.11-0.16
#: ms each on the project's machine (session 13), ten times a row's closed form, and a
#: diagnosis that refits such effects freezes tens of thousands.
FROZEN_ROW_S = 1.3e-4

#: The CPU-time backstop: a budget of ``s`` seconds of work also ends after ``HANG_FACTOR · s``
#: seconds of the thread's CPU time (a loop whose work the costs miss cannot hang).
HANG_FACTOR = 4.0

# (work deadline in ns, CPU deadline in s) of the innermost budget
_DEADLINE: contextvars.ContextVar[tuple[float, float]] = contextvars.ContextVar(
    "deadline", default=(math.inf, math.inf))
_WORK = threading.local()  # the thread's work so far (ns, an int: sums are exact)


class TimeLimitError(SimulationError):
    """The time budget of :func:`time_limit` ran out."""


def spent() -> int:
    """The budgets' clock: the work counted by :func:`check_time` in the calling thread, in
    **nanoseconds** (an integer: a sum of floats would round differently from a different
    start, and a budget would end one evaluation earlier or later)."""
    return getattr(_WORK, "ns", 0)


def _ns(seconds: float) -> int:
    return round(seconds * 1e9)


def mark(seconds: float) -> int:
    """The clock's reading once ``seconds`` more of work are spent (for :func:`reached`)."""
    return spent() + _ns(seconds)


def reached(end: int) -> bool:
    """Whether the work spent has reached ``end`` (:func:`mark`).

    >>> end = mark(1e-3); check_time(6e-4); reached(end), check_time(6e-4), reached(end)
    (False, None, True)
    """
    return spent() >= end


def left() -> float:
    """Work (s) left in the innermost :func:`time_limit` (``inf`` outside every budget).

    >>> with time_limit(1.0):
    ...     check_time(0.25)
    ...     left()
    0.75
    """
    deadline = _DEADLINE.get()[0]
    return max(deadline - spent(), 0) / 1e9 if deadline != math.inf else math.inf


def cpu_time() -> float:
    """The backstop's clock: the calling thread's CPU time (s, :func:`time.thread_time`)."""
    return time.thread_time()


@contextmanager
def time_limit(seconds: float) -> Iterator[None]:
    """A budget of ``seconds`` of work for the fits and integrations run inside the block:
    past it, :func:`check_time` raises :class:`TimeLimitError` (fits then return their best
    point so far, integrations fail). Nested budgets keep the earlier deadline.

    >>> with time_limit(1e-3):
    ...     check_time(4e-4)
    ...     check_time(4e-4)
    ...     check_time(4e-4)
    Traceback (most recent call last):
    ...
    spicethermal.fit.budget.TimeLimitError: time budget exhausted
    >>> with time_limit(math.inf):  # no budget: the enclosing one (here none) holds
    ...     check_time(1e9); left()
    inf
    """
    work, cpu = _DEADLINE.get()
    if seconds != math.inf:  # an infinite budget keeps the enclosing one
        work, cpu = min(work, mark(seconds)), min(cpu, cpu_time() + HANG_FACTOR * seconds)
    token = _DEADLINE.set((work, cpu))
    try:
        yield
    finally:
        _DEADLINE.reset(token)


@contextmanager
def unlimited() -> Iterator[None]:
    """Lift every :func:`time_limit` inside the block (for the checks that must complete,
    such as comparing a fit with the model it extends)."""
    token = _DEADLINE.set((math.inf, math.inf))
    try:
        yield
    finally:
        _DEADLINE.reset(token)


def bounded(fn: Callable[[], Any], seconds: float, default: Any) -> Any:
    """``fn()`` within ``seconds`` of work, else ``default`` (the enclosing
    :func:`time_limit` still raises when it runs out).

    >>> bounded(lambda: 1 + 1, 1.0, None), bounded(lambda: check_time(1.0), 0.5, "late")
    (2, 'late')
    """
    work, cpu = _DEADLINE.get()
    try:
        with time_limit(seconds):
            return fn()
    except TimeLimitError:
        if spent() >= work or cpu_time() > cpu:
            raise
        return default


#: The CPU clock is read at most this often (s of wall time) by :func:`check_time`: between
#: reads the thread's CPU time is bounded by the last reading plus the wall time since, and
#: the inner loops of the integrations call it tens of thousands of times per fit.
CLOCK_EVERY_S = 2e-3
_CLOCK = threading.local()  # wall time and CPU time of the thread's last reading


def check_time(cost: float = 0.0) -> None:
    """Count ``cost`` (s of work) and raise :class:`TimeLimitError` when the current
    :func:`time_limit` has run out (of work, or of CPU time past its backstop)."""
    work = _WORK.ns = spent() + _ns(cost)
    deadline, backstop = _DEADLINE.get()
    if deadline == math.inf:
        return
    if work >= deadline:
        raise TimeLimitError("time budget exhausted")
    wall = time.perf_counter()
    last_wall, last_cpu = getattr(_CLOCK, "last", (-math.inf, 0.0))
    if last_cpu + (wall - last_wall) <= backstop and wall - last_wall < CLOCK_EVERY_S:
        return
    now = cpu_time()
    _CLOCK.last = (wall, now)
    if now > backstop:
        raise TimeLimitError("time budget exhausted (CPU backstop)")
