"""ngspice check of an array drive: the switched drive around every change, the slow drift.

Two kinds of ngspice runs of the array's N-port ``.lib`` (:mod:`spicethermal.spice.array_lib`)
with one set of PWM current sources per cell (:func:`spicethermal.drive.result.pulse_sources`):

* **switched** — around every pattern change, from its start over a window that covers the
  boost and the ride to the target (three times the refresh, at least 30 and at most 2000
  periods), at 1/100 period; each run starts (``.ic``) in the exact switched state at the
  change (:class:`.dynamics.SwitchedMap`), so the runs are independent and go in parallel;
* **averaged** — the whole sequence with every heater at its period-average power: the slow
  heating of the neighbours and the substrate over minutes, which decides whether a dot that
  must stay down crosses its actuation temperature and whether the held dots drift.

From them: every cell's junction peak (the switched runs' maxima; over the averaged run, its
mean plus the periodic ripple of the cell's duty), the violations counted as
:mod:`.evaluate` counts them, and how far ngspice is from the prediction.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from typing import TYPE_CHECKING

import numpy as np

from .. import __version__
from ..drive.result import pulse_sources
from ..engines.pwmsim import workers
from ..spice.array_lib import pins, render_array_lib
from ..spice.lib import fmt
from ..spice.ngspice import sanitize_comment, simulator
from ..spice.templates import environment
from .dynamics import ArrayDynamics, SwitchedMap
from .evaluate import DutySchedule, steps_of
from .modal import ArraySchedule

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

    from .refresh import CellDrive, LineDrive

__all__ = ["drive_deck", "verify_drive", "verify_line"]

#: Periods of a switched run: at least, at most.
WINDOW_PERIODS = (30, 2000)
NAME = "CELL"


def _cell_schedule(schedule: DutySchedule, cell: int, start_s: float
                   ) -> tuple[tuple[float, float], ...]:
    out: list[tuple[float, float]] = []
    for t, d in schedule:
        value = (max(t - start_s, 0.0), d[cell])
        if out and value[0] <= out[-1][0]:  # pieces before the start: the last one holds
            out[-1] = value
        elif not out or out[-1][1] != value[1]:
            out.append(value)
    return tuple(out)


def _averaged_sources(schedule: DutySchedule, cell: int, pin: str, p_max_w: float,
                      edge_s: float) -> str:
    corners = [(0.0, 0.0)]  # off at the operating point, as the PWM sources are
    for t, d in _cell_schedule(schedule, cell, 0.0):
        if t > 0:
            corners.append((t, corners[-1][1]))
        corners.append((t + edge_s, p_max_w * d))
    text = " ".join(f"{fmt(t)} {fmt(v)}" for t, v in corners)
    return f"IAVG{cell + 1} 0 {pin} PWL({text})"


def drive_deck(dyn: ArrayDynamics, schedule: DutySchedule, ambient_c: float, stop_s: float,
               *, start_s: float = 0.0, averaged: bool = False, description: str = "") -> str:
    """A self-contained ngspice deck of a duty schedule on the array's ``.lib``.

    Parameters
    ----------
    dyn : ArrayDynamics
        The array under PWM.
    schedule : DutySchedule
        The duties (times on period starts).
    ambient_c : float
        The reference temperature, °C (on ``TREF``).
    stop_s : float
        End of the run, s of the schedule.
    start_s : float
        Start of the run (a period start), in the schedule's exact switched state there.
    averaged : bool
        Period-average powers instead of PWM (from 0; ``start_s`` must be 0).
    description : str
        A comment line.

    Returns
    -------
    str
    """
    pin = pins(dyn.model)
    period = dyn.period
    if averaged:
        sources = [_averaged_sources(schedule, i, pin[i], dyn.p, period * 1e-4)
                   for i in range(dyn.n)]
        tmax = min(stop_s / 2000, 0.05)
        ic: list[tuple[str, float]] = []
    else:
        sources = [line for i in range(dyn.n) for line in pulse_sources(
            _cell_schedule(schedule, i, start_s), 1 / period, dyn.p, pin[i],
            prefix=f"I{i + 1}_")]
        tmax = period / 100
        ic = _initial(dyn, schedule, start_s, ambient_c) if start_s > 0 else []
    return environment().get_template("bench/array_drive.cir.j2").render(
        version=__version__, description=sanitize_comment(description), start_s=start_s,
        averaged=averaged, lib=render_array_lib(dyn.model, "ngspice", NAME), pins=pin,
        name=NAME, ambient_c=ambient_c, sources=sources, ic=ic, reltol=1e-5 if averaged else 1e-4,
        tmax_s=tmax, tstop_s=stop_s - start_s)


def switched_state(dyn: ArrayDynamics, schedule: DutySchedule, t_s: float) -> NDArray:
    """Exact modal state of the switched schedule at the period start ``t_s``.

    Parameters
    ----------
    dyn : ArrayDynamics
        The array under PWM.
    schedule : DutySchedule
        The duties.
    t_s : float
        A period start, s.

    Returns
    -------
    NDArray
    """
    steps, _ = steps_of(schedule, dyn.period, t_s)
    z = np.zeros(dyn.modes.lam.size)
    for _, count, d in steps:
        z = SwitchedMap(dyn, np.asarray(d)).start(z, count)
    return z


def _initial(dyn: ArrayDynamics, schedule: DutySchedule, t_s: float, ambient_c: float
             ) -> list[tuple[str, float]]:
    rises = dyn.modes.v @ switched_state(dyn, schedule, t_s)
    pin = pins(dyn.model)
    n = dyn.n
    names = [pin[k] if k < n else f"X1.N{k - n + 1}" for k in range(len(rises))]
    return [(nm, ambient_c + float(r)) for nm, r in zip(names, rises, strict=True)]


def _windows(cd: CellDrive, evaluation) -> list[tuple[float, float]]:
    period = 1.0 / cd.limits.f_pwm_hz
    lo, hi = WINDOW_PERIODS
    out = []
    ends = [*cd.starts[1:], cd.t_end]
    for start, end, refresh in zip(cd.starts, ends, evaluation.refresh_s, strict=True):
        span = 3 * refresh if np.isfinite(refresh) else hi * period
        span = min(max(span, lo * period), hi * period, end - start)
        out.append((start, start + round(span / period) * period))
    return out


def verify_drive(cd: CellDrive, which: str = "ours", engine: str = "ngspice") -> dict:
    """Run a cell's drive in ngspice (see the module docstring) and count its violations.

    Parameters
    ----------
    cd : CellDrive
        The planned cell.
    which : str
        ``ours`` or ``naive``: the schedule checked.
    engine : str
        ``ngspice`` (``ngspice -b``, runs in parallel) or ``pyspice``.

    Returns
    -------
    dict
        ``peak_c`` (per cell, the largest junction in ngspice, °C), ``t_max`` and
        ``actuation`` (violations seen in ngspice), ``mean_error_k`` (largest |ngspice −
        predicted| of the period averages), ``peak_error_k`` (largest |ngspice − exact| of
        the switched runs' peaks), ``runs``.
    """
    schedule = {"ours": cd.schedule, "naive": cd.naive}[which]
    ev = cd.evaluation(which)
    lim = cd.limits
    dyn = ArrayDynamics(cd.model, lim.p_max_w, lim.f_pwm_hz)
    windows = _windows(cd, ev)
    decks = [drive_deck(dyn, schedule, lim.ambient_c, b, start_s=a,
                        description=f"{which} drive, switched from {a:g} s")
             for a, b in windows]
    decks.append(drive_deck(dyn, schedule, lim.ambient_c, cd.t_end, averaged=True,
                            description=f"{which} drive, period averages"))
    vectors = [f"V({p})" for p in pins(cd.model)[:-1]]
    backend = simulator(engine)
    with ThreadPoolExecutor(workers() if backend.name == "ngspice" else 1) as pool:
        waves = list(pool.map(lambda d: backend.run(d, vectors), decks))
    n = dyn.n
    peak = np.full(n, -np.inf)
    peak_error = 0.0
    seen: dict[tuple[str, int, int], float] = {}
    for k, ((a, b), wave) in enumerate(zip(windows, waves[:-1], strict=True)):
        tj = np.column_stack([wave[v] for v in vectors])
        peak = np.maximum(peak, tj.max(axis=0))
        exact = lim.ambient_c + _window_peaks(dyn, schedule, a, b)
        peak_error = max(peak_error, float(np.max(np.abs(tj.max(axis=0) - exact))))
        for i in np.flatnonzero(tj.max(axis=0) > lim.t_max_c + 1e-6):
            seen[("t_max", k, int(i))] = float(tj[:, i].max())
    avg = waves[-1]
    mean = np.column_stack([avg[v] for v in vectors])
    power = ArraySchedule.of([s for s, _ in schedule], [np.asarray(d) * dyn.p for _, d in schedule])
    predicted = lim.ambient_c + dyn.ports(dyn.modes.response(power, avg.t_s))
    mean_error = float(np.max(np.abs(mean - predicted)))
    duties = np.array([schedule[max(0, int(np.searchsorted([s for s, _ in schedule], t,
                                                             side="right")) - 1)][1]
                       for t in avg.t_s])
    with_ripple = mean + dyn.ripple(duties)
    peak = np.maximum(peak, with_ripple.max(axis=0))
    ends = [*cd.starts[1:], cd.t_end]
    for k, (a, b, up) in enumerate(zip(cd.starts, ends, cd.ups, strict=True)):
        sel = (avg.t_s >= a) & (avg.t_s <= b)
        for i in range(n):
            if with_ripple[sel, i].max() > lim.t_max_c + 1e-6:
                key = ("t_max", k, i)
                seen[key] = max(seen.get(key, -np.inf), float(with_ripple[sel, i].max()))
            if up[i]:
                continue
            below = np.flatnonzero(mean[sel, i] < lim.actuation_c)
            if below.size and mean[sel, i][below[0]:].max() >= lim.actuation_c:
                seen[("actuation", k, i)] = float(mean[sel, i][below[0]:].max())
    return {"engine": backend.name, "runs": len(decks), "peak_c": peak.tolist(),
            "t_max": sum(1 for kind, _, _ in seen if kind == "t_max"),
            "actuation": sum(1 for kind, _, _ in seen if kind == "actuation"),
            "mean_error_k": mean_error, "peak_error_k": peak_error,
            "windows_s": [list(w) for w in windows]}


def verify_line(ld: LineDrive, engine: str = "ngspice") -> dict[str, dict]:
    """:func:`verify_drive` of every distinct column of a line, for ``ours`` and ``naive``.

    Violations are counted per cell of the line (a column shown by several cells counts once
    for each of them, as :meth:`.refresh.LineDrive.count` does).

    Parameters
    ----------
    ld : LineDrive
        The planned line (or one array as a line of one cell).
    engine : str
        ``ngspice`` or ``pyspice``.

    Returns
    -------
    dict
        By drive (``ours``, ``naive``): ``engine``, ``runs``, ``t_max`` and ``actuation``
        (violations seen in ngspice), ``peak_c`` (per distinct column, its hottest junction),
        ``peak_error_k`` and ``mean_error_k`` (the largest over the columns).
    """
    shown = {c: ld.columns.count(c) for c in ld.drives}
    out: dict[str, dict] = {}
    for which in ("ours", "naive"):
        checks = {c: verify_drive(cd, which, engine) for c, cd in ld.drives.items()}
        first = next(iter(checks.values()))
        out[which] = {"engine": first["engine"],
                      "runs": sum(c["runs"] for c in checks.values()),
                      "t_max": sum(shown[c] * v["t_max"] for c, v in checks.items()),
                      "actuation": sum(shown[c] * v["actuation"] for c, v in checks.items()),
                      "peak_c": [max(v["peak_c"]) for v in checks.values()],
                      "peak_error_k": max(v["peak_error_k"] for v in checks.values()),
                      "mean_error_k": max(v["mean_error_k"] for v in checks.values())}
    return out


def _window_peaks(dyn: ArrayDynamics, schedule: DutySchedule, a: float, b: float) -> NDArray:
    """The exact switched peak rise (K) of each cell between ``a`` and ``b`` (period starts)."""
    steps, after = steps_of(schedule, dyn.period, b)
    z = np.zeros(dyn.modes.lam.size)
    first = round(a / dyn.period)
    best = np.full(dyn.n, -np.inf)
    for f, count, d in steps:
        sm = SwitchedMap(dyn, np.asarray(d))
        lo = max(first - f, 0)
        if lo < count:
            pk = sm.peaks(sm.start(z, np.arange(lo, count)))
            best = np.maximum(best, pk.max(axis=0))
        z = sm.start(z, count)
    return best
