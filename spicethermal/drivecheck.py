"""ngspice check of a safe fast drive (``spicethermal drive --verify``), in parallel pieces.

The check simulates the switched schedule (:meth:`DriveResult.spice_bench
<spicethermal.drive.DriveResult.spice_bench>`) in ``ngspice -b`` at 1/100 period over the
verification window (up to 4000 periods) and compares its junction peak with the prediction.
The window is one long, serial transient; for a linear model it need not be: the switched state
is known exactly at every period start (:meth:`DriveResult.switched_state
<spicethermal.drive.DriveResult.switched_state>`), so the window is cut at period starts into as
many pieces as there are cores (:func:`spicethermal.pwmsim.workers`), each started with ``.ic``
in that exact state and run in its own ngspice. The pieces are joined by a check, not by trust:
each must end where the next begins (``join_k``: the largest difference between ngspice's
junction at the end of a piece and the exact one the next piece starts from), so a wrong start
shows as a jump. A model with device effects has no exact switched state: one piece from cold.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:  # pragma: no cover
    from .drive import DriveResult
    from .spice import Waveforms


def cuts(result: DriveResult, pieces: int) -> list[float]:
    """Times (s) cutting the verification window into ``pieces`` runs at period starts.

    Parameters
    ----------
    result : DriveResult
        The drive to check.
    pieces : int
        Wanted number of runs (one for a model with device effects).

    Returns
    -------
    list of float
        ``0, t_1, ..., window``: piece k runs from ``cuts[k]`` to ``cuts[k + 1]``.

    Examples
    --------
    >>> from spicethermal.drive import optimize_drive
    >>> from spicethermal.ladder import Foster
    >>> from spicethermal.model import ThermalModel
    >>> r = optimize_drive(ThermalModel(Foster.from_tau([30.0, 70.0], [0.01, 1.0])),
    ...                    70.0, 55.0, p_max_w=1.0)
    >>> c = cuts(r, 2)
    >>> len(c), c[0], c[-1] == r.verification_window_s()
    (3, 0.0, True)
    """
    window = result.verification_window_s()
    periods = int(window * result.f_pwm_hz + 1e-9)
    k = max(1, min(int(pieces), periods)) if result.model.is_linear else 1
    inner = sorted({round(i * periods / k) * result.period_s for i in range(1, k)})
    return [0.0, *[t for t in inner if 0 < t < window], window]


def verify(result: DriveResult, pieces: int | None = None, *, quiet: bool = True
           ) -> dict[str, float]:
    """Run the switched drive in ngspice and compare its junction peak with the prediction.

    Parameters
    ----------
    result : DriveResult
        The drive to check.
    pieces : int, optional
        Parallel runs (default: the cores, :func:`spicethermal.pwmsim.workers`; always one
        for a model with device effects).
    quiet : bool
        No progress bar on stderr.

    Returns
    -------
    dict
        ``window_s``, ``pieces``, ``ngspice_peak_junction_c``, ``ngspice_peak_at_s``, and for a
        linear model ``predicted_peak_junction_c`` and ``join_k`` (0 with one piece).
    """
    from .progress import bar
    from .pwmsim import workers
    from .spice import NgspiceBatch

    edges = cuts(result, workers() if pieces is None else pieces)
    decks = [result.spice_bench(tstop_s=b, start_s=a)
             for a, b in zip(edges[:-1], edges[1:], strict=True)]

    def run(deck: str) -> Waveforms:
        return NgspiceBatch().run(deck, ["V(TJ)"])

    with ThreadPoolExecutor(len(decks)) as pool:  # the work is in ngspice processes
        waves = list(bar(pool.map(run, decks), total=len(decks), desc="ngspice drive check",
                         quiet=quiet))
    offset = result.bench_offset_c
    peak, at, join = -np.inf, 0.0, 0.0
    for start, end, wave in zip(edges[:-1], edges[1:], waves, strict=True):
        tj = wave["V(TJ)"] + offset
        k = int(np.argmax(tj))
        if tj[k] > peak:
            peak, at = float(tj[k]), start + float(wave.t_s[k])
        if end < edges[-1]:  # ngspice's end of this piece against the exact start of the next
            exact = result.ambient_c + float(result.switched_state(end)[0])
            join = max(join, abs(float(tj[-1]) - exact))
    out = {"window_s": edges[-1], "pieces": len(decks), "ngspice_peak_junction_c": peak,
           "ngspice_peak_at_s": at}
    tr = result.trace
    if tr.exact_t_s.size:
        sel = tr.exact_t_s <= edges[-1]
        out["predicted_peak_junction_c"] = float(np.max(tr.exact_peak_c[sel]))
        out["join_k"] = join
    return out
