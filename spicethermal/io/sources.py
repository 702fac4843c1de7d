"""The files of every command that takes a curve, read (``fit``, ``compare``, ``diagnose``,
``spectrum``, ``structure``, ``table1``): a calibration CSV (:func:`read_calibration`), a
K-factor given on the command line (:func:`calibration_option`), a Zth or cooling CSV
(:func:`read_curve_csv`); PyRth and T3Ster records are :mod:`.importers`, bundles
:mod:`.bundle`. :func:`spicethermal.identify.sources.read_source` reads any of them and
makes curves of them.
"""

from __future__ import annotations

import os
from dataclasses import replace
from pathlib import Path

import numpy as np

from ..core.errors import DataFormatError
from .bundle import Bundle, CalibrationTable, CoolingTable, KFactorLaw, ZthTable, read_columns
from .files import read_text
from .importers import END_SAMPLES

#: Kinds of source (:attr:`spicethermal.identify.sources.Source.kind`).
KINDS = ("bundle", "zth-csv", "cooling-csv", "pyrth", "t3ster")
#: The options that name a calibration, as the command line spells them.
CALIBRATION_OPTIONS = ("--calibration CSV (temp_c, v_tsp_v) or --k-factor MV_PER_K with "
                       "--ambient DEGC")


def read_calibration(path: str | os.PathLike) -> CalibrationTable:
    """A calibration CSV (``temp_c``, ``v_tsp_v``) as a table.

    Parameters
    ----------
    path : the CSV file.

    Returns
    -------
    CalibrationTable

    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "cal.csv"
    >>> _ = p.write_text("temp_c,v_tsp_v\\n25,0.6\\n75,0.5\\n")
    >>> read_calibration(p).v_tsp_v.tolist()
    [0.6, 0.5]
    """
    path = Path(path)
    cols = read_columns(path, ["temp_c", "v_tsp_v"])
    return CalibrationTable(cols["temp_c"], cols["v_tsp_v"], file=path.name, rows=cols.rows)


def calibration_option(calibration: str | os.PathLike | None, k_mv_per_k: float | None,
                       tref_c: float | None) -> CalibrationTable | KFactorLaw | None:
    """The calibration the command-line options give: a calibration CSV, or a K-factor
    anchored (for now) at 0 V at ``tref_c``, to be re-anchored at the end of the record
    (:func:`anchor_k_factor`); None when neither is given.

    Parameters
    ----------
    calibration : path-like or None
        ``--calibration CSV``.
    k_mv_per_k : float or None
        ``--k-factor MV_PER_K``.
    tref_c : float or None
        ``--ambient DEGC``: the temperature at the end of the record.

    Returns
    -------
    CalibrationTable, KFactorLaw or None

    Examples
    --------
    >>> print(calibration_option(None, -2.0, 25.0))
    K-factor calibration: K = -2 mV/K, 0 V at 25 degC
    """
    if calibration is not None and k_mv_per_k is not None:
        raise DataFormatError("give --calibration or --k-factor, not both")
    if calibration is not None:
        return read_calibration(calibration)
    if k_mv_per_k is None:
        return None
    if tref_c is None:
        raise DataFormatError("--k-factor needs --ambient DEGC: the temperature at the end of the "
                              "record, where the K-factor is anchored")
    return KFactorLaw.from_mv_per_k(k_mv_per_k, 0.0, tref_c, "--k-factor")


def anchor_k_factor(cal: KFactorLaw, v_tsp_v: np.ndarray) -> tuple[KFactorLaw, str]:
    """The K-factor anchored at the end of a record (the device back at ``t_ref_c``), and the
    note that says so.

    Parameters
    ----------
    cal : KFactorLaw
        The K-factor.
    v_tsp_v : ndarray
        The record's voltages: the mean of its last samples is ``v_ref_v``.

    Returns
    -------
    (KFactorLaw, str)

    Examples
    --------
    >>> anchor_k_factor(KFactorLaw(-2e-3, 0.0, 25.0), np.full(8, 0.6))[1]
    'calibration anchored: 0.6 V (end of record) = 25 degC'
    """
    cal = replace(cal, v_ref_v=float(np.mean(v_tsp_v[-END_SAMPLES:])))
    return cal, (f"calibration anchored: {cal.v_ref_v:.6g} V (end of record) = "
                 f"{cal.t_ref_c:g} degC")


def csv_header(path: str | os.PathLike) -> list[str]:
    """The column names of a CSV file (its first line that is not a ``#`` comment).

    Parameters
    ----------
    path : the file.

    Returns
    -------
    list of str
        Empty for a file without a header.
    """
    for line in read_text(Path(path)).splitlines():
        line = line.split("#", 1)[0].strip()
        if line:
            return [f.strip() for f in line.split(",")]
    return []


def read_curve_csv(path: Path, cal: CalibrationTable | KFactorLaw | None, tref_c: float | None,
                   power_w: float | None, rth: float | None
                   ) -> tuple[str, Bundle, tuple[str, ...], bool]:
    """A Zth CSV (``t_s`` and ``zth_k_per_w`` or ``r``) or a cooling CSV (``t_s`` and ``tj_c``
    or ``v_tsp_v``, optional ``tref_c``) as a bundle.

    Parameters
    ----------
    path : Path
        The CSV file.
    cal : CalibrationTable, KFactorLaw or None
        The calibration of a cooling CSV in volts (a K-factor is anchored at its end).
    tref_c : float or None
        The reference of a cooling CSV without ``tref_c``.
    power_w : float or None
        The power of a cooling CSV (1 W nominal).
    rth : float or None
        The Rth of a normalized Zth CSV.

    Returns
    -------
    (str, Bundle, tuple of str, bool)
        The kind (``zth-csv`` or ``cooling-csv``), the bundle, what was assumed on the way and
        whether the Rth was given.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "zth.csv"
    >>> _ = p.write_text("t_s,zth_k_per_w\\n1e-3,0.2\\n1e-2,0.5\\n")
    >>> kind, bundle, notes, rth_given = read_curve_csv(p, None, None, None, None)
    >>> kind, bundle.zth[0].zth_k_per_w.tolist(), rth_given
    ('zth-csv', [0.2, 0.5], False)
    """
    cols = read_columns(path, ["t_s", ("zth_k_per_w", "r", "tj_c", "v_tsp_v")], ["tref_c"])
    if "zth_k_per_w" in cols or "r" in cols:
        if "zth_k_per_w" in cols and "r" in cols:
            raise DataFormatError(f"{path}: has both zth_k_per_w and r; keep one")
        if "r" in cols and rth is None:
            raise DataFormatError(f"{path}: column r is normalized (Zth/Rth): give --rth")
        for col in ("zth_k_per_w", "r"):
            bad = np.flatnonzero(cols[col] < 0) if col in cols else []
            if len(bad):
                raise DataFormatError(f"{path}, row {int(cols.rows[bad[0]])}, column {col}: "
                                      f"{float(cols[col][bad[0]])!r} must be >= 0")
        table = ZthTable(cols["t_s"], zth_k_per_w=cols.get("zth_k_per_w"), r=cols.get("r"),
                         rth_k_per_w=rth, file=path.name, rows=cols.rows)
        return "zth-csv", Bundle(zth=(table,), source=str(path)), (), rth is not None
    notes = []
    if "tj_c" not in cols and cal is None:
        raise DataFormatError(f"{path}: column v_tsp_v needs a calibration: "
                              f"{CALIBRATION_OPTIONS}")
    if "tref_c" not in cols and tref_c is None:
        raise DataFormatError(f"{path}: a cooling curve needs a reference: a tref_c column or "
                              f"--ambient DEGC")
    if power_w is None:
        notes.append("power 1 W nominal (--power W)")
    v = None if "tj_c" in cols else cols["v_tsp_v"]
    if isinstance(cal, KFactorLaw) and v is not None:
        cal, note = anchor_k_factor(cal, v)
        notes.append(note)
    cooling = CoolingTable(cols["t_s"], 1.0 if power_w is None else power_w,
                           tj_c=cols.get("tj_c"), v_tsp_v=v, tref_c=cols.get("tref_c"),
                           tref_steady_c=tref_c, file=path.name, rows=cols.rows)
    bundle = Bundle(calibration=cal, cooling=(cooling,), source=str(path))
    return "cooling-csv", bundle, tuple(notes), False
