"""Driving an array through a sequence of patterns, and a Braille line through lines of text.

:func:`drive_patterns` plans one cell (an array model: a Braille cell of 6 or 8 dots) through
patterns that start at given times: each change is a :func:`.drive.plan_transition` from the
state the previous drive left, so a warm array is used as it is. It also builds the two
schedules it is compared with, on the same patterns:

* **naive** — what the single-actuator drive does when crosstalk is ignored: each dot that
  goes up gets the fastest safe drive of a lone actuator (:func:`spicethermal.drive.optimize.
  optimize_drive` on its self impedance, from switch-on), a dot that stays up goes on with it,
  a dot that goes down is switched off;
* **constant** — the crosstalk-aware hold duties from each change on, without any boost (the
  slow, safe baseline of the single drive's speed-up).

:func:`drive_text` shows lines of text on a line of independent cells (each a module on its
own substrate, the measured array): every cell follows the characters at its position; a line
begins when the previous one is complete (plus a dwell for reading). Cells that see the same
characters share one plan.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from ..core.errors import DataFormatError
from ..drive.optimize import optimize_drive
from ..drive.profile import compress
from .braille import text_patterns
from .drive import Limits, Transition, plan_transition
from .dynamics import ArrayDynamics
from .evaluate import DutySchedule, Evaluation, evaluate
from .model import ArrayModel

__all__ = ["CellDrive", "LineDrive", "NaiveDrives", "drive_patterns", "drive_text",
           "patterns_of_dots"]

#: Consecutive steps whose duties all differ by at most this are merged (energy kept).
DUTY_STEP = 0.005


@dataclass(frozen=True, eq=False)
class CellDrive:
    """One array driven through a sequence of patterns, with the baselines.

    Attributes
    ----------
    model : ArrayModel
        The array.
    limits : Limits
        The limits.
    starts : tuple of float
        When each pattern begins, s.
    ups : tuple of tuple of bool
        Each pattern's raised cells.
    transitions : tuple of Transition
        The drive of each change.
    schedule, naive, constant : DutySchedule
        The crosstalk-aware drive and the two baselines.
    t_end : float
        End of the last pattern's window, s.
    ours, naive_eval, constant_eval : Evaluation
        How each does on the coupled network.
    """

    model: ArrayModel
    limits: Limits
    starts: tuple[float, ...]
    ups: tuple[tuple[bool, ...], ...]
    transitions: tuple[Transition, ...]
    schedule: DutySchedule
    naive: DutySchedule
    constant: DutySchedule
    t_end: float
    ours: Evaluation = field(repr=False)
    naive_eval: Evaluation = field(repr=False)
    constant_eval: Evaluation = field(repr=False)

    def evaluation(self, which: str) -> Evaluation:
        """How the drive ``ours``, ``naive`` or ``constant`` does on the coupled network.

        Parameters
        ----------
        which : str
            ``ours``, ``naive`` or ``constant``.

        Returns
        -------
        Evaluation
        """
        return {"ours": self.ours, "naive": self.naive_eval,
                "constant": self.constant_eval}[which]


def patterns_of_dots(dots: Sequence[Sequence[int]], model: ArrayModel) -> list[tuple[bool, ...]]:
    """Braille dot numbers (1-8) as raised cells of ``model`` (ports named ``D1`` ...).

    Parameters
    ----------
    dots : sequence of sequence of int
        Each pattern's raised dots.
    model : ArrayModel
        A Braille cell.

    Returns
    -------
    list of tuple of bool
    """
    names = [p.name for p in model.ports]
    out = []
    for pattern in dots:
        for d in pattern:
            if f"D{d}" not in names:
                raise DataFormatError(f"pattern: dot {d} is not a port of the array (its ports: "
                                      f"{', '.join(names)}); text needs a Braille cell whose "
                                      f"ports are named D1 ...")
        out.append(tuple(f"D{k + 1}" in {f"D{d}" for d in pattern} for k in range(len(names))))
    return out


def _join(pieces: list[tuple[float, DutySchedule]]) -> DutySchedule:
    """Schedules that begin at given times, each until the next begins, as one."""
    out: list[tuple[float, tuple[float, ...]]] = []
    for k, (start, sched) in enumerate(pieces):
        stop = pieces[k + 1][0] if k + 1 < len(pieces) else np.inf
        for t, d in sched:
            if start + t < stop - 1e-12 and (not out or out[-1][1] != d):
                out.append((start + t, d))
    return tuple(out)


def _compressed(tr: Transition, period: float) -> DutySchedule:
    steps = compress(list(tr.steps), DUTY_STEP)
    return Transition(tr.up, tuple(steps), tr.hold).schedule(period)


class NaiveDrives:
    """The naive baseline: the single-actuator drive of each cell's self impedance, computed
    once per cell and shared by every plan of the same array and limits.

    Parameters
    ----------
    dyn : ArrayDynamics
        The array under PWM.
    lim : Limits
        The limits.
    """

    def __init__(self, dyn: ArrayDynamics, lim: Limits) -> None:
        self.dyn, self.lim = dyn, lim
        self._cache: dict[int, tuple[tuple[float, float], ...]] = {}

    def of(self, cell: int) -> tuple[tuple[float, float], ...]:
        """The lone drive of ``cell`` from switch-on, ``((t_s, duty), ...)``.

        Parameters
        ----------
        cell : int
            The cell.

        Returns
        -------
        tuple of (float, float)
        """
        if cell not in self._cache:
            lim = self.lim
            self._cache[cell] = optimize_drive(
                self.dyn.model.self_model(cell), lim.t_max_c, lim.target_c, lim.ambient_c,
                p_max_w=lim.p_max_w, f_pwm_hz=lim.f_pwm_hz, tol_k=lim.tol_k,
                two_phase=False).schedule
        return self._cache[cell]

    def schedule(self, starts: list[float], ups: list[tuple[bool, ...]]) -> DutySchedule:
        """Every cell on its lone drive from the pattern that raised it, off when down.

        Parameters
        ----------
        starts : list of float
            When each pattern begins, s.
        ups : list of tuple of bool
            Each pattern's raised cells.

        Returns
        -------
        DutySchedule
        """
        n = self.dyn.n
        origin: list[float | None] = [None] * n
        per_cell: list[list[tuple[float, float]]] = [[] for _ in range(n)]
        for k, (start, up) in enumerate(zip(starts, ups, strict=True)):
            stop = starts[k + 1] if k + 1 < len(starts) else np.inf
            for i in range(n):
                if not up[i]:
                    origin[i] = None
                    per_cell[i].append((start, 0.0))
                    continue
                if origin[i] is None:
                    origin[i] = start
                drive = self.of(i)
                per_cell[i].append((start, _at(drive, start - origin[i])))
                per_cell[i] += [(origin[i] + t, d) for t, d in drive
                                if start < origin[i] + t < stop]
        out: list[tuple[float, tuple[float, ...]]] = []
        for t in sorted({t for cell in per_cell for t, _ in cell}):
            duties = tuple(_at(cell, t) for cell in per_cell)
            if not out or out[-1][1] != duties:
                out.append((t, duties))
        return tuple(out)


def _at(pieces: Sequence[tuple[float, float]], t: float) -> float:
    """The duty of ``(start, duty)`` pieces in force at ``t`` (0 before the first)."""
    value = 0.0
    for start, d in pieces:
        if start > t + 1e-12:
            break
        value = d
    return value


def drive_patterns(model: ArrayModel, ups: Sequence[Sequence[bool]], lim: Limits,
                   starts: Sequence[float] | None = None, *,
                   next_start: Callable[[float, float], float] | None = None,
                   naive: NaiveDrives | None = None,
                   planned: Sequence[Transition] = ()) -> CellDrive:
    """Plan ``model`` through the patterns ``ups`` and evaluate it against the baselines.

    Parameters
    ----------
    model : ArrayModel
        The array (one cell of a display).
    ups : sequence of sequence of bool
        Each pattern's raised cells.
    lim : Limits
        The limits.
    starts : sequence of float, optional
        When each pattern begins (s, the first at 0). Default: each as soon as the previous
        one is complete (``next_start(start, refresh)``, default ``start + refresh``).
    next_start : callable, optional
        When the next pattern begins, from this one's start and refresh time.
    naive : NaiveDrives, optional
        The naive baseline's lone drives (shared between plans of the same array).
    planned : sequence of Transition
        Transitions already planned for the first patterns (with the same start times).

    Returns
    -------
    CellDrive
    """
    dyn = naive.dyn if naive is not None else ArrayDynamics(model, lim.p_max_w, lim.f_pwm_hz)
    ups_t = [tuple(bool(x) for x in u) for u in ups]
    if not ups_t:
        raise DataFormatError("array drive: no pattern")
    period = dyn.period
    z = np.zeros(dyn.modes.lam.size)
    given = list(starts) if starts is not None else None
    begin = [0.0]
    transitions, pieces = [], []
    for k, up in enumerate(ups_t):
        tr = planned[k] if k < len(planned) else plan_transition(dyn, z, up, lim)
        sched = _compressed(tr, period)
        transitions.append(tr)
        pieces.append((begin[k], sched))
        if k + 1 == len(ups_t):
            break
        if given is not None:
            nxt = round(given[k + 1] / period) * period
        else:
            ev = evaluate(dyn, _join(pieces), begin, ups_t[:k + 1], lim,
                          begin[k] + 15 * float(dyn.modes.tau.max()))
            refresh = ev.refresh_s[-1]
            if not np.isfinite(refresh):
                raise DataFormatError(f"array drive: pattern {k + 1} never completes")
            at = (next_start or (lambda s, r: s + r))(begin[k], refresh)
            nxt = max(begin[k] + period, np.ceil(at / period - 1e-9) * period)
        z = _state_at(dyn, _join(pieces), nxt)
        begin.append(float(nxt))
    t_end = begin[-1] + 15 * float(dyn.modes.tau.max())
    ours = _join(pieces)
    naive_sched = (naive or NaiveDrives(dyn, lim)).schedule(begin, ups_t)
    constant = _join([(b, ((0.0, tr.hold),)) for b, tr in zip(begin, transitions, strict=True)])
    return CellDrive(model, lim, tuple(begin), tuple(ups_t), tuple(transitions), ours,
                     naive_sched, constant, t_end,
                     evaluate(dyn, ours, begin, ups_t, lim, t_end),
                     evaluate(dyn, naive_sched, begin, ups_t, lim, t_end),
                     evaluate(dyn, constant, begin, ups_t, lim, t_end))


def _state_at(dyn: ArrayDynamics, schedule: DutySchedule, t: float) -> np.ndarray:
    """The averaged modal state at ``t`` under a duty schedule."""
    z = np.zeros(dyn.modes.lam.size)
    times = [s for s, _ in schedule] + [np.inf]
    for (a, d), b in zip(schedule, times[1:], strict=True):
        if a >= t:
            break
        z = dyn.advance(z, min(b, t) - a, np.asarray(d))
    return z


@dataclass(frozen=True, eq=False)
class LineDrive:
    """Lines of text on a line of cells.

    Attributes
    ----------
    lines : tuple of str
        The text, one string per line.
    cells : int
        Cells in the display line.
    starts : tuple of float
        When each line begins, s.
    refresh_s : tuple of float
        Each line's refresh time: the slowest cell's, s.
    drives : dict
        The plan of each distinct column of characters, keyed by those characters.
    columns : tuple of str
        Per cell, its characters (the key of its plan).
    """

    lines: tuple[str, ...]
    cells: int
    starts: tuple[float, ...]
    refresh_s: tuple[float, ...]
    drives: dict[str, CellDrive]
    columns: tuple[str, ...]

    def count(self, which: str, kind: str | None = None) -> int:
        """Violations over the whole line of the drive ``ours``, ``naive`` or ``constant``.

        Parameters
        ----------
        which : str
            ``ours``, ``naive`` or ``constant``.
        kind : str, optional
            ``t_max`` or ``actuation``.

        Returns
        -------
        int
        """
        return sum(self.drives[c].evaluation(which).count(kind) for c in self.columns)

    def refresh(self, which: str) -> tuple[float, ...]:
        """Each line's refresh time (the slowest cell) under a drive, s.

        Parameters
        ----------
        which : str
            ``ours``, ``naive`` or ``constant``.

        Returns
        -------
        tuple of float
        """
        return self._slowest(which, lambda e: e.refresh_s)

    def raised(self, which: str) -> tuple[float, ...]:
        """Each line's raise time (every raised dot of every cell up at least once), s.

        Parameters
        ----------
        which : str
            ``ours``, ``naive`` or ``constant``.

        Returns
        -------
        tuple of float
        """
        return self._slowest(which, lambda e: e.raised_s)

    def _slowest(self, which: str,
                 times: Callable[[Evaluation], Sequence[float]]) -> tuple[float, ...]:
        """Each line's slowest cell, by ``times`` of each cell's evaluation under a drive, s."""
        return tuple(max(times(self.drives[c].evaluation(which))[k] for c in self.columns)
                     for k in range(len(self.lines)))


def drive_text(model: ArrayModel, lines: Sequence[str], lim: Limits, cells: int = 40,
               dwell_s: float = 0.0, progress: Callable[[int, int], None] | None = None
               ) -> LineDrive:
    """Show ``lines`` of text, one after the other, on a line of ``cells`` Braille cells.

    Parameters
    ----------
    model : ArrayModel
        One cell (ports ``D1`` ...; six- or eight-dot).
    lines : sequence of str
        The text (each line padded with spaces, or refused if longer than ``cells``).
    lim : Limits
        The limits.
    cells : int
        Cells in the display line.
    dwell_s : float
        Time a completed line stays for reading before the next begins, s.
    progress : callable, optional
        Called with (done, total) distinct columns.

    Returns
    -------
    LineDrive
    """
    if not lines:
        raise DataFormatError("text: no line to show")
    for k, line in enumerate(lines):
        if len(line) > cells:
            raise DataFormatError(f"text: line {k + 1} has {len(line)} characters, the display "
                                  f"{cells} cells")
    padded = [line.ljust(cells) for line in lines]
    columns = tuple("".join(line[c] for line in padded) for c in range(cells))
    distinct = sorted(set(columns))
    # line by line: every distinct column of characters so far is planned on the lines' start
    # times (each after the slowest cell of the line before, plus the dwell), reusing the plan
    # of its first lines
    starts = [0.0]
    plans: dict[str, CellDrive] = {}  # by the characters shown so far
    naive = NaiveDrives(ArrayDynamics(model, lim.p_max_w, lim.f_pwm_hz), lim)
    for k in range(len(lines)):
        done: list[float] = []
        for head in sorted({col[:k + 1] for col in distinct}):
            ups = patterns_of_dots(text_patterns(head), model)
            before = plans.get(head[:-1])
            cd = drive_patterns(model, ups, lim, starts, naive=naive,
                                planned=before.transitions if before is not None else ())
            plans[head] = cd
            done.append(cd.ours.refresh_s[k])
        if k + 1 < len(lines):
            worst = max(done)
            if not np.isfinite(worst):
                raise DataFormatError(f"text: line {k + 1} never completes")
            period = 1.0 / lim.f_pwm_hz
            starts.append(float(np.ceil((starts[k] + worst + dwell_s) / period - 1e-9)
                                * period))
        if progress is not None:
            progress(k + 1, len(lines))
    drives = {col: plans[col] for col in distinct}
    refresh = tuple(max(drives[c].ours.refresh_s[k] for c in columns)
                    for k in range(len(lines)))
    return LineDrive(tuple(lines), cells, tuple(starts), refresh, drives, columns)
