"""Datasheet data, read: Zth points, published Foster tables, the paper's Table 1 data.

* :func:`read_zth_table` — a datasheet Zth(t) read off its log-log curve, as a CSV
  (``t_s`` and ``zth_k_per_w``, or normalized ``r`` with Rth); its curve is
  :func:`spicethermal.identify.datasheet.read_zth_points`.
* :func:`read_foster_table` — a published Foster model: ``r_k_per_w`` and ``tau_s`` (or
  ``c_j_per_k``) per stage -> :class:`~spicethermal.core.ladder.Foster`.
* :func:`mur880e` — the MUR880E data of the paper's Table 1, shipped with the package; the
  table itself, for any measured curve, is :func:`spicethermal.identify.datasheet.table1`.

>>> ds = mur880e()
>>> ds.rth_k_per_w, ds.t_s.tolist()[:2], ds.r.tolist()[:2]
(1.51, [1e-05, 0.0001], [0.018, 0.06])
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..core.errors import DataFormatError, where
from ..core.ladder import Foster
from .columns import parse_columns, read_columns
from .datasets import ZthTable

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

MUR880E_RTH_K_PER_W = 1.51


@dataclass(frozen=True, eq=False)
class Datasheet:
    """A datasheet's normalized impedance r(t) at times ``t_s``, with its Rth; optionally a
    published measurement at the same times (the paper's column for the MUR880E); its curve is
    :func:`spicethermal.identify.datasheet.datasheet_curve`.

    Attributes
    ----------
    device : str
        The device's name.
    t_s, r : NDArray
        The times (s) and the normalized impedance r(t) = Zth/Rth there.
    rth_k_per_w : float
        The datasheet's Rth, K/W.
    reference_r : NDArray or None
        A published measurement at the same times.
    reference_label : str
        Whose measurement.
    source : str
        Where the points come from.
    """

    device: str
    t_s: NDArray
    r: NDArray
    rth_k_per_w: float
    reference_r: NDArray | None = None
    reference_label: str = ""
    source: str = ""


def mur880e() -> Datasheet:
    """The MUR880E junction-to-case r(t) of the paper's Table 1 (Rthjc = 1.51 K/W), from
    the data set shipped in ``spicethermal/data/mur880e_table1.csv``; the paper's measured
    column is kept as ``reference_r``."""
    res = resources.files("spicethermal.data").joinpath("mur880e_table1.csv")
    cols = parse_columns(res.read_text(encoding="utf-8"),
                         ["t_s", "r_datasheet", "r_measured"], label="mur880e_table1.csv")
    return Datasheet("MUR880E", cols["t_s"], cols["r_datasheet"], MUR880E_RTH_K_PER_W,
                     reference_r=cols["r_measured"], reference_label="paper",
                     source="paper Table 1 (datasheet curve read at six times)")


def read_zth_table(path: str | os.PathLike, rth_k_per_w: float | None = None) -> ZthTable:
    """Datasheet Zth points from a CSV: ``t_s`` and ``zth_k_per_w`` (absolute) or ``r``
    (normalized, needs ``rth_k_per_w``).

    Parameters
    ----------
    path : str or os.PathLike
        The CSV file.
    rth_k_per_w : float, optional
        Rth, K/W (needed for normalized ``r``).

    Returns
    -------
    ZthTable
        The points as read, checked.

    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "zth.csv"
    >>> _ = p.write_text("t_s,r\\n1e-3,0.18\\n1e-2,0.39\\n")
    >>> read_zth_table(p, rth_k_per_w=1.51).r.tolist()
    [0.18, 0.39]
    """
    path = Path(path)
    cols = read_columns(path, ["t_s", ("zth_k_per_w", "r")])
    if "zth_k_per_w" in cols and "r" in cols:
        raise DataFormatError(f"{path}: has both zth_k_per_w and r; keep one")
    if "r" in cols and rth_k_per_w is None:
        raise DataFormatError(f"{path}: column r is normalized (Zth/Rth): give rth_k_per_w")
    for col in ("zth_k_per_w", "r"):
        if col in cols:
            bad = np.flatnonzero(cols[col] < 0)
            if bad.size:
                i = bad[0]
                raise DataFormatError(f"{where(str(path), int(cols.rows[i]), col)}"
                                      f"{float(cols[col][i])!r} must be >= 0")
    return ZthTable(cols["t_s"], zth_k_per_w=cols.get("zth_k_per_w"), r=cols.get("r"),
                    rth_k_per_w=rth_k_per_w, file=str(path), rows=cols.rows)


def read_foster_table(path: str | os.PathLike) -> Foster:
    """A published Foster model from a CSV: one row per stage, ``r_k_per_w`` and ``tau_s``
    (or ``c_j_per_k``).

    Parameters
    ----------
    path : str or os.PathLike
        The CSV file.

    Returns
    -------
    Foster
        The published ladder.

    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "foster.csv"
    >>> _ = p.write_text("# vendor table\\nr_k_per_w,tau_s\\n0.5,1e-3\\n1.0,0.1\\n")
    >>> read_foster_table(p).rth
    1.5
    """
    path = Path(path)
    cols = read_columns(path, ["r_k_per_w", ("tau_s", "c_j_per_k")])
    second = "tau_s" if "tau_s" in cols else "c_j_per_k"
    for col in ("r_k_per_w", second):
        bad = np.flatnonzero(cols[col] <= 0)
        if bad.size:
            i = bad[0]
            raise DataFormatError(f"{where(str(path), int(cols.rows[i]), col)}"
                                  f"{float(cols[col][i])!r} must be > 0")
    if second == "tau_s":
        return Foster.from_tau(cols["r_k_per_w"], cols["tau_s"])
    return Foster(cols["r_k_per_w"], cols["c_j_per_k"])
