"""Real thermal transients in other tools' files, read: :class:`Record`.

* :func:`pyrth_record` — the PyRth text format (``MOSFET_dry.txt``): a ``DATA`` line, a header
  line, then two columns, time (s) and sensor voltage (V). The file holds no calibration and
  no power: pass them (the MOSFET files' calibration points are
  :data:`PYRTH_MOSFET_CALIBRATION`, shipped as ``pyrth_mosfet/calibration.csv``; PyRth's
  nominal power is 1 W). There is no default calibration: another device's would be wrong.
* :func:`t3ster_record` — the legacy export of a Simcenter T3Ster: ``.raw`` (time response
  record: ``time_us adc_count`` rows after a ``#`` header that gives the ADC step ``lsb`` (V,
  7th header line) and the offset voltage ``uref`` (V, 9th), so that
  ``V = uref + (count - 4095/2) · lsb``), ``.pwr`` (``Power=`` in its ``[power]`` section, the
  heating power step in W) and ``.tco`` (temperature/voltage calibration rows after ``#``
  comments; the 6th and 7th header lines hold the instrument's fitted line ``V = a0 + a1 T``,
  kept as a ``polynomial`` calibration with the rows as its residuals).

Both are cooling transients recorded from the trigger: leading samples taken before the
switch (PyRth: the first run of identical values; T3Ster: time 0) are dropped, the times are
kept as recorded. What the files hold is read here, as a :class:`Record`; the bundle made of
it, with its calibration anchored and its reference temperature read through the calibration,
is :func:`spicethermal.identify.records.read_pyrth` and
:func:`~spicethermal.identify.records.read_t3ster`.
"""

from __future__ import annotations

import os
import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..core.errors import DataFormatError, where
from .columns import parse_number
from .datasets import CalibrationTable, KFactorLaw
from .files import read_text

#: Calibration points of the PyRth MOSFET files, (Tj degC, Usens V): about -2.32 mV/K.
PYRTH_MOSFET_CALIBRATION: tuple[tuple[float, float], ...] = (
    (23.4, 0.55843), (37.625, 0.52536), (51.85, 0.49232), (66.075, 0.45927), (80.3, 0.42621))

#: Samples averaged at the end of a record for the reference temperature.
END_SAMPLES = 5

T3STER_ADC_LEVELS = 4095.0


#: What the importers accept as a calibration.
CalibrationLike = CalibrationTable | KFactorLaw | Sequence[Sequence[float]]


@dataclass(frozen=True, eq=False)
class Record:
    """A cooling transient as another tool's files hold it.

    Attributes
    ----------
    t_s, v_tsp_v : ndarray
        The samples after the switch: times (s, as recorded) and sensor voltages (V).
    rows : ndarray
        The file line of each sample.
    label : str
        The record's file, as messages name it.
    device : str
        The device's name (given, or made from the file's).
    source : dict
        What was read and dropped, for the bundle's ``source`` key.
    power_w : float or None
        The heating power step, when the files hold it (T3Ster's ``.pwr``).
    calibration : CalibrationTable or None
        The calibration, when the files hold it (T3Ster's ``.tco``).
    """

    t_s: np.ndarray
    v_tsp_v: np.ndarray
    rows: np.ndarray
    label: str
    device: str
    source: dict[str, Any] = field(default_factory=dict)
    power_w: float | None = None
    calibration: CalibrationTable | None = None


def calibration_table(calibration: CalibrationLike | None, label: str
                      ) -> CalibrationTable | KFactorLaw:
    """The calibration given for a record that holds none, as a bundle holds it.

    Parameters
    ----------
    calibration : CalibrationTable, KFactorLaw or (temp_c, v_tsp_v) pairs
        As given (None: an error that names the options).
    label : str
        The record, as messages name it.

    Returns
    -------
    CalibrationTable or KFactorLaw

    Examples
    --------
    >>> calibration_table(PYRTH_MOSFET_CALIBRATION, "x.txt").temp_c.tolist()[:2]
    [23.4, 37.625]
    """
    if calibration is None:
        raise DataFormatError(f"{label}: the file holds no calibration: give one (--calibration "
                              f"CSV with temp_c, v_tsp_v, or --k-factor MV_PER_K with --ambient "
                              f"DEGC)")
    if isinstance(calibration, CalibrationTable | KFactorLaw):
        return calibration
    try:
        pts = np.asarray(calibration, dtype=float)
    except (TypeError, ValueError):
        raise DataFormatError(f"{label}: calibration must be (temp_c, v_tsp_v) pairs") from None
    if pts.ndim != 2 or pts.shape[1] != 2:
        raise DataFormatError(f"{label}: calibration must be (temp_c, v_tsp_v) pairs")
    return CalibrationTable(pts[:, 0], pts[:, 1], file="calibration.csv")


def _two_columns(lines: Sequence[tuple[int, str]], label: str, names: tuple[str, str]
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    a, b, rows = [], [], []
    for lineno, line in lines:
        fields = line.split()
        if len(fields) != 2:
            raise DataFormatError(f"{where(label, lineno)}{len(fields)} fields, expected 2 "
                                  f"({names[0]}, {names[1]})")
        a.append(parse_number(fields[0], label, lineno, names[0]))
        b.append(parse_number(fields[1], label, lineno, names[1]))
        rows.append(lineno)
    if not rows:
        raise DataFormatError(f"{where(label)}no data rows")
    return np.array(a), np.array(b), np.array(rows)


def pyrth_record(path: str | os.PathLike, device: str | None = None) -> Record:
    """Read a PyRth transient text file (``DATA`` line, header, ``time voltage`` rows).

    Parameters
    ----------
    path : str or os.PathLike
        The ``.txt`` file.
    device : str, optional
        A name for the device (default: made from the file's).

    Returns
    -------
    Record
        Without power or calibration (the file holds neither).

    Examples
    --------
    >>> from spicethermal.data import path
    >>> r = pyrth_record(path("pyrth_mosfet/MOSFET_dry.txt"))
    >>> r.device, r.source["dropped_before_switch"] > 0, r.power_w
    ('PyRth transient MOSFET_dry', True, None)
    """
    path = Path(path)
    label = str(path)
    lines = read_text(path).splitlines()
    start = next((i for i, line in enumerate(lines) if line.strip() == "DATA"), None)
    if start is None:
        raise DataFormatError(f"{label}: no DATA line; not a PyRth transient file")
    body = [(i + 1, line.strip()) for i, line in enumerate(lines) if i > start + 1
            and line.strip() and not line.strip().startswith("#")]
    if start + 1 >= len(lines):
        raise DataFormatError(f"{where(label, start + 1)}DATA line without a header")
    t, v, rows = _two_columns(body, label, ("time", "voltage"))
    # the samples before the switch hold one repeated value: drop that leading run
    same = int(np.argmax(v != v[0])) if np.any(v != v[0]) else v.size
    first = same if same >= 2 else 0
    if v.size - first < 3:
        raise DataFormatError(f"{label}: fewer than 3 samples after the switch")
    return Record(t[first:], v[first:], rows[first:], label,
                  device or f"PyRth transient {path.stem}",
                  {"format": "pyrth-text", "file": path.name, "dropped_before_switch": first})


def _t3ster_power(path: Path) -> float:
    section = ""
    for lineno, raw in enumerate(read_text(path).splitlines(), start=1):
        line = raw.split(";", 1)[0].strip()
        if line.startswith("[") and line.endswith("]"):
            section = line[1:-1].lower()
        elif "=" in line:
            key, value = (s.strip() for s in line.split("=", 1))
            if key.lower() in ("power", "powerstep") and section in ("power", ""):
                p = parse_number(value.split()[0] if value else "", str(path), lineno, key)
                if p == 0:
                    raise DataFormatError(f"{where(str(path), lineno, key)}zero power step")
                return abs(p)
    raise DataFormatError(f"{path}: no Power= entry in a [power] section")


def _t3ster_calibration(path: Path) -> CalibrationTable:
    lines = list(enumerate(read_text(path).splitlines(), start=1))
    body = [(i, line.strip()) for i, line in lines
            if line.strip() and not line.strip().startswith("#")]
    temp, volt, rows = _two_columns(body, str(path), ("temp_c", "v_tsp_v"))
    header = [line.strip().lstrip("#").strip() for _, line in lines
              if line.strip().startswith("#")]
    coefficients = None
    if len(header) >= 7 and all(re.fullmatch(r"[+-]?[\d.]+([eE][+-]?\d+)?", h)
                                for h in header[5:7]):
        coefficients = (float(header[5]), float(header[6]))
    return CalibrationTable(temp, volt, file="calibration.csv", coefficients=coefficients)


def t3ster_record(raw: str | os.PathLike, pwr: str | os.PathLike | None = None,
                  tco: str | os.PathLike | None = None, device: str | None = None) -> Record:
    """Read a T3Ster measurement (``.raw`` + ``.pwr`` + ``.tco``).

    Parameters
    ----------
    raw : str or os.PathLike
        The ``.raw`` time response record.
    pwr : str or os.PathLike, optional
        The power file; default the ``.pwr`` beside ``raw`` with the same stem.
    tco : str or os.PathLike, optional
        The calibration; default the only ``.tco`` file in that directory.
    device : str, optional
        A name for the device.

    Returns
    -------
    Record
        With the ``.pwr`` power and the ``.tco`` calibration (kind ``polynomial`` when its
        header holds the line).

    Examples
    --------
    >>> from spicethermal.data import path
    >>> r = t3ster_record(path("pyrth_mosfet/t3ster/T25_I-m5m-I-h600m_100s.raw"))
    >>> r.calibration.kind, round(r.power_w, 4)
    ('polynomial', 1.7541)
    """
    raw = Path(raw)
    label = str(raw)
    pwr = Path(pwr) if pwr is not None else raw.with_suffix(".pwr")
    if tco is None:
        found = sorted(raw.parent.glob("*.tco"))
        if len(found) != 1:
            raise DataFormatError(f"{label}: give the .tco calibration file ({len(found)} "
                                  f"found beside it)")
        tco = found[0]
    tco = Path(tco)
    header: list[tuple[int, str]] = []
    body: list[tuple[int, str]] = []
    for lineno, line in enumerate(read_text(raw).splitlines(), start=1):
        s = line.strip()
        if not s:
            continue
        (header if s.startswith("#") else body).append((lineno, s))
    if not header or "TIME RESPONSE RECORD" not in header[0][1].upper():
        raise DataFormatError(f"{where(label, 1)}not a T3Ster time response record")
    if len(header) < 9:
        raise DataFormatError(f"{label}: T3Ster header has {len(header)} lines, expected 10")

    def head(i: int, what: str) -> float:
        lineno, s = header[i]
        text = s.lstrip("#").strip()
        if not re.fullmatch(r"[+-]?[\d.]+([eE][+-]?\d+)?", text):
            raise DataFormatError(f"{where(label, lineno)}{what}: malformed number {text!r}")
        return float(text)

    lsb = head(6, "ADC step (lsb)")
    uref = head(8, "offset voltage (uref)")
    if lsb <= 0:
        raise DataFormatError(f"{where(label, header[6][0])}ADC step must be > 0")
    t_us, counts, rows = _two_columns(body, label, ("time_us", "adc_count"))
    after = t_us > 0
    if after.sum() < 3:
        raise DataFormatError(f"{label}: fewer than 3 samples after the switch")
    v = uref + (counts[after] - T3STER_ADC_LEVELS / 2.0) * lsb
    return Record(t_us[after] * 1e-6, v, rows[after], label, device or f"T3Ster record {raw.stem}",
                  {"format": "t3ster", "file": raw.name, "pwr": pwr.name, "tco": tco.name,
                   "lsb_v": lsb, "uref_v": uref, "dropped_before_switch": int((~after).sum())},
                  calibration=_t3ster_calibration(tco), power_w=_t3ster_power(pwr))
