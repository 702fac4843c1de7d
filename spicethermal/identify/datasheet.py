"""The paper's Table 1 (§5) for any measured curve, and datasheet curves as Zth(t).

* :func:`read_zth_points` — a datasheet Zth(t) from a CSV
  (:func:`spicethermal.io.datasheet.read_zth_table`) as a :class:`ZthCurve`;
  :func:`datasheet_curve` — a :class:`~spicethermal.io.datasheet.Datasheet`'s points as one.
* :func:`table1` — rebuilds Table 1 for any measured curve: measured vs datasheet r(t) at the
  datasheet's times, ``error = (measured - datasheet) / datasheet · 100``, the measured r(t)
  interpolated in log time (and √t-extrapolated before its first sample, as the paper did
  below 100 us).

>>> ds = mur880e()
>>> c = datasheet_curve(ds)
>>> c.label, c.rth_k_per_w
('MUR880E datasheet', 1.51)
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..core.errors import DataFormatError
from ..io.bundle import Bundle
from ..io.columns import frozen
from ..io.datasheet import Datasheet, mur880e, read_zth_table
from ..io.jsondoc import JsonDocument
from .curves import ZthCurve

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray


def datasheet_curve(datasheet: Datasheet) -> ZthCurve:
    """The datasheet's points as a :class:`ZthCurve`.

    Parameters
    ----------
    datasheet : Datasheet
        The datasheet (:func:`~spicethermal.io.datasheet.mur880e`, ...).

    Returns
    -------
    ZthCurve
        Labelled ``DEVICE datasheet``.
    """
    return ZthCurve.from_points(datasheet.t_s, r=datasheet.r,
                                rth_k_per_w=datasheet.rth_k_per_w,
                                label=f"{datasheet.device} datasheet")


def read_zth_points(path: str | os.PathLike, rth_k_per_w: float | None = None,
                    device: str = "") -> ZthCurve:
    """Datasheet Zth points from a CSV: ``t_s`` and ``zth_k_per_w`` (absolute) or ``r``
    (normalized, needs ``rth_k_per_w``). Absolute points without Rth take their last value.

    Parameters
    ----------
    path : str or os.PathLike
        The CSV file (:func:`~spicethermal.io.datasheet.read_zth_table`).
    rth_k_per_w : float, optional
        Rth, K/W (needed for normalized ``r``).
    device : str
        Label of the curve.

    Returns
    -------
    ZthCurve
        The datasheet curve.

    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "zth.csv"
    >>> _ = p.write_text("t_s,r\\n1e-3,0.18\\n1e-2,0.39\\n")
    >>> read_zth_points(p, rth_k_per_w=1.51).zth_k_per_w.round(4).tolist()
    [0.2718, 0.5889]
    """
    table = read_zth_table(path, rth_k_per_w)
    return ZthCurve.from_table(table, label=device or Path(path).name)


def _pct(value: float) -> str:
    return f"{round(float(value), 1) + 0.0:.1f}"  # no "-0.0"


def _percent(measured: NDArray, reference: NDArray) -> NDArray:
    return (measured - reference) / reference * 100.0


#: Measured and datasheet Rth further apart than this factor are not the same device (or not
#: the same mounting): Table 1 then says so.
RTH_MISMATCH_FACTOR = 2.0


def rth_mismatch(measured_k_per_w: float, datasheet_k_per_w: float) -> str | None:
    """A warning when the measured and datasheet Rth differ by more than
    :data:`RTH_MISMATCH_FACTOR`, else None.

    >>> rth_mismatch(146.8, 1.51)[:70]
    "the measured Rth (146.8 K/W) is 97× the datasheet's (1.51 K/W): not th"
    >>> rth_mismatch(1.6, 1.51) is None
    True
    """
    ratio = measured_k_per_w / datasheet_k_per_w
    if not (ratio > RTH_MISMATCH_FACTOR or ratio < 1 / RTH_MISMATCH_FACTOR):
        return None
    times = f"{ratio:.2g}×" if ratio > 1 else f"1/{1 / ratio:.2g}"
    return (f"the measured Rth ({measured_k_per_w:.4g} K/W) is {times} the datasheet's "
            f"({datasheet_k_per_w:.4g} K/W): not the datasheet's device or mounting, so the "
            f"errors compare only the shapes of r(t)")


@dataclass(frozen=True, eq=False)
class Table1(JsonDocument):
    """Measured vs datasheet r(t) (the paper's Table 1 for any device and curve)."""

    device: str
    t_s: NDArray
    measured_r: NDArray
    datasheet_r: NDArray
    error_percent: NDArray
    rth_measured_k_per_w: float
    rth_datasheet_k_per_w: float
    extrapolated: NDArray
    reference_r: NDArray | None = None
    reference_error_percent: NDArray | None = None
    reference_label: str = ""
    curve_label: str = ""
    early: str = ""
    meta: dict[str, Any] = field(default_factory=dict, repr=False)

    @property
    def warnings(self) -> list[str]:
        """What the reader must know before reading the errors (an Rth mismatch)."""
        warning = rth_mismatch(self.rth_measured_k_per_w, self.rth_datasheet_k_per_w)
        return [warning] if warning else []

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dict (``format: spicethermal-table1/1``)."""
        rows = []
        for i, t in enumerate(self.t_s):
            row = {"t_s": float(t), "measured_r": float(self.measured_r[i]),
                   "datasheet_r": float(self.datasheet_r[i]),
                   "error_percent": float(self.error_percent[i]),
                   "extrapolated": bool(self.extrapolated[i])}
            if self.reference_r is not None:
                row[f"{self.reference_label}_measured_r"] = float(self.reference_r[i])
                row[f"{self.reference_label}_error_percent"] = float(
                    self.reference_error_percent[i])
            rows.append(row)
        return {"format": "spicethermal-table1/1", "device": self.device,
                "curve": self.curve_label,
                "rth_measured_k_per_w": self.rth_measured_k_per_w,
                "rth_datasheet_k_per_w": self.rth_datasheet_k_per_w,
                "rms_error_percent": float(np.sqrt(np.mean(self.error_percent ** 2))),
                "early_time_correction": self.early, "warnings": self.warnings,
                "rows": rows}

    def format(self) -> str:
        """The table as aligned text, laid out like the paper's."""
        head = ["time (ms)", "measured r(t)", "datasheet r(t)", "error (%)"]
        if self.reference_r is not None:
            head += [f"{self.reference_label} r(t)", f"{self.reference_label} error (%)"]
        body = []
        for i, t in enumerate(self.t_s):
            mark = "*" if self.extrapolated[i] else ""
            row = [f"{t * 1e3:.2f}", f"{self.measured_r[i]:.4f}{mark}",
                   f"{self.datasheet_r[i]:.3f}", _pct(self.error_percent[i])]
            if self.reference_r is not None:
                row += [f"{self.reference_r[i]:.3f}", _pct(self.reference_error_percent[i])]
            body.append(row)
        widths = [max(len(r[j]) for r in [head, *body]) for j in range(len(head))]
        lines = [f"{self.device}: measured ({self.curve_label}, Rth = "
                 f"{self.rth_measured_k_per_w:.4g} K/W) vs datasheet (Rth = "
                 f"{self.rth_datasheet_k_per_w:.4g} K/W)"]
        lines += ["  ".join(c.rjust(w) for c, w in zip(r, widths, strict=True))
                  for r in [head, *body]]
        if self.extrapolated.any():
            lines.append("* extrapolated by the sqrt(t) law (masked or before the first sample)")
        if self.early:
            lines.append(f"early-time correction: {self.early}")
        lines.extend(f"warning: {w}" for w in self.warnings)
        return "\n".join(lines)

    def __str__(self) -> str:
        return self.format()


def table1(source: ZthCurve | Bundle, datasheet: Datasheet | None = None, *,
           curve: int = 0, normalize: str = "measured") -> Table1:
    """Rebuild the paper's Table 1: measured vs datasheet r(t) with the error in percent.

    Parameters
    ----------
    source : a :class:`ZthCurve`, or a :class:`Bundle` (its curve number ``curve``: cooling
        curves first, then zth tables).
    datasheet : default :func:`mur880e`.
    normalize : ``"measured"`` — r(t) = Zth/Rth with the measured Rth (eq. 2, the paper, which
        biased the diode so that Rth matched the datasheet's); ``"datasheet"`` — divide by the
        datasheet's Rth.

    Returns
    -------
    Table1
        One row per datasheet time: measured and datasheet r(t), error in percent.

    Examples
    --------
    >>> ds = mur880e()
    >>> paper = ZthCurve.from_points(ds.t_s, r=ds.reference_r, rth_k_per_w=1.51)
    >>> (table1(paper).error_percent.round(1) + 0.0).tolist()   # the paper's error column
    [11.1, 13.3, 5.6, 0.0, 0.0, 0.0]
    """
    ds = datasheet if datasheet is not None else mur880e()
    if isinstance(source, Bundle):
        curves = ZthCurve.from_bundle(source)
        if not curves:
            raise DataFormatError(f"{source.source or 'bundle'}: no cooling curve or zth table")
        if not 0 <= curve < len(curves):
            raise DataFormatError(f"{source.source or 'bundle'}: curve {curve} does not exist "
                                  f"(it has {len(curves)})")
        zc = curves[curve]
    elif isinstance(source, ZthCurve):
        zc = source
    else:
        raise DataFormatError(f"table1: expected a ZthCurve or a Bundle, got "
                              f"{type(source).__name__}")
    if normalize not in ("measured", "datasheet"):
        raise DataFormatError(f"normalize = {normalize!r}: 'measured' or 'datasheet'")
    rth = zc.rth_k_per_w if normalize == "measured" else ds.rth_k_per_w
    # dense noisy records: a local straight line in log time over 0.1 decade (as resample_log
    # "bin" at 10 per decade); sparse ones: interpolation in log time
    measured = zc.at(ds.t_s, extrapolate=True, average_decades=0.1) / rth
    # read before the first sample, or inside the masked span (√t-extrapolated values)
    first = zc.early.masked_s[1] if zc.early and zc.early.masked_points else zc.t_s[0]
    extrapolated = ds.t_s < max(first, zc.t_s[0]) * (1 - 1e-9)
    ref_err = None if ds.reference_r is None else _percent(ds.reference_r, ds.r)
    if not np.all(np.isfinite(measured)) or math.isnan(rth):
        raise DataFormatError("table1: the measured curve gives no finite r(t)")
    return Table1(ds.device, ds.t_s, frozen(measured), ds.r, frozen(_percent(measured, ds.r)),
                  zc.rth_k_per_w, ds.rth_k_per_w, extrapolated, ds.reference_r, ref_err,
                  ds.reference_label, zc.label, str(zc.early) if zc.early else "")
