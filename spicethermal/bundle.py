"""Measurement bundles (``spicethermal-bundle/2``, ``docs/bundle-format.md``), read and written.

A bundle is a directory with ``bundle.json`` and CSV files (a header row, SI units in the
column names, ``#`` comments allowed). :class:`Bundle` is its immutable in-memory form; each
section is one table: :class:`CalibrationTable`, :class:`CoolingTable`, :class:`PwmTable`,
:class:`ZthTable`. Every problem found on reading (or on building one in memory) raises
:class:`~spicethermal.errors.DataFormatError` naming the file, the row (the line number in the
file, the header being line 1 of a file without comments) and the column, or the key of
``bundle.json``.

>>> import tempfile, pathlib
>>> b = Bundle(device="diode", reference="case", ambient_c=25.0,
...            cooling=(CoolingTable(t_s=[1e-4, 1e-3], tj_c=[38.0, 36.5], power_w=10.0,
...                                  tj_steady_c=40.1, tref_steady_c=25.0),))
>>> path = b.write(pathlib.Path(tempfile.mkdtemp()) / "run1")
>>> Bundle.read(path).cooling[0].tj_c.tolist()
[38.0, 36.5]
"""

from __future__ import annotations

import math
import os
import re
import shutil
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .calibration import KFactor
from .errors import DataFormatError, where
from .files import (
    clean_leftovers,
    dumps_json,
    link_tree,
    locked,
    read_json,
    read_text,
    replace_dir,
    temp_dir_for,
)

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import ArrayLike, NDArray

    from .calibration import Calibration, Converter

FORMAT = "spicethermal-bundle/2"
#: Versions read; a bundle is written with the lowest one that holds it (a /1 reader still
#: reads every bundle whose calibration is a table). /2 adds calibration kinds.
FORMATS = ("spicethermal-bundle/1", FORMAT)
#: Calibration kinds of ``bundle.json`` (``docs/bundle-format.md``).
CALIBRATION_KINDS = ("table", "k-factor", "polynomial")
MANIFEST = "bundle.json"
ABSOLUTE_ZERO_C = -273.15
#: Hottest plausible reading (degC): a reading above it is a unit or file error, not a device.
MAX_TEMPERATURE_C = 2000.0

#: Known columns: name -> (family prefix used to spot a wrong unit, what it means).
COLUMNS: dict[str, tuple[str, str]] = {
    "t_s": ("t", "time in s"),
    "tj_c": ("tj", "junction temperature in degC"),
    "tref_c": ("tref", "reference temperature in degC"),
    "temp_c": ("temp", "temperature in degC"),
    "v_tsp_v": ("v_tsp", "TSP voltage in V"),
    "freq_hz": ("freq", "frequency in Hz"),
    "duty": ("duty", "duty cycle, 0..1"),
    "power_w": ("power", "power in W"),
    "zth_k_per_w": ("zth", "thermal impedance in K/W"),
    "r": ("r", "normalized thermal impedance Zth/Rth"),
    "r_k_per_w": ("r", "stage resistance in K/W"),
    "tau_s": ("tau", "time constant in s"),
    "c_j_per_k": ("c", "capacitance in J/K"),
}

#: Unit suffixes that mark a column as a known one in a foreign unit (``t_ms`` for ``t_s``).
_UNITS = {"s", "ms", "us", "ns", "min", "h", "hr", "c", "degc", "k", "f", "degf", "v", "mv",
          "uv", "hz", "khz", "mhz", "w", "mw", "kw", "uw", "k_per_w", "c_per_w", "k_per_mw",
          "degc_per_w", "pct", "percent", "j_per_k", "mj_per_k", "ws_per_k"}

_NUMBER = re.compile(r"^[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?$")


# --------------------------------------------------------------------------------------------
# CSV tables
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class Columns:
    """Columns of one CSV file: ``data[name]`` (float arrays) and the file row of each value."""

    file: str
    data: Mapping[str, NDArray]
    rows: NDArray

    def __getitem__(self, name: str) -> NDArray:
        return self.data[name]

    def get(self, name: str) -> NDArray | None:
        return self.data.get(name)

    def __contains__(self, name: object) -> bool:
        return name in self.data


def _frozen(values: ArrayLike) -> NDArray:
    arr = np.array(values, dtype=float).ravel()
    arr.setflags(write=False)
    return arr


def read_columns(path: str | os.PathLike, required: Sequence[str | tuple[str, ...]] = (),
                 optional: Sequence[str] = (), *, label: str | None = None,
                 root: str | os.PathLike | None = None) -> Columns:
    """Read a CSV table with a header row, SI units in column names, ``#`` comments allowed.

    Parameters
    ----------
    path : path of the file.
    required : column names that must be present; a tuple means "one of these".
    optional : column names read when present. Other columns are ignored, unless they look
        like a known column in another unit (``t_ms`` for ``t_s``), which is an error.
    label : how messages name the file (default: the path as given).
    root : a directory the file must lie inside (see :func:`spicethermal.files.read_text`).

    Returns
    -------
    Columns
        The requested columns as float arrays, and the file line of each data row.

    Raises
    ------
    DataFormatError
        Empty file, missing column, wrong unit, wrong number of fields, malformed or
        non-finite number; the message names file, row (line number) and column.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "c.csv"
    >>> _ = p.write_text("# calibration\\ntemp_c,v_tsp_v\\n25,0.60\\n50,0.55\\n")
    >>> cols = read_columns(p, ["temp_c", "v_tsp_v"])
    >>> cols["v_tsp_v"].tolist(), cols.rows.tolist()
    ([0.6, 0.55], [3, 4])
    """
    path = Path(path)
    name = label if label is not None else str(path)
    return parse_columns(read_text(path, name, "CSV file", root=root), required, optional,
                         label=name)


def parse_columns(text: str, required: Sequence[str | tuple[str, ...]] = (),
                  optional: Sequence[str] = (), *, label: str = "<text>") -> Columns:
    """Parse CSV ``text`` as :func:`read_columns` does (``label`` names it in messages)."""
    header: list[str] | None = None
    header_line = 0
    records: list[tuple[int, list[str]]] = []
    lines = text.splitlines()
    fast = None
    for lineno, raw in enumerate(lines, start=1):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        fields = [f.strip() for f in line.split(",")]
        if header is None:
            header, header_line = fields, lineno
            fast = _parse_numeric(lines[lineno:], len(header))
            if fast is not None:
                break
        else:
            records.append((lineno, fields))
    if header is None:
        raise DataFormatError(f"{where(label)}file is empty (no header row)")
    for i, col in enumerate(header):
        if not col:
            raise DataFormatError(f"{where(label, header_line)}column {i + 1} has no name")
        if _NUMBER.match(col):
            raise DataFormatError(f"{where(label, header_line)}the first row must be a header "
                                  f"with column names, found the number {col}")
    seen: set[str] = set()
    for col in header:
        if col in seen:
            raise DataFormatError(f"{where(label, header_line, col)}column appears twice")
        seen.add(col)

    wanted: list[str] = []
    for req in required:
        options = (req,) if isinstance(req, str) else tuple(req)
        present = [o for o in options if o in header]
        if not present:
            _missing(label, header_line, header, options)
        wanted.extend(present)
    wanted.extend(o for o in optional if o in header and o not in wanted)
    # a known column in a foreign unit is an error even where it is optional
    for opt in optional:
        if opt not in header:
            _check_units(label, header_line, header, opt)
    index = {col: header.index(col) for col in wanted}
    if fast is not None:  # every row a line of finite numbers: no per-field checks needed
        rows = np.arange(header_line + 1, header_line + 1 + len(fast))
        rows.setflags(write=False)
        return Columns(label, {c: _frozen(fast[:, j]) for c, j in index.items()}, rows)
    if not records:
        raise DataFormatError(f"{where(label)}no data rows after the header")

    values = {col: np.empty(len(records)) for col in wanted}
    rows = np.empty(len(records), dtype=int)
    for k, (lineno, fields) in enumerate(records):
        if len(fields) != len(header):
            raise DataFormatError(f"{where(label, lineno)}{len(fields)} fields, the header has "
                                  f"{len(header)}")
        rows[k] = lineno
        for col, j in index.items():
            values[col][k] = _number(fields[j], label, lineno, col)
    rows.setflags(write=False)
    return Columns(label, {c: _frozen(v) for c, v in values.items()}, rows)


def _parse_numeric(lines: Sequence[str], width: int) -> NDArray | None:
    """The data rows as a float array in one vectorised pass (numpy's C parser), or None when
    a row needs the per-field path with its messages: a comment, a blank line, a field that is
    not a finite number, a wrong field count, or a small table (quick either way)."""
    if len(lines) < 1000 or any("#" in line for line in lines):
        return None
    try:
        arr = np.loadtxt(lines, delimiter=",", dtype=float, ndmin=2)
    except ValueError:
        return None
    if arr.shape != (len(lines), width) or not np.all(np.isfinite(arr)):
        return None
    return arr


def parse_number(text: str, file: str, row: int, column: str) -> float:
    """One CSV field as a finite float; the message names file, row and column.

    >>> parse_number("1e-3", "a.csv", 2, "t_s")
    0.001
    """
    if not text:
        raise DataFormatError(f"{where(file, row, column)}empty field, expected a number")
    if not _NUMBER.match(text):
        if text.lower().lstrip("+-") in ("nan", "inf", "infinity"):
            raise DataFormatError(f"{where(file, row, column)}{text} is not a finite number")
        raise DataFormatError(f"{where(file, row, column)}malformed number {text!r}")
    value = float(text)
    if not math.isfinite(value):
        raise DataFormatError(f"{where(file, row, column)}{text} is not a finite number")
    return value


_number = parse_number  # the name the readers here use


def _check_units(file: str, header_line: int, header: Sequence[str], expected: str) -> None:
    family = COLUMNS.get(expected, (expected, ""))[0]
    for col in header:
        if (col != expected and col not in COLUMNS and col.startswith(family + "_")
                and col[len(family) + 1:].lower() in _UNITS):
            meaning = COLUMNS.get(expected, ("", expected))[1]
            raise DataFormatError(
                f"{where(file, header_line, col)}wrong unit: the bundle format wants SI units "
                f"in column names, here {expected} ({meaning})")


def _missing(file: str, header_line: int, header: Sequence[str], options: Sequence[str]) -> None:
    for opt in options:
        _check_units(file, header_line, header, opt)
    wanted = " or ".join(options)
    raise DataFormatError(f"{where(file, header_line)}missing column {wanted} "
                          f"(found: {', '.join(header)})")


def format_columns(columns: Mapping[str, ArrayLike], comments: Iterable[str] = ()) -> str:
    """CSV text with a header row; floats written with full (round-trip) precision.

    >>> print(format_columns({"t_s": [0.001, 0.01], "tj_c": [30.5, 29.0]}), end="")
    t_s,tj_c
    0.001,30.5
    0.01,29.0
    """
    names = list(columns)
    arrays = [np.asarray(columns[n], dtype=float).ravel() for n in names]
    lengths = {a.size for a in arrays}
    if len(lengths) > 1:
        raise DataFormatError(f"columns {', '.join(names)} differ in length")
    lines = [f"# {c}" for c in comments]
    lines.append(",".join(names))
    lines.extend(",".join(repr(float(a[i])) for a in arrays) for i in range(arrays[0].size))
    return "\n".join(lines) + "\n"


def manifest_files(path: str | os.PathLike) -> set[str]:
    """Names of the data files that the ``bundle.json`` of directory ``path`` lists (empty
    when there is none or it cannot be parsed: then nothing counts as replaceable).

    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> _ = (d / MANIFEST).write_text('{"cooling": [{"file": "c1.csv"}], "pwm": {"file": 3}}')
    >>> manifest_files(d)
    {'c1.csv'}
    """
    try:
        doc = read_json(Path(path) / MANIFEST, root=path)
    except DataFormatError:
        return set()
    names: set[str] = set()
    if isinstance(doc, dict):
        for key in ("calibration", "cooling", "pwm", "zth"):
            entries = doc.get(key)
            for entry in entries if isinstance(entries, list) else [entries]:
                if isinstance(entry, dict) and isinstance(entry.get("file"), str):
                    names.add(entry["file"])
    return names


# --------------------------------------------------------------------------------------------
# checks shared by the tables (they name file, row and column)
# --------------------------------------------------------------------------------------------
def _rows_for(n: int, rows: ArrayLike | None) -> NDArray:
    if rows is None:
        return np.arange(1, n + 1)  # arrays in memory: row k is the k-th value
    return np.asarray(rows, dtype=int)


def _column(name: str, values: ArrayLike | None, file: str, rows: NDArray | None,
            n: int | None = None) -> NDArray | None:
    if values is None:
        return None
    try:
        arr = np.array(values, dtype=float).ravel()
    except (TypeError, ValueError):
        raise DataFormatError(f"{where(file, None, name)}values must be numbers") from None
    if n is not None and arr.size != n:
        raise DataFormatError(f"{where(file, None, name)}{arr.size} values, expected {n}")
    if arr.size == 0:
        raise DataFormatError(f"{where(file, None, name)}no data rows")
    rr = _rows_for(arr.size, rows)
    bad = np.flatnonzero(~np.isfinite(arr))
    if bad.size:
        i = bad[0]
        raise DataFormatError(f"{where(file, int(rr[i]), name)}{arr[i]} is not a finite number")
    arr.setflags(write=False)
    return arr


def check_times(t_s: NDArray, file: str, rows: ArrayLike | None = None,
                column: str = "t_s") -> None:
    """Times must be >= 0 and strictly increasing; the message names the offending row."""
    rr = _rows_for(t_s.size, rows)
    neg = np.flatnonzero(t_s < 0)
    if neg.size:
        i = neg[0]
        raise DataFormatError(f"{where(file, int(rr[i]), column)}negative time {float(t_s[i])!r}")
    d = np.diff(t_s)
    dup = np.flatnonzero(d == 0)
    back = np.flatnonzero(d < 0)
    first = min(dup[0] if dup.size else t_s.size, back[0] if back.size else t_s.size)
    if first < t_s.size:
        i = first + 1
        if d[first] == 0:
            raise DataFormatError(f"{where(file, int(rr[i]), column)}duplicate time "
                                  f"{float(t_s[i])!r} (also on row {int(rr[i - 1])})")
        raise DataFormatError(f"{where(file, int(rr[i]), column)}time goes backwards: "
                              f"{float(t_s[i])!r} after {float(t_s[i - 1])!r} (times must "
                              f"increase)")


def check_temperatures(values: NDArray, file: str, rows: ArrayLike | None, column: str) -> None:
    """Temperatures in degC must lie between absolute zero and :data:`MAX_TEMPERATURE_C`."""
    rr = _rows_for(values.size, rows)
    bad = np.flatnonzero(values < ABSOLUTE_ZERO_C)
    if bad.size:
        i = bad[0]
        raise DataFormatError(f"{where(file, int(rr[i]), column)}{float(values[i])!r} degC "
                              f"is below absolute zero")
    hot = np.flatnonzero(values > MAX_TEMPERATURE_C)
    if hot.size:
        i = hot[0]
        raise DataFormatError(f"{where(file, int(rr[i]), column)}{float(values[i])!r} degC is "
                              f"above {MAX_TEMPERATURE_C:g} degC, hotter than any device "
                              f"survives (silicon melts at 1414 degC)")


def _check_range(values: NDArray, file: str, rows: ArrayLike | None, column: str, *,
                 low: float = -math.inf, high: float = math.inf, low_open: bool = False,
                 what: str = "") -> None:
    rr = _rows_for(values.size, rows)
    bad = (values <= low if low_open else values < low) | (values > high)
    idx = np.flatnonzero(bad)
    if idx.size:
        i = idx[0]
        raise DataFormatError(f"{where(file, int(rr[i]), column)}{float(values[i])!r}: {what}")


def _scalar(value: Any, key: str, *, positive: bool = False, temperature: bool = False,
            nonnegative: bool = False, optional: bool = True) -> float | None:
    if value is None:
        if optional:
            return None
        raise DataFormatError(f"{key}: missing")
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
        raise DataFormatError(f"{key}: {value!r} is not a number")
    v = float(value)
    if not math.isfinite(v):
        raise DataFormatError(f"{key}: {value!r} is not a finite number")
    if positive and v <= 0:
        raise DataFormatError(f"{key}: {v!r} must be > 0")
    if nonnegative and v < 0:
        raise DataFormatError(f"{key}: {v!r} must be >= 0")
    if temperature and v < ABSOLUTE_ZERO_C:
        raise DataFormatError(f"{key}: {v!r} degC is below absolute zero")
    if temperature and v > MAX_TEMPERATURE_C:
        raise DataFormatError(f"{key}: {v!r} degC is above {MAX_TEMPERATURE_C:g} degC, hotter "
                              f"than any device survives")
    return v


def _set(obj: object, **values: Any) -> None:
    for k, v in values.items():
        object.__setattr__(obj, k, v)


# --------------------------------------------------------------------------------------------
# the sections
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class CalibrationTable:
    """TSP calibration points: ``temp_c`` (degC) and ``v_tsp_v`` (V), one row per point.

    Kind ``table`` (a polynomial is fitted here, :meth:`fit`) or, with ``coefficients`` (V per
    degC^k, ascending), kind ``polynomial``: a fit made elsewhere, the points kept for its
    residuals. The other kind, a K-factor, is :class:`~spicethermal.calibration.KFactor`.
    """

    temp_c: NDArray
    v_tsp_v: NDArray
    file: str | None = None
    rows: NDArray | None = field(default=None, repr=False)
    extra: Mapping[str, Any] = field(default_factory=dict, repr=False)
    coefficients: tuple[float, ...] | None = None

    def __post_init__(self) -> None:
        f = self.file or "calibration.csv"
        t = _column("temp_c", self.temp_c, f, self.rows)
        v = _column("v_tsp_v", self.v_tsp_v, f, self.rows, t.size)
        check_temperatures(t, f, self.rows, "temp_c")
        if t.size < 2:
            raise DataFormatError(f"{where(f)}a calibration needs at least 2 points")
        _set(self, temp_c=t, v_tsp_v=v)
        if self.coefficients is not None:
            _set(self, coefficients=self.fit().coefficients)

    @property
    def kind(self) -> str:
        """``"table"`` or ``"polynomial"`` (``docs/bundle-format.md``)."""
        return "table" if self.coefficients is None else "polynomial"

    def columns(self) -> dict[str, NDArray]:
        return {"temp_c": self.temp_c, "v_tsp_v": self.v_tsp_v}

    def manifest(self) -> dict[str, Any]:
        if self.coefficients is None:
            return {}
        return {"kind": self.kind, "coefficients_v": list(self.coefficients)}

    def fit(self, degree: int | str = "auto") -> Calibration:
        """The :class:`~spicethermal.calibration.Calibration`: fitted to the points
        (``"auto"``: linear unless its linearity test fails, then quadratic), or the given
        polynomial (``degree`` is then ignored)."""
        from .calibration import Calibration

        if self.coefficients is not None:
            return Calibration.from_coefficients(self.coefficients, self.temp_c, self.v_tsp_v)
        return Calibration.fit(self.temp_c, self.v_tsp_v, degree=degree)


@dataclass(frozen=True, eq=False)
class CoolingTable:
    """One cooling curve: ``t_s`` from the instant power is removed, ``tj_c`` or raw
    ``v_tsp_v``, optional ``tref_c``; ``power_w`` before the cut and the steady state just
    before it (``tj_steady_c``, ``tref_steady_c``, either may be unknown)."""

    t_s: NDArray
    power_w: float
    tj_c: NDArray | None = None
    v_tsp_v: NDArray | None = None
    tref_c: NDArray | None = None
    tj_steady_c: float | None = None
    tref_steady_c: float | None = None
    file: str | None = None
    rows: NDArray | None = field(default=None, repr=False)
    extra: Mapping[str, Any] = field(default_factory=dict, repr=False)

    def __post_init__(self) -> None:
        f = self.file or "cooling.csv"
        t = _column("t_s", self.t_s, f, self.rows)
        check_times(t, f, self.rows)
        tj = _column("tj_c", self.tj_c, f, self.rows, t.size)
        v = _column("v_tsp_v", self.v_tsp_v, f, self.rows, t.size)
        if tj is None and v is None:
            raise DataFormatError(f"{where(f)}a cooling curve needs column tj_c or v_tsp_v")
        if tj is not None:
            check_temperatures(tj, f, self.rows, "tj_c")
        tref = _column("tref_c", self.tref_c, f, self.rows, t.size)
        if tref is not None:
            check_temperatures(tref, f, self.rows, "tref_c")
        _set(self, t_s=t, tj_c=tj, v_tsp_v=v, tref_c=tref,
             power_w=_scalar(self.power_w, f"{f}: power_w", positive=True, optional=False),
             tj_steady_c=_scalar(self.tj_steady_c, f"{f}: tj_steady_c", temperature=True),
             tref_steady_c=_scalar(self.tref_steady_c, f"{f}: tref_steady_c",
                                   temperature=True))

    def columns(self) -> dict[str, NDArray]:
        cols = {"t_s": self.t_s}
        for name in ("tj_c", "v_tsp_v", "tref_c"):
            if getattr(self, name) is not None:
                cols[name] = getattr(self, name)
        return cols

    def manifest(self) -> dict[str, Any]:
        entry: dict[str, Any] = {"power_w": self.power_w}
        if self.tj_steady_c is not None:
            entry["tj_steady_c"] = self.tj_steady_c
        if self.tref_steady_c is not None:
            entry["tref_steady_c"] = self.tref_steady_c
        return entry


@dataclass(frozen=True, eq=False)
class PwmTable:
    """PWM readings in the periodic steady state: ``freq_hz``, ``duty``, ``tj_c`` (what the
    bench reads at the end of the sample window), optional ``tref_c`` and per-row
    ``row_power_w`` (column ``power_w``, overrides the section's ``power_w``)."""

    freq_hz: NDArray
    duty: NDArray
    tj_c: NDArray
    power_w: float | None = None
    tref_c: NDArray | None = None
    row_power_w: NDArray | None = None
    sample_window_s: float = 0.0
    file: str | None = None
    rows: NDArray | None = field(default=None, repr=False)
    extra: Mapping[str, Any] = field(default_factory=dict, repr=False)

    def __post_init__(self) -> None:
        f = self.file or "pwm.csv"
        fr = _column("freq_hz", self.freq_hz, f, self.rows)
        n = fr.size
        _check_range(fr, f, self.rows, "freq_hz", low=0, low_open=True, what="must be > 0")
        d = _column("duty", self.duty, f, self.rows, n)
        _check_range(d, f, self.rows, "duty", low=0, high=1, what="must lie in [0, 1]")
        tj = _column("tj_c", self.tj_c, f, self.rows, n)
        check_temperatures(tj, f, self.rows, "tj_c")
        tref = _column("tref_c", self.tref_c, f, self.rows, n)
        if tref is not None:
            check_temperatures(tref, f, self.rows, "tref_c")
        pw = _column("power_w", self.row_power_w, f, self.rows, n)
        if pw is not None:
            _check_range(pw, f, self.rows, "power_w", low=0, low_open=True, what="must be > 0")
        power = _scalar(self.power_w, f"{f}: power_w", positive=True)
        if power is None and pw is None:
            raise DataFormatError(f"{where(f)}no power: give the section's power_w or a "
                                  f"power_w column")
        window = _scalar(self.sample_window_s, f"{f}: sample_window_s", nonnegative=True)
        _set(self, freq_hz=fr, duty=d, tj_c=tj, tref_c=tref, row_power_w=pw, power_w=power,
             sample_window_s=0.0 if window is None else window)

    @property
    def powers_w(self) -> NDArray:
        """Power of every row: the row's own ``power_w`` or else the section's."""
        if self.row_power_w is not None:
            return self.row_power_w
        return _frozen(np.full(self.freq_hz.size, self.power_w))

    def columns(self) -> dict[str, NDArray]:
        cols = {"freq_hz": self.freq_hz, "duty": self.duty, "tj_c": self.tj_c}
        if self.tref_c is not None:
            cols["tref_c"] = self.tref_c
        if self.row_power_w is not None:
            cols["power_w"] = self.row_power_w
        return cols

    def manifest(self) -> dict[str, Any]:
        entry: dict[str, Any] = {}
        if self.power_w is not None:
            entry["power_w"] = self.power_w
        entry["sample_window_s"] = self.sample_window_s
        return entry


@dataclass(frozen=True, eq=False)
class ZthTable:
    """A thermal impedance curve: ``t_s`` and ``zth_k_per_w`` (absolute) or ``r``
    (normalized, Zth/Rth, then ``rth_k_per_w`` is needed for absolute values)."""

    t_s: NDArray
    zth_k_per_w: NDArray | None = None
    r: NDArray | None = None
    rth_k_per_w: float | None = None
    file: str | None = None
    rows: NDArray | None = field(default=None, repr=False)
    extra: Mapping[str, Any] = field(default_factory=dict, repr=False)

    def __post_init__(self) -> None:
        f = self.file or "zth.csv"
        t = _column("t_s", self.t_s, f, self.rows)
        check_times(t, f, self.rows)
        z = _column("zth_k_per_w", self.zth_k_per_w, f, self.rows, t.size)
        r = _column("r", self.r, f, self.rows, t.size)
        if (z is None) == (r is None):
            raise DataFormatError(f"{where(f)}give exactly one of the columns zth_k_per_w "
                                  f"(absolute) or r (normalized)")
        _set(self, t_s=t, zth_k_per_w=z, r=r,
             rth_k_per_w=_scalar(self.rth_k_per_w, f"{f}: rth_k_per_w", positive=True))

    @property
    def normalized(self) -> bool:
        """True when the file holds r(t) rather than Zth(t)."""
        return self.r is not None

    def columns(self) -> dict[str, NDArray]:
        key = "r" if self.normalized else "zth_k_per_w"
        return {"t_s": self.t_s, key: self.r if self.normalized else self.zth_k_per_w}

    def manifest(self) -> dict[str, Any]:
        entry: dict[str, Any] = {"normalized": self.normalized}
        if self.rth_k_per_w is not None:
            entry["rth_k_per_w"] = self.rth_k_per_w
        return entry


# --------------------------------------------------------------------------------------------
# the bundle
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class Bundle:
    """A measurement bundle (``spicethermal-bundle/2``, or /1); every section is optional.

    Build it from tables (as the bench does), read it with :meth:`read`, write it with
    :meth:`write`. Unknown keys of ``bundle.json`` are kept in ``extra`` (and in each
    table's ``extra``) and written back.

    >>> b = Bundle(calibration=CalibrationTable([25, 75], [0.60, 0.50]))
    >>> round(b.calibration_fit().k_factor_mv_per_k, 6)
    -2.0
    """

    device: str = ""
    reference: str = "ambient"
    ambient_c: float | None = None
    calibration: CalibrationTable | KFactor | None = None
    cooling: tuple[CoolingTable, ...] = ()
    pwm: PwmTable | None = None
    zth: tuple[ZthTable, ...] = ()
    extra: Mapping[str, Any] = field(default_factory=dict, repr=False)
    source: str | None = field(default=None, compare=False)

    def __post_init__(self) -> None:
        if not isinstance(self.device, str):
            raise DataFormatError(f"{MANIFEST}, key device: {self.device!r} is not a string")
        if self.reference not in ("ambient", "case"):
            raise DataFormatError(f"{MANIFEST}, key reference: {self.reference!r} must be "
                                  f"'ambient' or 'case'")
        ambient = _scalar(self.ambient_c, f"{MANIFEST}, key ambient_c", temperature=True)
        cooling = tuple(self.cooling)
        zth = tuple(self.zth)
        for i, c in enumerate(cooling):
            if not isinstance(c, CoolingTable):
                raise DataFormatError(f"{MANIFEST}, key cooling[{i}]: not a CoolingTable")
            if c.tj_c is None and self.calibration is None:
                raise DataFormatError(f"{MANIFEST}, key cooling[{i}]: {c.file or 'the curve'} "
                                      f"gives v_tsp_v but the bundle has no calibration")
        for i, z in enumerate(zth):
            if not isinstance(z, ZthTable):
                raise DataFormatError(f"{MANIFEST}, key zth[{i}]: not a ZthTable")
        _set(self, ambient_c=ambient, cooling=cooling, zth=zth, extra=dict(self.extra))
        names = [n for n, _ in self._named_tables()]
        dups = {n for n in names if names.count(n) > 1}
        if dups:
            raise DataFormatError(f"{MANIFEST}: two sections use the file {sorted(dups)[0]}")

    # -- helpers for users of the bundle -------------------------------------------------
    def calibration_fit(self, degree: int | str = "auto") -> Converter:
        """The TSP converter of any calibration kind: the fitted or given polynomial of a
        table, or the K-factor itself (raises if the bundle has none)."""
        if self.calibration is None:
            raise DataFormatError(f"{self._where()}the bundle has no calibration")
        if isinstance(self.calibration, KFactor):
            return self.calibration
        return self.calibration.fit(degree)

    def cooling_tj_c(self, index: int = 0) -> NDArray:
        """Junction temperature of cooling curve ``index`` in degC (``v_tsp_v`` converted
        through the calibration when the curve has no ``tj_c``)."""
        c = self.cooling[index]
        if c.tj_c is not None:
            return c.tj_c
        return _frozen(self.calibration_fit().temperature(c.v_tsp_v))

    def cooling_reference_c(self, index: int = 0) -> tuple[NDArray | None, float | None]:
        """``(tref_c, tref_steady_c)`` of cooling curve ``index`` after the DESIGN rule:
        without ``tref_c`` the reference is ``tref_steady_c``, else ``ambient_c``."""
        c = self.cooling[index]
        steady = c.tref_steady_c
        if steady is None and c.tref_c is None:
            steady = self.ambient_c
        return c.tref_c, steady

    def _where(self) -> str:
        return f"{self.source}: " if self.source else ""

    def _named_tables(self) -> list[tuple[str, Any]]:
        out: list[tuple[str, Any]] = []
        if isinstance(self.calibration, CalibrationTable):
            out.append((self.calibration.file or "calibration.csv", self.calibration))
        for i, c in enumerate(self.cooling, start=1):
            out.append((c.file or f"cooling_{i}.csv", c))
        if self.pwm is not None:
            out.append((self.pwm.file or "pwm.csv", self.pwm))
        for i, z in enumerate(self.zth, start=1):
            out.append((z.file or f"zth_{i}.csv", z))
        return out

    # -- reading -------------------------------------------------------------------------
    @classmethod
    def read(cls, path: str | os.PathLike,
             calibration: CalibrationTable | KFactor | None = None) -> Bundle:
        """Read and validate the bundle directory ``path`` (or its ``bundle.json``).

        ``calibration`` replaces the bundle's own (or supplies a missing one). Raises
        :class:`DataFormatError` naming the file, row and column (or the key of
        ``bundle.json``) of the first problem.
        """
        path = Path(path)
        if path.is_file() and path.name == MANIFEST:
            path = path.parent
        if not path.is_dir():
            raise DataFormatError(f"{path}: not a bundle directory (no such directory)")
        manifest = path / MANIFEST
        label = str(manifest)
        if not manifest.exists():
            raise DataFormatError(f"{path}: not a bundle (no {MANIFEST})")
        doc = read_json(manifest, root=path)
        if not isinstance(doc, dict):
            raise DataFormatError(f"{label}: must hold a JSON object")
        fmt = doc.get("format")
        if fmt not in FORMATS:
            raise DataFormatError(f"{label}, key format: {fmt!r}, expected "
                                  f"{' or '.join(map(repr, FORMATS))}")

        def section(key: str) -> dict:
            value = doc.get(key)
            if not isinstance(value, dict):
                raise DataFormatError(f"{label}, key {key}: must be an object")
            return value

        def sections(key: str) -> list[dict]:
            value = doc.get(key)
            if isinstance(value, dict):
                value = [value]
            if not isinstance(value, list):
                raise DataFormatError(f"{label}, key {key}: must be a list of objects")
            for i, v in enumerate(value):
                if not isinstance(v, dict):
                    raise DataFormatError(f"{label}, key {key}[{i}]: must be an object")
            return value

        def table(entry: dict, key: str, required, optional=()) -> tuple[str, Columns]:
            name = entry.get("file")
            if not isinstance(name, str) or not name:
                raise DataFormatError(f"{label}, key {key}.file: missing or not a file name")
            target = (path / name)
            if Path(name).is_absolute() or ".." in Path(name).parts:
                raise DataFormatError(f"{label}, key {key}.file: {name!r} must be a file "
                                      f"inside the bundle")
            return name, read_columns(target, required, optional, label=str(target),
                                      root=path)

        def num(entry: dict, key: str, name: str, **kw) -> float | None:
            return _scalar(entry.get(name), f"{label}, key {key}.{name}", **kw)

        def known(entry: dict, keys: Iterable[str]) -> dict:
            return {k: v for k, v in entry.items() if k not in set(keys) | {"file"}}

        def wrap(make, fname: str):
            try:
                return make()
            except DataFormatError as exc:  # name the file on disk, not just its basename
                text = str(exc)
                if text.startswith(fname) and not text.startswith(str(path / fname)):
                    text = str(path / fname) + text[len(fname):]
                raise DataFormatError(text) from None

        if calibration is None and doc.get("calibration") is not None:
            calibration = _read_calibration(section("calibration"), fmt, label, table, wrap,
                                             known)

        cooling = []
        if doc.get("cooling") is not None:
            for i, entry in enumerate(sections("cooling")):
                key = f"cooling[{i}]"
                name, cols = table(entry, key, ["t_s", ("tj_c", "v_tsp_v")], ["tref_c"])
                power = num(entry, key, "power_w", positive=True, optional=False)
                tjs = num(entry, key, "tj_steady_c", temperature=True)
                trs = num(entry, key, "tref_steady_c", temperature=True)
                if "v_tsp_v" in cols and "tj_c" not in cols and calibration is None:
                    raise DataFormatError(f"{label}, key {key}: {name} gives v_tsp_v but the "
                                          f"bundle has no calibration to convert it (add one, "
                                          f"docs/bundle-format.md, or pass --calibration CSV "
                                          f"or --k-factor MV_PER_K with --tref DEGC)")
                cooling.append(wrap(lambda cols=cols, name=name, entry=entry, power=power,
                                    tjs=tjs, trs=trs: CoolingTable(
                    t_s=cols["t_s"], power_w=power, tj_c=cols.get("tj_c"),
                    v_tsp_v=None if "tj_c" in cols else cols.get("v_tsp_v"),
                    tref_c=cols.get("tref_c"), tj_steady_c=tjs, tref_steady_c=trs, file=name,
                    rows=cols.rows,
                    extra=known(entry, ("power_w", "tj_steady_c", "tref_steady_c"))), name))

        pwm = None
        if doc.get("pwm") is not None:
            entry = section("pwm")
            name, cols = table(entry, "pwm", ["freq_hz", "duty", "tj_c"], ["tref_c", "power_w"])
            power = num(entry, "pwm", "power_w", positive=True)
            window = num(entry, "pwm", "sample_window_s", nonnegative=True)
            if power is None and "power_w" not in cols:
                raise DataFormatError(f"{label}, key pwm.power_w: missing, and {name} has no "
                                      f"power_w column")
            pwm = wrap(lambda: PwmTable(
                freq_hz=cols["freq_hz"], duty=cols["duty"], tj_c=cols["tj_c"], power_w=power,
                tref_c=cols.get("tref_c"), row_power_w=cols.get("power_w"),
                sample_window_s=0.0 if window is None else window, file=name, rows=cols.rows,
                extra=known(entry, ("power_w", "sample_window_s"))), name)

        zth = []
        if doc.get("zth") is not None:
            for i, entry in enumerate(sections("zth")):
                key = f"zth[{i}]"
                name, cols = table(entry, key, ["t_s", ("zth_k_per_w", "r")])
                rth = num(entry, key, "rth_k_per_w", positive=True)
                norm = entry.get("normalized")
                if norm is not None and not isinstance(norm, bool):
                    raise DataFormatError(f"{label}, key {key}.normalized: {norm!r} must be "
                                          f"true or false")
                if "zth_k_per_w" in cols and "r" in cols:
                    raise DataFormatError(f"{where(str(path / name))}has both zth_k_per_w and "
                                          f"r; keep one")
                has_r = "r" in cols
                if norm is not None and norm != has_r:
                    col = "r" if norm else "zth_k_per_w"
                    raise DataFormatError(f"{label}, key {key}.normalized: {norm} but {name} "
                                          f"has no column {col}")
                zth.append(wrap(lambda cols=cols, name=name, entry=entry, rth=rth: ZthTable(
                    t_s=cols["t_s"], zth_k_per_w=cols.get("zth_k_per_w"), r=cols.get("r"),
                    rth_k_per_w=rth, file=name, rows=cols.rows,
                    extra=known(entry, ("rth_k_per_w", "normalized"))), name))

        device = doc.get("device", "")
        reference = doc.get("reference", "ambient")
        ambient = num(doc, "", "ambient_c", temperature=True) if "ambient_c" in doc else None
        extra = {k: v for k, v in doc.items() if k not in (
            "format", "device", "reference", "ambient_c", "calibration", "cooling", "pwm",
            "zth")}
        return cls(device=device, reference=reference, ambient_c=ambient,
                   calibration=calibration, cooling=tuple(cooling), pwm=pwm, zth=tuple(zth),
                   extra=extra, source=str(path))

    # -- writing -------------------------------------------------------------------------
    def manifest(self) -> dict[str, Any]:
        """The ``bundle.json`` document (file names as :meth:`write` uses them)."""
        v1 = isinstance(self.calibration, CalibrationTable | None) and (
            self.calibration is None or self.calibration.kind == "table")
        doc: dict[str, Any] = {"format": FORMATS[0] if v1 else FORMAT, "device": self.device,
                               "reference": self.reference}
        if self.ambient_c is not None:
            doc["ambient_c"] = self.ambient_c
        named = dict((id(t), n) for n, t in self._named_tables())
        if isinstance(self.calibration, KFactor):
            doc["calibration"] = self.calibration.manifest()
        elif self.calibration is not None:
            doc["calibration"] = {"file": named[id(self.calibration)],
                                  **self.calibration.manifest(), **self.calibration.extra}
        if self.cooling:
            doc["cooling"] = [{"file": named[id(c)], **c.manifest(), **c.extra}
                              for c in self.cooling]
        if self.pwm is not None:
            doc["pwm"] = {"file": named[id(self.pwm)], **self.pwm.manifest(), **self.pwm.extra}
        if self.zth:
            doc["zth"] = [{"file": named[id(z)], **z.manifest(), **z.extra} for z in self.zth]
        for k, v in self.extra.items():
            doc.setdefault(k, v)
        return doc

    def write(self, path: str | os.PathLike, *, overwrite: bool = True,
              wait: bool = False) -> Path:
        """Write the bundle to directory ``path`` atomically and return the path.

        Under the bundle's lock (:func:`spicethermal.files.locked`: another writer is a
        :class:`~spicethermal.errors.BusyError`, or is waited for with ``wait``) every file is
        written and fsynced into a new directory beside ``path``, which then replaces
        ``path`` in one step (:func:`spicethermal.files.replace_dir`): at every instant
        ``path`` holds the complete old or the complete new bundle, and leftovers of an
        interrupted write are removed by the next one. Files of the old bundle that the new
        one does not list (an operator's notes, the raw logs, a superseded data set) are
        kept (hard links): a write never deletes a file, and a data file of the new bundle
        replaces only a file that the old manifest listed. An existing bundle is
        replaced (unless ``overwrite`` is false); an existing directory that is not a bundle
        is never touched.
        """
        given = path = Path(path)
        named = self._named_tables()
        for name, _ in named:
            if Path(name).name != name or name in (MANIFEST, "", ".", ".."):
                raise DataFormatError(f"{MANIFEST}: file name {name!r} must be a plain name")
        path = Path(os.path.realpath(path))  # a link to the bundle stays a link to it
        with locked(path, wait=wait):
            clean_leftovers(path)
            keep: list[str] = []
            if path.exists():
                if not overwrite:
                    raise DataFormatError(f"{path}: exists (not overwriting)")
                if not path.is_dir() or (any(path.iterdir())
                                         and not (path / MANIFEST).exists()):
                    raise DataFormatError(f"{path}: exists and is not a bundle; not replacing "
                                          f"it")
                ours = manifest_files(path) | {MANIFEST}
                new = {n for n, _ in named} | {MANIFEST}
                entries = os.listdir(path)
                keep = sorted(n for n in entries if n not in new)  # nothing is deleted
                clash = sorted(n for n in entries if n in new and n not in ours)
                if clash:
                    raise DataFormatError(f"{path / clash[0]}: exists and is not part of the "
                                          f"bundle; not overwriting it")
            tmp = temp_dir_for(path)
            try:
                files = [(name, format_columns(tbl.columns())) for name, tbl in named]
                files.append((MANIFEST, dumps_json(self.manifest(), indent=2) + "\n"))
                for name, text in files:
                    with open(tmp / name, "w", encoding="utf-8", newline="\n") as handle:
                        handle.write(text)
                        handle.flush()
                        os.fsync(handle.fileno())
                link_tree(path, tmp, keep)
                replace_dir(tmp, path)
            except BaseException:
                shutil.rmtree(tmp, ignore_errors=True)
                raise
        return given

    def with_(self, **changes: Any) -> Bundle:
        """A copy with some fields replaced (the bundle itself is immutable)."""
        return replace(self, **changes)


def _read_calibration(entry: dict, fmt: str, label: str, table, wrap, known
                      ) -> CalibrationTable | KFactor:
    """The ``calibration`` section of ``bundle.json``, any kind (``docs/bundle-format.md``)."""
    kind = entry.get("kind", "table")
    key = f"{label}, key calibration"
    if "kind" in entry and fmt == FORMATS[0]:
        raise DataFormatError(f"{key}.kind: calibration kinds need format {FORMAT!r}")
    if kind not in CALIBRATION_KINDS:
        raise DataFormatError(f"{key}.kind: {kind!r}, expected one of "
                              f"{', '.join(CALIBRATION_KINDS)}")
    if kind == "k-factor":
        extra = sorted(set(entry) - {"kind", "k_mv_per_k", "k_v_per_k", "v_ref_v", "t_ref_c"})
        if extra:
            raise DataFormatError(f"{key}.{extra[0]}: not a key of a k-factor calibration")
        given = [k for k in ("k_mv_per_k", "k_v_per_k") if k in entry]
        if len(given) != 1:
            raise DataFormatError(f"{key}: a k-factor calibration needs exactly one of "
                                  f"k_mv_per_k or k_v_per_k")
        for name in ("v_ref_v", "t_ref_c"):
            if name not in entry:
                raise DataFormatError(f"{key}.{name}: missing (a K-factor needs the voltage at "
                                      f"a reference temperature)")
        k = _scalar(entry[given[0]], f"{key}.{given[0]}", optional=False)
        v = _scalar(entry["v_ref_v"], f"{key}.v_ref_v", optional=False)
        t = _scalar(entry["t_ref_c"], f"{key}.t_ref_c", temperature=True, optional=False)
        if k == 0:
            raise DataFormatError(f"{key}.{given[0]}: zero, the TSP does not depend on T")
        return KFactor(k * (1e-3 if given[0] == "k_mv_per_k" else 1.0), v, t, key)
    name, cols = table(entry, "calibration", ["temp_c", "v_tsp_v"])
    coefficients = None
    if kind == "polynomial":
        coefficients = entry.get("coefficients_v")
        if not isinstance(coefficients, list) or any(
                isinstance(c, bool) or not isinstance(c, int | float) for c in coefficients):
            raise DataFormatError(f"{key}.coefficients_v: a polynomial calibration needs a "
                                  f"list of numbers (V per degC^k, ascending)")
    return wrap(lambda: CalibrationTable(
        cols["temp_c"], cols["v_tsp_v"], file=name, rows=cols.rows,
        extra=known(entry, ("kind", "coefficients_v")), coefficients=coefficients), name)
