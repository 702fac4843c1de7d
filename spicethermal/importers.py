"""Importers of real thermal transients from other tools' files into a :class:`Bundle`.

* :func:`read_pyrth` — the PyRth text format (``MOSFET_dry.txt``): a ``DATA`` line, a header
  line, then two columns, time (s) and sensor voltage (V). The file holds no calibration and
  no power: pass them (the MOSFET files' calibration points are
  :data:`PYRTH_MOSFET_CALIBRATION`; PyRth's nominal power is 1 W).
* :func:`read_t3ster` — the legacy export of a Simcenter T3Ster: ``.raw`` (time response
  record: ``time_us adc_count`` rows after a ``#`` header that gives the ADC step ``lsb`` (V,
  7th header line) and the offset voltage ``uref`` (V, 9th), so that
  ``V = uref + (count - 4095/2) · lsb``), ``.pwr`` (``Power=`` in its ``[power]`` section, the
  heating power step in W) and ``.tco`` (temperature/voltage calibration rows after ``#``
  comments).

Both are cooling transients recorded from the trigger: leading samples taken before the
switch (PyRth: the first run of identical values; T3Ster: time 0) are dropped, the times are
kept as recorded. The reference temperature is taken as the junction temperature at the end
of the record (``tref_steady_c``, the mean of the last 5 samples): the device is assumed back
at its reference by then, so Rth is the rise recorded over the whole transient.
"""

from __future__ import annotations

import os
import re
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path

import numpy as np

from .bundle import Bundle, CalibrationTable, CoolingTable, _number
from .errors import DataFormatError, where
from .files import read_text

#: Calibration points of the PyRth MOSFET files, (Tj degC, Usens V): about -2.32 mV/K.
PYRTH_MOSFET_CALIBRATION: tuple[tuple[float, float], ...] = (
    (23.4, 0.55843), (37.625, 0.52536), (51.85, 0.49232), (66.075, 0.45927), (80.3, 0.42621))

#: Samples averaged at the end of a record for the reference temperature.
END_SAMPLES = 5

T3STER_ADC_LEVELS = 4095.0


def _calibration_table(calibration: CalibrationTable | Sequence[Sequence[float]],
                       label: str) -> CalibrationTable:
    if isinstance(calibration, CalibrationTable):
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
        a.append(_number(fields[0], label, lineno, names[0]))
        b.append(_number(fields[1], label, lineno, names[1]))
        rows.append(lineno)
    if not rows:
        raise DataFormatError(f"{where(label)}no data rows")
    return np.array(a), np.array(b), np.array(rows)


def _cooling_bundle(t: np.ndarray, v: np.ndarray, rows: np.ndarray, label: str,
                    calibration: CalibrationTable, power_w: float, device: str,
                    source: dict) -> Bundle:
    cal = calibration.fit("auto")
    tref = float(np.mean(cal.temperature(v[-END_SAMPLES:])))
    cooling = CoolingTable(t, power_w, v_tsp_v=v, tref_steady_c=tref, file=label, rows=rows,
                           extra={"tref_steady_from": f"mean of the last {END_SAMPLES} samples"})
    bundle = Bundle(device=device, reference="ambient", calibration=calibration,
                    cooling=(cooling,), extra={"source": source})
    # checked above under the source's name; written as a plain file name
    return bundle.with_(cooling=(replace(cooling, file="cooling_1.csv"),), source=label)


def read_pyrth(path: str | os.PathLike,
               calibration: CalibrationTable | Sequence[Sequence[float]] =
               PYRTH_MOSFET_CALIBRATION,
               power_w: float = 1.0, device: str | None = None) -> Bundle:
    """Read a PyRth transient text file (``DATA`` line, header, ``time voltage`` rows).

    Parameters
    ----------
    path : the ``.txt`` file.
    calibration : (temp_c, v_tsp_v) pairs or a :class:`CalibrationTable`.
    power_w : the heating power step, W (PyRth's files do not store it; 1 W nominal).

    Returns
    -------
    Bundle
        Calibration and one cooling curve with raw ``v_tsp_v``.

    Examples
    --------
    >>> from spicethermal.data import path
    >>> b = read_pyrth(path("pyrth_mosfet/MOSFET_dry.txt"))
    >>> round(b.calibration_fit().k_factor_mv_per_k, 2)
    -2.32
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
    table = _calibration_table(calibration, label)
    return _cooling_bundle(t[first:], v[first:], rows[first:], label, table, power_w,
                           device or f"PyRth transient {path.stem}",
                           {"format": "pyrth-text", "file": path.name,
                            "dropped_before_switch": first, "power_w_nominal": power_w})


def _t3ster_power(path: Path) -> float:
    section = ""
    for lineno, raw in enumerate(read_text(path).splitlines(), start=1):
        line = raw.split(";", 1)[0].strip()
        if line.startswith("[") and line.endswith("]"):
            section = line[1:-1].lower()
        elif "=" in line:
            key, value = (s.strip() for s in line.split("=", 1))
            if key.lower() in ("power", "powerstep") and section in ("power", ""):
                p = _number(value.split()[0] if value else "", str(path), lineno, key)
                if p == 0:
                    raise DataFormatError(f"{where(str(path), lineno, key)}zero power step")
                return abs(p)
    raise DataFormatError(f"{path}: no Power= entry in a [power] section")


def _t3ster_calibration(path: Path) -> CalibrationTable:
    body = [(i, line.strip()) for i, line in enumerate(read_text(path).splitlines(), start=1)
            if line.strip() and not line.strip().startswith("#")]
    temp, volt, rows = _two_columns(body, str(path), ("temp_c", "v_tsp_v"))
    return CalibrationTable(temp, volt, file="calibration.csv")


def read_t3ster(raw: str | os.PathLike, pwr: str | os.PathLike | None = None,
                tco: str | os.PathLike | None = None, device: str | None = None) -> Bundle:
    """Read a T3Ster measurement (``.raw`` + ``.pwr`` + ``.tco``) into a bundle.

    ``pwr`` defaults to the ``.pwr`` file beside ``raw`` with the same stem; ``tco`` to the
    only ``.tco`` file in that directory. See the module docstring for the formats.
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
    return _cooling_bundle(t_us[after] * 1e-6, v, rows[after], label, _t3ster_calibration(tco),
                           _t3ster_power(pwr), device or f"T3Ster record {raw.stem}",
                           {"format": "t3ster", "file": raw.name, "pwr": pwr.name,
                            "tco": tco.name, "lsb_v": lsb, "uref_v": uref,
                            "dropped_before_switch": int((~after).sum())})
