"""What ``spicethermal drive`` reports for an array: the document, its text, its figures' data.

:func:`cell_document` (one array through patterns) and :func:`line_document` (lines of text on
a line of cells) build the ``spicethermal-array-drive/1`` document
(``docs/array-model-format.md``): the limits, every pattern or line with its refresh time under
the crosstalk-aware drive, the naive lone drives and the constant hold, the violations of each
(predicted, and in ngspice when checked), the junction peaks and the achieved refresh rate.
:func:`summary` is its text; :func:`heat_rows` the temperatures of every dot over time that
the heat map draws.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

    from .refresh import CellDrive, LineDrive

__all__ = ["DRIVE_FORMAT", "cell_document", "heat_rows", "line_document", "summary"]

DRIVE_FORMAT = "spicethermal-array-drive/1"
DRIVES = ("ours", "naive", "constant")
#: The heat map's longest window, s (long enough for the substrate to warm).
HEAT_MAP_S = 120.0


def _limits(cd: CellDrive) -> dict[str, float]:
    lim = cd.limits
    return {"ambient_c": lim.ambient_c, "t_max_c": lim.t_max_c, "target_c": lim.target_c,
            "tol_k": lim.tol_k, "actuation_c": lim.actuation_c, "margin_k": lim.margin_k,
            "p_max_w": lim.p_max_w, "f_pwm_hz": lim.f_pwm_hz}


def _seconds(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


def cell_document(cd: CellDrive, checks: dict[str, dict] | None = None) -> dict[str, Any]:
    """The drive document of one array through its patterns.

    Parameters
    ----------
    cd : CellDrive
        The planned array.
    checks : dict, optional
        ngspice checks by drive (``ours``, ``naive``; :func:`.check.verify_drive`).

    Returns
    -------
    dict
        JSON-ready; ``null`` refresh times never complete.
    """
    names = [p.name for p in cd.model.ports]
    evs = {k: cd.evaluation(k) for k in DRIVES}
    patterns = [{"t_s": t, "up": [n for n, u in zip(names, up, strict=True) if u],
                 "refresh_s": {k: _seconds(ev.refresh_s[i]) for k, ev in evs.items()},
                 "raised_s": {k: _seconds(ev.raised_s[i]) for k, ev in evs.items()},
                 "hold_duty": list(cd.transitions[i].hold)}
                for i, (t, up) in enumerate(zip(cd.starts, cd.ups, strict=True))]
    return {"format": DRIVE_FORMAT, "kind": "patterns", "ports": names, "limits": _limits(cd),
            "patterns": patterns,
            "violations": {k: {"t_max": ev.count("t_max"), "actuation": ev.count("actuation")}
                           for k, ev in evs.items()},
            "peak_c": {k: ev.peak_c.tolist() for k, ev in evs.items()},
            "schedule": [[t, list(d)] for t, d in cd.schedule],
            "ngspice": checks or {}}


def line_document(ld: LineDrive, checks: dict[str, dict] | None = None) -> dict[str, Any]:
    """The drive document of lines of text on a line of cells.

    Parameters
    ----------
    ld : LineDrive
        The planned line.
    checks : dict, optional
        ngspice checks by drive (``ours``, ``naive``), summed over the distinct columns.

    Returns
    -------
    dict
    """
    first = ld.drives[ld.columns[0]]
    refresh = {k: [_seconds(x) for x in ld.refresh(k)] for k in DRIVES}
    raised = {k: [_seconds(x) for x in ld.raised(k)] for k in DRIVES}
    ours = ld.refresh("ours")
    rate = [1.0 / x if x > 0 and math.isfinite(x) else None for x in ours]
    return {"format": DRIVE_FORMAT, "kind": "text", "lines": list(ld.lines), "cells": ld.cells,
            "ports": [p.name for p in first.model.ports], "limits": _limits(first),
            "starts_s": list(ld.starts), "refresh_s": refresh, "raised_s": raised,
            "refresh_rate_hz": rate,
            "distinct_columns": len(ld.drives),
            "violations": {k: {"t_max": ld.count(k, "t_max"),
                               "actuation": ld.count(k, "actuation")} for k in DRIVES},
            "peak_c": {k: max(float(np.max(ld.drives[c].evaluation(k).peak_c))
                              for c in ld.columns) for k in DRIVES},
            "ngspice": checks or {}}


def _time(x: float | None) -> str:
    return "never" if x is None else f"{1e3 * x:.1f} ms" if x < 1 else f"{x:.3g} s"


def summary(doc: dict[str, Any]) -> str:
    """The document as text: refresh times, violations, peaks, ngspice.

    Parameters
    ----------
    doc : dict
        :func:`cell_document` or :func:`line_document`.

    Returns
    -------
    str
    """
    lim = doc["limits"]
    lines = [f"array drive: {len(doc['ports'])} dots per cell, target {lim['target_c']:g} ± "
             f"{lim['tol_k']:g} °C, actuation {lim['actuation_c']:g} °C (down dots below "
             f"{lim['actuation_c'] - lim['margin_k']:g} °C), t_max {lim['t_max_c']:g} °C, "
             f"{lim['p_max_w']:g} W at {lim['f_pwm_hz']:g} Hz"]
    if doc["kind"] == "text":
        lines.append(f"{len(doc['lines'])} line(s) of text on {doc['cells']} cells "
                     f"({doc['distinct_columns']} distinct columns planned)")
        for k, text in enumerate(doc["lines"]):
            r = {d: doc["refresh_s"][d][k] for d in DRIVES}
            u = {d: doc["raised_s"][d][k] for d in DRIVES}
            lines.append(f"  line {k + 1} {text!r} at {doc['starts_s'][k]:.4g} s: refresh "
                         f"{_time(r['ours'])} (naive {_time(r['naive'])}, constant hold "
                         f"{_time(r['constant'])}); every dot up after {_time(u['ours'])} "
                         f"(naive {_time(u['naive'])}, constant {_time(u['constant'])})")
        rate = doc["refresh_rate_hz"][0]
        if rate is not None:
            lines.append(f"refresh rate of a line from blank: {rate:.1f} lines/s "
                         f"({_time(doc['refresh_s']['ours'][0])})")
    else:
        for k, pat in enumerate(doc["patterns"]):
            r, u = pat["refresh_s"], pat["raised_s"]
            lines.append(f"  pattern {k + 1} at {pat['t_s']:.4g} s, up {' '.join(pat['up']) or '-'}"
                         f": refresh {_time(r['ours'])} (naive {_time(r['naive'])}, constant "
                         f"hold {_time(r['constant'])}); dots up after {_time(u['ours'])} "
                         f"(naive {_time(u['naive'])})")
    for d in DRIVES:
        v = doc["violations"][d]
        peak = doc["peak_c"][d]
        top = max(peak) if isinstance(peak, list) else peak
        lines.append(f"{d:>8}: {v['t_max']} t_max and {v['actuation']} actuation violations; "
                     f"hottest junction {top:.2f} °C")
    for d, check in doc.get("ngspice", {}).items():
        lines.append(f"ngspice ({d}): {check['t_max']} t_max and {check['actuation']} actuation "
                     f"violations, hottest junction {max(check['peak_c']):.2f} °C; peaks within "
                     f"{check['peak_error_k']:.3g} K and averages within "
                     f"{check['mean_error_k']:.3g} K of the prediction ({check['runs']} runs)")
    return "\n".join(lines)


def heat_rows(ld: LineDrive, line: int = 0, t_points: int = 300, which: str = "ours"
              ) -> tuple[NDArray, NDArray, list[str]]:
    """Every dot's heater temperature under a drive over one line's window.

    Parameters
    ----------
    ld : LineDrive
        The planned line.
    line : int
        Which line.
    which : str
        ``ours``, ``naive`` or ``constant``.
    t_points : int
        Time samples (logarithmic from a PWM period to the next line, or at most
        :data:`HEAT_MAP_S`).

    Returns
    -------
    t_s : NDArray
        Times from the line's start, s.
    temps_c : NDArray
        ``(cells · dots, len(t_s))``: cell by cell, dot by dot, °C.
    labels : list of str
        ``"c3 D2"`` per row.
    """
    start = ld.starts[line]
    end = ld.starts[line + 1] if line + 1 < len(ld.starts) else None
    first = ld.drives[ld.columns[0]]
    period = 1.0 / first.limits.f_pwm_hz
    stop = (end if end is not None else first.t_end) - start
    stop = min(stop, HEAT_MAP_S)
    t = np.geomspace(period, stop, t_points)
    rows, labels = [], []
    for c, col in enumerate(ld.columns):
        ev = ld.drives[col].evaluation(which)
        for i, port in enumerate(first.model.ports):
            rows.append(np.interp(start + t, ev.t_s, ev.mean_c[:, i]))
            labels.append(f"c{c + 1} {port.name}")
    return t, np.array(rows), labels
