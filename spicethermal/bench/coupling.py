"""The coupling run of an array board: heat one, read all, for every heater in turn.

For each heater the firmware's coupling procedure (``firmware/PROTOCOL.md`` §6) scans every
port cold, heats that heater to its steady state, scans every port through the sample window,
cuts the power and scans every port at log-spaced times. This module turns the samples into
the bundle's ``coupling`` section (:mod:`spicethermal.io.coupling`):

* every port's TSP voltage becomes a temperature through the bundle's calibration (made on the
  hot plate with the first diode), each diode anchored at its own cold reading — the ambient
  the reference thermocouple reads then — so that only the calibration's slope carries over
  from diode to diode (the K-factor practice of JESD51-14, ``docs/bundle-format.md``);
* the curve's scans become rows (port 1's time; the spacing of a scan, ``scan_s``, from the
  reported times), the window scans the steady temperatures before the cut.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Protocol

import numpy as np

from ..array.braille import cell_ports
from ..core.errors import DataFormatError, InstrumentError
from ..io.coupling import CouplingSection, CouplingTable, Port
from . import protocol as p
from .client import COUPLING_PROTOCOL

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import ArrayLike, NDArray

    from ..identify.calibration import Calibration
    from .client import BenchClient, Run
    from .plan import Plan

__all__ = ["array_ports", "coupling_table", "measure_coupling"]


class TspConversion(Protocol):
    """What converts a TSP reading (:class:`spicethermal.bench.session.TspConversion`)."""

    cal: Calibration

    def tj_c(self, v_tsp_v: ArrayLike, t_ref_diode_c: float) -> NDArray:
        """Junction temperatures, °C."""


def array_ports(plan: Plan, heaters: int) -> list[Port]:
    """The ports of the board's ``heaters``, placed on the plan's grid.

    Parameters
    ----------
    plan : Plan
        ``array_rows``, ``array_cols`` (0: a Braille cell for 6 or 8 heaters, else a row) and
        ``array_pitch_mm``.
    heaters : int
        What the board reports.

    Returns
    -------
    list of Port
    """
    rows, cols = plan.array_rows, plan.array_cols
    if not rows or not cols:
        rows, cols = (heaters // 2, 2) if heaters in (6, 8) else (1, heaters)
    if rows * cols != heaters:
        raise DataFormatError(f"bench coupling: a {rows} x {cols} grid has {rows * cols} cells, "
                              f"the board {heaters} heaters (give --grid ROWSxCOLS)")
    return cell_ports(rows, cols, plan.array_pitch_mm)


def _by_port(samples: Sequence[p.Sample], kind: int, n: int) -> list[list[p.Sample]]:
    out: list[list[p.Sample]] = [[] for _ in range(n)]
    for s in samples:
        if s.kind == kind:
            out[getattr(s, "port", 0)].append(s)
    return out


def coupling_table(run: Run, conv: TspConversion, heater: int, n: int,
                   window_s: float) -> tuple[CouplingTable, float]:
    """One heater's table from its run, and the scan spacing it shows (s).

    Parameters
    ----------
    run : Run
        The coupling procedure's samples.
    conv : TspConversion
        The calibration.
    heater : int
        The heated port.
    n : int
        Ports read.
    window_s : float
        The sample window of the steady readings, s.

    Returns
    -------
    table : CouplingTable
    scan_s : float
    """
    where = f"coupling run of heater {heater + 1}"
    cold = _by_port(run.samples, p.KIND_COLD, n)
    steady = _by_port(run.samples, p.KIND_STEADY, n)
    power = [s for s in run.samples if s.kind == p.KIND_POWER]
    curve = [s for s in run.samples if s.kind == p.KIND_CURVE]
    if any(not c for c in cold) or any(not s for s in steady) or not power or not curve \
            or len(curve) % n:
        raise InstrumentError(f"{where}: incomplete (every port needs cold, steady and curve "
                              f"readings)")
    t_rd = float(np.mean([s.taux_c for s in run.samples]))
    tamb_cold = float(np.mean([s.tamb_c for c in cold for s in c]))
    g = conv.cal.voltage
    # each diode's offset from the calibrated one, from its cold reading at tamb_cold
    offset = [float(np.mean([s.v_tsp_v for s in c])) + float(g(t_rd)) - float(g(tamb_cold))
              for c in cold]
    scans = np.array(curve, dtype=object).reshape(-1, n)
    if any(s.port != k for row in scans for k, s in enumerate(row)):
        raise InstrumentError(f"{where}: a curve scan does not read the ports in order")
    v = np.array([[s.v_tsp_v for s in row] for row in scans]) - np.array(offset)
    tj = np.column_stack([conv.tj_c(v[:, k], t_rd) for k in range(n)])
    t = np.array([row[0].t_s for row in scans])
    spacing = np.array([[s.t_s - row[0].t_s for s in row] for row in scans])
    scan_s = float(np.median(spacing[:, 1:] / np.arange(1, n))) if n > 1 else 0.0
    steady_c = [float(np.mean(conv.tj_c([s.v_tsp_v - offset[k] for s in steady[k]], t_rd)))
                for k in range(n)]
    table = CouplingTable(
        heated=heater, t_s=t, tj_c=np.round(tj, 5),
        power_w=round(float(np.mean([s.power_w for s in power])), 7),
        tref_c=np.round([row[0].tamb_c for row in scans], 4),
        tj_steady_c=tuple(round(x, 5) for x in steady_c),
        tref_steady_c=round(float(np.mean([s.tamb_c for c in steady for s in c])), 4),
        extra={"window_s": window_s, "tsp_offset_v": [round(x, 8) for x in offset]})
    return table, scan_s


def measure_coupling(bench: BenchClient, plan: Plan, conv: TspConversion | None,
                     step: Callable[[str, float], None]) -> CouplingSection:
    """Heat every heater of the array board in turn and read every port.

    Parameters
    ----------
    bench : BenchClient
        A connected array board.
    plan : Plan
        Power (``coupling_power_w``), settling, window, readings, the curve's times, the grid.
    conv : TspConversion or None
        The bundle's calibration (needed).
    step : callable
        Progress: called with a label and the simulated seconds of the step.

    Returns
    -------
    CouplingSection
    """
    if bench.info.proto < COUPLING_PROTOCOL:
        raise InstrumentError(f"{bench.url}: firmware {bench.info.firmware} (protocol "
                              f"{bench.info.proto}) has no coupling procedure; update it to 1.3")
    heaters = bench.info.ports
    if heaters < 2:
        raise InstrumentError(f"{bench.url}: board {bench.info.name!r} (firmware "
                              f"{bench.info.firmware}) is not an array board")
    if conv is None:
        raise DataFormatError("bench coupling: needs a calibration (run 'bench calibrate' into "
                              "the same bundle first)")
    ports = array_ports(plan, heaters)
    tables, spacings = [], []
    for k in range(heaters):
        budget = plan.settle_s + plan.cooling_t_last_s
        step(f"coupling: heater {ports[k].name} ({k + 1} of {heaters})", budget)
        run = bench.coupling(k, plan.coupling_power_w, plan.settle_s, plan.window_s,
                             plan.n_readings, plan.cooling_t_first_s, plan.cooling_t_last_s,
                             plan.per_decade)
        bench.progress.advance(budget)
        table, scan_s = coupling_table(run, conv, k, heaters, plan.window_s)
        tables.append(table)
        spacings.append(scan_s)
    return CouplingSection(tuple(ports), float(np.median(spacings)), tuple(tables))
