"""Importers of real thermal transients from other tools' files into a :class:`Bundle`.

* :func:`read_pyrth` — the PyRth text format (``MOSFET_dry.txt``): a ``DATA`` line, a header
  line, then two columns, time (s) and sensor voltage (V). The file holds no calibration and
  no power: pass them (the MOSFET files' calibration points are
  :data:`PYRTH_MOSFET_CALIBRATION`, shipped as ``pyrth_mosfet/calibration.csv``; PyRth's
  nominal power is 1 W). There is no default calibration: another device's would be wrong.
* :func:`read_t3ster` — the legacy export of a Simcenter T3Ster: ``.raw`` (time response
  record: ``time_us adc_count`` rows after a ``#`` header that gives the ADC step ``lsb`` (V,
  7th header line) and the offset voltage ``uref`` (V, 9th), so that
  ``V = uref + (count - 4095/2) · lsb``), ``.pwr`` (``Power=`` in its ``[power]`` section, the
  heating power step in W) and ``.tco`` (temperature/voltage calibration rows after ``#``
  comments; the 6th and 7th header lines hold the instrument's fitted line ``V = a0 + a1 T``,
  kept as a ``polynomial`` calibration with the rows as its residuals).

Both are cooling transients recorded from the trigger: leading samples taken before the
switch (PyRth: the first run of identical values; T3Ster: time 0) are dropped, the times are
kept as recorded. The reference temperature is taken as the junction temperature at the end
of the record (``tref_steady_c``, the mean of the last 5 samples): the device is assumed back
at its reference by then, so Rth is the rise recorded over the whole transient.

The calibration may be a table or polynomial (converted as it stands) or a
:class:`~spicethermal.identify.calibration.KFactor`. Given ``tref_c``, the temperature of the device
at the end of the record, any of them is re-anchored there (its slope kept, its level moved:
:func:`~spicethermal.identify.calibration.anchored`): the sensor voltage of a transient often sits
tens of mV away from the oven calibration's (another sense current, an amplifier offset), so
that the table alone puts a device at room temperature near 2 degC (the PyRth MOSFET files:
0.608 V at the end of the record, where the table reads 0.558 V at 23.4 degC).
"""

from __future__ import annotations

import os
import re
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path

import numpy as np

from ..core.errors import DataFormatError, where
from ..identify.calibration import KFactor, anchored
from .bundle import Bundle, CalibrationTable, CoolingTable, parse_number
from .files import read_text

#: Calibration points of the PyRth MOSFET files, (Tj degC, Usens V): about -2.32 mV/K.
PYRTH_MOSFET_CALIBRATION: tuple[tuple[float, float], ...] = (
    (23.4, 0.55843), (37.625, 0.52536), (51.85, 0.49232), (66.075, 0.45927), (80.3, 0.42621))

#: Samples averaged at the end of a record for the reference temperature.
END_SAMPLES = 5

T3STER_ADC_LEVELS = 4095.0


#: What the importers accept as a calibration.
CalibrationLike = CalibrationTable | KFactor | Sequence[Sequence[float]]


def _calibration_table(calibration: CalibrationLike | None, label: str
                       ) -> CalibrationTable | KFactor:
    if calibration is None:
        raise DataFormatError(f"{label}: the file holds no calibration: give one (--calibration "
                              f"CSV with temp_c, v_tsp_v, or --k-factor MV_PER_K with --ambient "
                              f"DEGC)")
    if isinstance(calibration, CalibrationTable | KFactor):
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


def _cooling_bundle(t: np.ndarray, v: np.ndarray, rows: np.ndarray, label: str,
                    calibration: CalibrationTable | KFactor, power_w: float, device: str,
                    source: dict, tref_c: float | None = None) -> Bundle:
    cal = calibration if isinstance(calibration, KFactor) else calibration.fit("auto")
    v_end = float(np.mean(v[-END_SAMPLES:]))
    if tref_c is not None:
        calibration = cal = anchored(cal, v_end, tref_c)
        source = {**source, "anchored": f"{v_end:.6g} V (end of record) = {tref_c:g} degC"}
    tref = float(cal.temperature(v_end))
    cooling = CoolingTable(t, power_w, v_tsp_v=v, tref_steady_c=tref, file=label, rows=rows,
                           extra={"tref_steady_from": f"mean of the last {END_SAMPLES} samples"})
    bundle = Bundle(device=device, reference="ambient", ambient_c=tref_c,
                    calibration=calibration, cooling=(cooling,), extra={"source": source})
    # checked above under the source's name; written as a plain file name
    return bundle.with_(cooling=(replace(cooling, file="cooling_1.csv"),), source=label)


def read_pyrth(path: str | os.PathLike, calibration: CalibrationLike | None = None,
               power_w: float = 1.0, device: str | None = None,
               tref_c: float | None = None) -> Bundle:
    """Read a PyRth transient text file (``DATA`` line, header, ``time voltage`` rows).

    Parameters
    ----------
    path : the ``.txt`` file.
    calibration : (temp_c, v_tsp_v) pairs, a :class:`CalibrationTable` or a
        :class:`~spicethermal.identify.calibration.KFactor`; required (the file has none).
    power_w : the heating power step, W (PyRth's files do not store it; 1 W nominal).
    tref_c : temperature of the device at the end of the record; re-anchors the calibration
        there (module docstring). Default: the calibration's own reading.

    Returns
    -------
    Bundle
        Calibration and one cooling curve with raw ``v_tsp_v``.

    Examples
    --------
    >>> from spicethermal.data import path
    >>> b = read_pyrth(path("pyrth_mosfet/MOSFET_dry.txt"), PYRTH_MOSFET_CALIBRATION,
    ...                tref_c=25.0)
    >>> print(b.calibration_fit())
    K-factor calibration: K = -2.324 mV/K, 0.607995 V at 25 degC
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
                            "dropped_before_switch": first, "power_w_nominal": power_w},
                           tref_c)


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


def read_t3ster(raw: str | os.PathLike, pwr: str | os.PathLike | None = None,
                tco: str | os.PathLike | None = None, device: str | None = None,
                tref_c: float | None = None) -> Bundle:
    """Read a T3Ster measurement (``.raw`` + ``.pwr`` + ``.tco``) into a bundle.

    Parameters
    ----------
    raw : the ``.raw`` time response record.
    pwr : the power file; default the ``.pwr`` beside ``raw`` with the same stem.
    tco : the calibration; default the only ``.tco`` file in that directory.
    device : a name for the bundle.
    tref_c : temperature of the device at the end of the record (re-anchors the calibration).

    Returns
    -------
    Bundle
        The ``.tco`` calibration (kind ``polynomial`` when its header holds the line) and one
        cooling curve with raw ``v_tsp_v`` at the ``.pwr`` power.

    Examples
    --------
    >>> from spicethermal.data import path
    >>> b = read_t3ster(path("pyrth_mosfet/t3ster/T25_I-m5m-I-h600m_100s.raw"))
    >>> b.calibration.kind, round(b.cooling[0].power_w, 4)
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
    return _cooling_bundle(t_us[after] * 1e-6, v, rows[after], label, _t3ster_calibration(tco),
                           _t3ster_power(pwr), device or f"T3Ster record {raw.stem}",
                           {"format": "t3ster", "file": raw.name, "pwr": pwr.name,
                            "tco": tco.name, "lsb_v": lsb, "uref_v": uref,
                            "dropped_before_switch": int((~after).sum())}, tref_c)
