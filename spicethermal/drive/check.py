"""ngspice check of a safe fast drive (``spicethermal drive --verify``), in parallel pieces.

The check simulates the switched schedule (:meth:`DriveResult.spice_bench
<spicethermal.drive.result.DriveResult.spice_bench>`) in ``ngspice -b`` at 1/100 period over the
verification window (up to 4000 periods) and compares its junction peak with the prediction.
The window is one long, serial transient; for a linear model it need not be: the switched state
is known exactly at every period start (:meth:`DriveResult.switched_state
<spicethermal.drive.result.DriveResult.switched_state>`), so the window is cut at period
starts into as many pieces as there are cores (:func:`spicethermal.engines.pwmsim.workers`; a
boost at constant power is one more, at a step not bound by the period), each started with
``.ic`` in that exact state and run in its own ngspice. The pieces are joined by a check, not
by trust: each must end where the next begins (``join_k``: the largest difference between ngspice's
junction at the end of a piece and the exact one the next piece starts from), so a wrong start
shows as a jump. A model with device effects has no exact switched state: one piece from cold.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from typing import TYPE_CHECKING

import numpy as np

from ..core.progress import bar
from ..engines.pwmsim import workers
from ..spice.ngspice import simulator

if TYPE_CHECKING:  # pragma: no cover
    from ..spice.ngspice import Waveforms
    from .result import DriveResult


def pieces(result: DriveResult, n: int) -> list[tuple[float, float, float]]:
    """The verification window as ngspice runs ``(start_s, end_s, tmax_s)``, cut at period starts.

    The switched stretches (0 < duty < 1) share ``n`` runs in proportion to their periods, at
    a maximum step of 1/100 period; a stretch at constant power (duty 0 or 1: the boost) is one
    run whose step only ngspice's error control bounds (at most 1/1000 of the stretch), not
    the period. A model with device effects is one run over the window at 1/100 period.

    Parameters
    ----------
    result : DriveResult
        The drive to check.
    n : int
        Runs wanted for the switched stretches.

    Returns
    -------
    list of (float, float, float)
        Consecutive runs covering ``[0, verification_window_s]``.

    Examples
    --------
    >>> from spicethermal.drive.optimize import optimize_drive
    >>> from spicethermal.core.ladder import Foster
    >>> from spicethermal.model import ThermalModel
    >>> r = optimize_drive(ThermalModel(Foster.from_tau([30.0, 70.0], [0.01, 1.0])),
    ...                    70.0, 55.0, p_max_w=1.0)
    >>> runs = pieces(r, 2)
    >>> r.schedule[0][1], [(round(a / r.period_s), round(b / r.period_s)) for a, b, _ in runs]
    (1.0, [(0, 27), (27, 443), (443, 859)])
    >>> runs[-1][1] == r.verification_window_s(), runs[0][2] == runs[0][1] / 1000  # the boost
    (True, True)
    """
    window, period = result.verification_window_s(), result.period_s
    fine = period / 100
    if not result.model.is_linear:
        return [(0.0, window, fine)]
    # stretches of the schedule inside the window: (start, end, switched)
    stretches: list[list] = []
    ends = [t for t, _ in result.schedule[1:]] + [window]
    for (t, d), end in zip(result.schedule, ends, strict=True):
        a, b, switched = t, min(end, window), 0 < d < 1
        if a >= window:
            break
        if stretches and stretches[-1][2] == switched:
            stretches[-1][1] = b
        else:
            stretches.append([a, b, switched])
    total = sum(round((b - a) / period) for a, b, sw in stretches if sw)
    runs = []
    for a, b, switched in stretches:
        if not switched:
            runs.append((a, b, (b - a) / 1000))
            continue
        periods = round((b - a) / period)
        k = max(1, min(periods, round(n * periods / max(total, 1))))
        cut = [a + round(i * periods / k) * period for i in range(k)] + [b]
        runs += [(x, y, fine) for x, y in zip(cut[:-1], cut[1:], strict=True) if y > x]
    return runs


def verify(result: DriveResult, n: int | None = None, *, quiet: bool = True,
           engine: str = "ngspice") -> dict[str, float]:
    """Run the switched drive in ngspice and compare its junction peak with the prediction.

    Parameters
    ----------
    result : DriveResult
        The drive to check.
    n : int, optional
        Parallel runs of the switched stretches (default: the cores,
        :func:`spicethermal.engines.pwmsim.workers`); see :func:`pieces`.
    quiet : bool
        No progress bar on stderr.
    engine : str
        ``ngspice`` (``ngspice -b``, the runs in parallel) or ``pyspice`` (libngspice in
        process, one run at a time).

    Returns
    -------
    dict
        ``engine``, ``window_s``, ``pieces``, ``ngspice_peak_junction_c``,
        ``ngspice_peak_at_s``, and for a linear model ``predicted_peak_junction_c`` and
        ``join_k`` (0 with one piece).
    """
    runs = pieces(result, workers() if n is None else n)
    decks = [result.spice_bench(tstop_s=b, tmax_s=tmax, start_s=a) for a, b, tmax in runs]

    backend = simulator(engine)

    def run(deck: str) -> Waveforms:
        return backend.run(deck, ["V(TJ)"])

    # the work is in ngspice processes; the shared library runs one simulation at a time
    with ThreadPoolExecutor(len(decks) if backend.name == "ngspice" else 1) as pool:
        waves = list(bar(pool.map(run, decks), total=len(decks), desc="ngspice drive check",
                         quiet=quiet))
    offset = result.bench_offset_c
    peak, at, join = -np.inf, 0.0, 0.0
    window = runs[-1][1]
    for (start, end, _), wave in zip(runs, waves, strict=True):
        tj = wave["V(TJ)"] + offset
        k = int(np.argmax(tj))
        if tj[k] > peak:
            peak, at = float(tj[k]), start + float(wave.t_s[k])
        if end < window:  # ngspice's end of this piece against the exact start of the next
            exact = result.ambient_c + float(result.switched_state(end)[0])
            join = max(join, abs(float(tj[-1]) - exact))
    out = {"engine": backend.name, "window_s": window, "pieces": len(decks),
           "ngspice_peak_junction_c": peak, "ngspice_peak_at_s": at}
    tr = result.trace
    if tr.exact_t_s.size:
        sel = tr.exact_t_s <= window
        out["predicted_peak_junction_c"] = float(np.max(tr.exact_peak_c[sel]))
        out["join_k"] = join
    return out
