"""Time budgets for fits and integrations: CPU-time deadlines that a numerical hang cannot
escape.

:func:`time_limit` sets a budget for the block inside it; the inner loops call
:func:`check_time`, which raises :class:`TimeLimitError` past it; :func:`unlimited` lifts every
budget for checks that must complete; :func:`bounded` runs a function within a budget and
falls back to a default.
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

__all__ = ["TimeLimitError", "bounded", "check_time", "cpu_time", "time_limit", "unlimited"]

_DEADLINE: contextvars.ContextVar[float] = contextvars.ContextVar("deadline", default=math.inf)


class TimeLimitError(SimulationError):
    """The time budget of :func:`time_limit` ran out."""


@contextmanager
def time_limit(seconds: float) -> Iterator[None]:
    """A time budget for the fits and integrations run inside the block: past it,
    :func:`check_time` raises :class:`TimeLimitError` (fits then return their best point so far,
    integrations fail). Nested budgets keep the earlier deadline. The clock is the CPU time of
    the calling thread (:func:`cpu_time`): a numerical hang is caught the same way on a busy
    machine as on an idle one, and neither the machine's load nor the threads of a BLAS (or of
    a batch run) eat into the budget.

    >>> with time_limit(0.0):
    ...     check_time()
    Traceback (most recent call last):
    ...
    spicethermal.fit.budget.TimeLimitError: time budget exhausted
    """
    deadline = min(_DEADLINE.get(), cpu_time() + seconds)
    token = _DEADLINE.set(deadline)
    try:
        yield
    finally:
        _DEADLINE.reset(token)


@contextmanager
def unlimited() -> Iterator[None]:
    """Lift every :func:`time_limit` inside the block (for the checks that must complete,
    such as comparing a fit with the model it extends)."""
    token = _DEADLINE.set(math.inf)
    try:
        yield
    finally:
        _DEADLINE.reset(token)


def bounded(fn: Callable[[], Any], seconds: float, default: Any) -> Any:
    """``fn()`` within ``seconds`` of CPU time, else ``default`` (the enclosing
    :func:`time_limit` still raises when it runs out).

    >>> bounded(lambda: 1 + 1, 1.0, None), bounded(check_time, 0.0, "late")
    (2, 'late')
    """
    outer = _DEADLINE.get()
    try:
        with time_limit(seconds):
            return fn()
    except TimeLimitError:
        if cpu_time() > outer:
            raise
        return default


#: The CPU clock is read at most this often (s of wall time) by :func:`check_time`: between
#: reads the thread's CPU time is bounded by the last reading plus the wall time since, and
#: the inner loops of the integrations call it tens of thousands of times per fit.
CLOCK_EVERY_S = 2e-3
_CLOCK = threading.local()  # wall time and CPU time of the thread's last reading


def cpu_time() -> float:
    """The budgets' clock: the calling thread's CPU time (s, :func:`time.thread_time`)."""
    return time.thread_time()


def check_time() -> None:
    """Raise :class:`TimeLimitError` when the current :func:`time_limit` has run out."""
    deadline = _DEADLINE.get()
    if deadline == math.inf:
        return
    wall = time.perf_counter()
    last_wall, last_cpu = getattr(_CLOCK, "last", (-math.inf, 0.0))
    if last_cpu + (wall - last_wall) <= deadline and wall - last_wall < CLOCK_EVERY_S:
        return
    now = cpu_time()
    _CLOCK.last = (wall, now)
    if now > deadline:
        raise TimeLimitError("time budget exhausted")
