"""Progress on stderr for long commands: one library (tqdm), off with ``-q`` and off when stderr
is not a terminal (pipes, logs, the tests), so no command's output ever depends on it.

>>> list(bar(range(3), quiet=True))
[0, 1, 2]
"""

from __future__ import annotations

import sys
import threading
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from typing import TypeVar

__all__ = ["bar", "enabled", "status_line", "task"]

T = TypeVar("T")


def enabled(quiet: bool = False) -> bool:
    """Whether progress is shown: not ``quiet`` and stderr is a terminal.

    >>> enabled(quiet=True)
    False
    """
    return not quiet and sys.stderr.isatty()


def bar(items: Iterable[T], *, total: int | None = None, desc: str = "",
        quiet: bool = False) -> Iterator[T]:
    """``items`` as they come, with a progress bar on stderr when :func:`enabled`.

    Parameters
    ----------
    items : what to iterate over.
    total : how many there are (default ``len(items)`` when it has one).
    desc : what is being done (a few words).
    quiet : no bar (the commands' ``-q``).

    Returns
    -------
    Iterator over ``items``.

    Examples
    --------
    >>> sum(bar([1, 2, 3], desc="adding", quiet=True))
    6
    """
    if not enabled(quiet):
        yield from items
        return
    from tqdm import tqdm

    yield from tqdm(items, total=total, desc=desc, file=sys.stderr, leave=False)


@contextmanager
def task(desc: str, *, quiet: bool = False) -> Iterator[None]:
    """One long step that cannot be counted (an ngspice run): its name and elapsed time on
    stderr while it runs, when :func:`enabled`.

    Parameters
    ----------
    desc : what is being done (a few words).
    quiet : nothing shown (the commands' ``-q``).

    Returns
    -------
    A context manager; the step runs inside it.

    Examples
    --------
    >>> with task("waiting", quiet=True):
    ...     pass
    """
    if not enabled(quiet):
        yield
        return
    from tqdm import tqdm

    with tqdm(total=1, desc=desc, file=sys.stderr, leave=False,
              bar_format="{desc}: {elapsed}") as shown:
        stop = threading.Event()

        def tick() -> None:
            while not stop.wait(0.5):
                shown.refresh()

        clock = threading.Thread(target=tick, daemon=True)
        clock.start()
        try:
            yield
        finally:
            stop.set()
            clock.join()
            shown.update(1)


@contextmanager
def status_line(*, quiet: bool = False) -> Iterator[Callable[[str], None]]:
    """A one-line status on stderr that each call overwrites (what a long computation is
    doing now), cleared at the end; a function that does nothing when not :func:`enabled`.

    Parameters
    ----------
    quiet : nothing shown (the commands' ``-q``).

    Returns
    -------
    A context manager giving ``say(text)``.

    Examples
    --------
    >>> with status_line(quiet=True) as say:
    ...     say("fitting")
    """
    if not enabled(quiet):
        yield lambda _text: None
        return
    width = [0]

    def say(text: str) -> None:
        line = text[:100]
        sys.stderr.write("\r" + line + " " * max(width[0] - len(line), 0))
        sys.stderr.flush()
        width[0] = len(line)

    try:
        yield say
    finally:
        sys.stderr.write("\r" + " " * width[0] + "\r")
        sys.stderr.flush()
