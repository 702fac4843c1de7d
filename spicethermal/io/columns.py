"""CSV column files (a header row, SI units in the column names, ``#`` comments allowed) and
the checks every table of a bundle shares; every problem names the file, row and column.
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..core.errors import DataFormatError, where
from .files import (
    read_text,
)

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import ArrayLike, NDArray


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
    "i_a": ("i", "current in A"),
    "vf_v": ("vf", "forward voltage in V"),
    "t_pulse_s": ("t_pulse", "time into the current pulse in s"),
}

#: Unit suffixes that mark a column as a known one in a foreign unit (``t_ms`` for ``t_s``).
_UNITS = {"s", "ms", "us", "ns", "min", "h", "hr", "c", "degc", "k", "f", "degf", "v", "mv", "ma",
          "ua", "a",
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


def frozen(values: ArrayLike) -> NDArray:
    """``values`` as a flat read-only float array (the tables are immutable)."""
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
    root : a directory the file must lie inside (see :func:`spicethermal.io.files.read_text`).

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
        return Columns(label, {c: frozen(fast[:, j]) for c, j in index.items()}, rows)
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
    return Columns(label, {c: frozen(v) for c, v in values.items()}, rows)


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


# --------------------------------------------------------------------------------------------
# checks shared by the tables (they name file, row and column)
# --------------------------------------------------------------------------------------------
def rows_for(n: int, rows: ArrayLike | None) -> NDArray:
    """The file row of each of ``n`` values (their position, 1-based, for arrays in memory)."""
    if rows is None:
        return np.arange(1, n + 1)  # arrays in memory: row k is the k-th value
    return np.asarray(rows, dtype=int)


def check_column(name: str, values: ArrayLike | None, file: str, rows: NDArray | None,
                 n: int | None = None) -> NDArray | None:
    """Column ``name`` as a frozen array: finite numbers, ``n`` of them when given (None stays
    None); a problem names the file, row and column."""
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
    rr = rows_for(arr.size, rows)
    bad = np.flatnonzero(~np.isfinite(arr))
    if bad.size:
        i = bad[0]
        raise DataFormatError(f"{where(file, int(rr[i]), name)}{arr[i]} is not a finite number")
    arr.setflags(write=False)
    return arr


def check_times(t_s: NDArray, file: str, rows: ArrayLike | None = None,
                column: str = "t_s") -> None:
    """Times must be >= 0 and strictly increasing; the message names the offending row."""
    rr = rows_for(t_s.size, rows)
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
    rr = rows_for(values.size, rows)
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


def check_range(values: NDArray, file: str, rows: ArrayLike | None, column: str, *,
                 low: float = -math.inf, high: float = math.inf, low_open: bool = False,
                 what: str = "") -> None:
    """Refuse values outside ``[low, high]`` (``low`` excluded with ``low_open``), naming the
    file, row and column of the first one."""
    rr = rows_for(values.size, rows)
    bad = (values <= low if low_open else values < low) | (values > high)
    idx = np.flatnonzero(bad)
    if idx.size:
        i = idx[0]
        raise DataFormatError(f"{where(file, int(rr[i]), column)}{float(values[i])!r}: {what}")


def scalar(value: Any, key: str, *, positive: bool = False, temperature: bool = False,
           nonnegative: bool = False, optional: bool = True) -> float | None:
    """A number of ``bundle.json`` (key ``key``), checked; None when absent and ``optional``."""
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


def set_fields(obj: object, **values: Any) -> None:
    """Set fields of a frozen dataclass from its ``__post_init__`` (normalised values)."""
    for k, v in values.items():
        object.__setattr__(obj, k, v)
