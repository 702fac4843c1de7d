"""One reader for every command that takes a curve (``fit``, ``compare``, ``diagnose``,
``spectrum``, ``structure``, ``table1``).

A *source* is one of:

* a bundle directory (``spicethermal-bundle/1`` or ``/2``, ``docs/bundle-format.md``);
* a Zth CSV — measured or digitized datasheet points: ``t_s`` and ``zth_k_per_w``, or ``r``
  (normalized, needs ``rth_k_per_w``);
* a cooling CSV: ``t_s`` and ``tj_c`` (optional ``tref_c``) or raw ``v_tsp_v`` (needs a
  calibration);
* a PyRth transient ``.txt`` (time, sensor voltage; needs a calibration);
* a T3Ster ``.raw`` record (its ``.pwr`` and ``.tco`` beside it).

:func:`read_source` reads any of them (:mod:`spicethermal.io.sources`,
:mod:`spicethermal.io.importers`) into a :class:`Source`: a
:class:`~spicethermal.io.bundle.Bundle` plus what was assumed on the way (``notes``, printed by the
commands), whose curves are Zth(t) (:meth:`Source.curve`). Nothing is silently
defaulted: a file without a calibration needs ``calibration`` (a CSV of ``temp_c, v_tsp_v``)
or ``k_factor_mv_per_k`` with ``tref_c``, and the error says which option to pass.

>>> from spicethermal.data import path
>>> src = read_source(path("pyrth_mosfet/MOSFET_dry.txt"), k_factor_mv_per_k=-2.324,
...                   tref_c=25.0)
>>> src.kind, round(src.curve().rth_k_per_w, 1)
('pyrth', 13.8)
"""

from __future__ import annotations

import os
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from ..core.errors import DataFormatError
from ..fit.ladder import BINS_PER_DECADE, DENSE_POINTS, log_bins
from ..io.bundle import MANIFEST, Bundle, CoolingTable, KFactorLaw
from ..io.importers import END_SAMPLES
from ..io.sources import anchor_k_factor, calibration_option, read_curve_csv
from .curves import NotAboveReference, ZthCurve
from .readings import calibration_fit, cooling_tj_c
from .records import read_pyrth, read_t3ster


@dataclass(frozen=True)
class Source:
    """A curve source read into a bundle; ``notes`` say what was assumed or done on reading."""

    path: Path
    kind: str
    bundle: Bundle
    notes: tuple[str, ...] = ()
    rth_given: bool = False

    @property
    def n_curves(self) -> int:
        """Cooling curves, then zth tables."""
        return len(self.bundle.cooling) + len(self.bundle.zth)

    def curve(self, index: int = 0, *, early_window_s: tuple[float, float] | None = None,
              mask_s: float | str | None = "auto", tj_steady_c: float | None = None
              ) -> ZthCurve:
        """Curve ``index`` as Zth(t): cooling curves first (early-time correction, ``v_tsp_v``
        through the calibration), then zth tables.

        Parameters
        ----------
        index : which curve (``--curve``).
        early_window_s : the √t fit window (``--early-window``); default chosen from the
            electrical transient (:meth:`~spicethermal.identify.curves.ZthCurve.from_cooling`).
        mask_s : the electrical transient to mask, s, ``"auto"`` or ``None``.
        tj_steady_c : junction temperature at the cut of a cooling curve that lacks it.

        Returns
        -------
        ZthCurve
            Labelled ``name/curve`` for a bundle, the file's stem otherwise.
        """
        n_cool = len(self.bundle.cooling)
        if self.n_curves == 0:
            raise DataFormatError(f"{self.path}: no cooling curve and no zth table")
        if not 0 <= index < self.n_curves:
            raise DataFormatError(f"--curve {index}: {self.path} has {n_cool} cooling curve(s) "
                                  f"and {len(self.bundle.zth)} zth table(s) (valid: 0.."
                                  f"{self.n_curves - 1})")
        if index < n_cool:
            c = self.bundle.cooling[index]
            tref, tref_steady = self.bundle.cooling_reference_c(index)
            tjs = c.tj_steady_c if c.tj_steady_c is not None else tj_steady_c
            try:
                zc = ZthCurve.from_cooling(c.t_s, cooling_tj_c(self.bundle, index), c.power_w,
                                           tjs, tref, tref_steady, mask_s=mask_s,
                                           fit_window_s=early_window_s,
                                           label=c.file or f"cooling[{index}]")
            except NotAboveReference as exc:
                if c.v_tsp_v is None or isinstance(self.bundle.calibration, KFactorLaw):
                    raise
                recipe = k_factor_recipe(self.bundle, index, exc.ref_c)
                raise DataFormatError(f"{exc.core}. {recipe}") from None
        else:
            z = self.bundle.zth[index - n_cool]
            if z.normalized and z.rth_k_per_w is None:
                raise DataFormatError(f"{self.path}: {z.file or 'zth table'} holds normalized r "
                                      f"(Zth/Rth): give --rth")
            zc = ZthCurve.from_table(z, label=z.file or f"zth[{index - n_cool}]")
        label = (f"{self.path.name}/{zc.label}" if self.kind == "bundle" else self.path.stem)
        return replace(zc, label=label)

    def rth_held(self, index: int = 0) -> bool:
        """Whether the curve's Rth is measured (a cooling curve, eq. 1) or given, so that a fit
        should hold ``ΣR = Rth``; False for a Zth table whose Rth is only its last point."""
        if index < len(self.bundle.cooling):
            return True
        z = self.bundle.zth[index - len(self.bundle.cooling)]
        return z.rth_k_per_w is not None

    def comparable(self, points_per_decade: int = BINS_PER_DECADE, *,
                   mask_transient: bool = False) -> tuple[Bundle, list[str]]:
        """The bundle as ``compare`` and ``diagnose`` take it, and what was done to it: zth
        tables become the cooling curves they imply at 1 W (``Tj(t) = Tref + Rth − Zth(t)`` by
        superposition, ``Tref`` the ambient or 25 degC), and cooling curves denser than
        :data:`DENSE_POINTS` samples are averaged into ``points_per_decade`` log-spaced bins
        (:func:`thin`).

        ``mask_transient``: leave out of each cooling curve the samples ``fit`` masks as the
        electrical transient (:meth:`curve`'s early-time correction, the same detection), so
        that a model is judged on what it was fitted to describe; each curve's
        ``extra["left_out"]`` then says ``{"samples": n, "before_s": t}``."""
        notes: list[str] = []
        cooling = []
        for i, c in enumerate(self.bundle.cooling):
            if mask_transient:
                c = self._masked(i, notes)
            thinned = thin(c, points_per_decade)
            if thinned is not c:
                notes.append(f"{c.file}: {c.t_s.size} samples averaged into {thinned.t_s.size} "
                             f"log-spaced bins ({points_per_decade} per decade)")
            cooling.append(thinned)
        bundle = self.bundle.with_(cooling=tuple(cooling))
        if not self.bundle.zth:
            return bundle, notes
        ambient = self.bundle.ambient_c if self.bundle.ambient_c is not None else 25.0
        for i in range(len(self.bundle.zth)):
            zc = self.curve(len(self.bundle.cooling) + i)
            cooling.append(CoolingTable(zc.t_s, 1.0, tj_c=ambient + zc.rth_k_per_w
                                        - zc.zth_k_per_w,
                                        tj_steady_c=ambient + zc.rth_k_per_w,
                                        tref_steady_c=ambient,
                                        file=f"cooling_{len(cooling) + 1}.csv",
                                        extra={"from_zth": zc.label}))
            notes.append(f"{zc.label}: compared as the cooling curve it implies at 1 W from "
                         f"{ambient:g} degC")
        return bundle.with_(cooling=tuple(cooling), zth=(), ambient_c=ambient), notes


    def _masked(self, index: int, notes: list[str]) -> CoolingTable:
        """Cooling curve ``index`` without the samples fit masks (``extra["left_out"]``)."""
        c = self.bundle.cooling[index]
        try:
            early = self.curve(index).early
        except DataFormatError:  # no Zth from it: fit would refuse it, nothing to mirror
            return c
        t_mask = early.masked_s[1] if early is not None and early.masked_points else 0.0
        keep = c.t_s >= t_mask
        left_out = {"samples": int(c.t_s.size - keep.sum()), "before_s": float(t_mask)}
        if left_out["samples"]:
            notes.append(f"{c.file}: {left_out['samples']} samples before {t_mask:.3g} s left "
                         f"out (the electrical transient, masked as fit masks it)")

        def cut(values: np.ndarray | None) -> np.ndarray | None:
            return None if values is None else values[keep]

        return replace(c, t_s=c.t_s[keep], tj_c=cut(c.tj_c), v_tsp_v=cut(c.v_tsp_v),
                       tref_c=cut(c.tref_c), rows=cut(c.rows),
                       extra={**c.extra, "left_out": left_out})


def thin(cooling: CoolingTable, points_per_decade: int = BINS_PER_DECADE) -> CoolingTable:
    """A cooling curve with more than :data:`DENSE_POINTS` samples averaged into log-spaced
    bins (every column by the same bins; a bin of one sample keeps it); others unchanged.

    Parameters
    ----------
    cooling : the curve.
    points_per_decade : bins per decade of time.

    Returns
    -------
    CoolingTable
        The thinned curve (the same object when it is not dense).

    >>> t = np.geomspace(1e-6, 1.0, 2000)
    >>> c = thin(CoolingTable(t, 1.0, tj_c=30 - np.sqrt(t), tref_steady_c=25.0), 10)
    >>> c.t_s.size, bool(np.all(np.diff(c.t_s) > 0))
    (61, True)
    """
    t = cooling.t_s
    if t.size <= DENSE_POINTS:
        return cooling
    keep = t > 0
    start, counts = log_bins(t[keep], points_per_decade)

    def mean(values: np.ndarray | None) -> np.ndarray | None:
        return None if values is None else np.add.reduceat(values[keep], start) / counts

    return replace(cooling, t_s=mean(t), tj_c=mean(cooling.tj_c), v_tsp_v=mean(cooling.v_tsp_v),
                   tref_c=mean(cooling.tref_c), rows=None)


def read_source(source: str | os.PathLike, *, calibration: str | os.PathLike | None = None,
                k_factor_mv_per_k: float | None = None, tref_c: float | None = None,
                power_w: float | None = None, rth_k_per_w: float | None = None) -> Source:
    """Read any curve source (see the module docstring).

    Parameters
    ----------
    source : the bundle directory (or its ``bundle.json``) or file.
    calibration : a calibration CSV (``temp_c, v_tsp_v``); replaces a bundle's or a ``.tco``.
    k_factor_mv_per_k : a K-factor instead, anchored by ``tref_c``.
    tref_c : temperature of the device at the end of the record (re-anchors the calibration
        of a raw transient), or the reference of a cooling CSV without ``tref_c``.
    power_w : heating power of a PyRth ``.txt`` (the file has none; 1 W nominal) or of a
        cooling CSV.
    rth_k_per_w : Rth of a normalized Zth CSV (``r``), held as ``ΣR = Rth`` by a fit.

    Returns
    -------
    Source
    """
    path = Path(source)
    if path.name == MANIFEST and path.is_file():
        path = path.parent
    if not path.exists():
        raise DataFormatError(f"{path}: no such file or bundle directory")
    cal = calibration_option(calibration, k_factor_mv_per_k, tref_c)
    notes: list[str] = []
    if path.is_dir():
        bundle = Bundle.read(path, cal)
        if cal is not None:
            raw = [c.v_tsp_v for c in bundle.cooling if c.v_tsp_v is not None]
            if isinstance(cal, KFactorLaw) and raw:
                cal, note = anchor_k_factor(cal, raw[0])
                notes.append(note)
                bundle = bundle.with_(calibration=cal)
            notes.append(f"calibration from the command line: {cal}")
        return Source(path, "bundle", _with_rth(bundle, rth_k_per_w), tuple(notes),
                      rth_k_per_w is not None)
    suffix = path.suffix.lower()
    if suffix == ".txt":
        if power_w is None:
            notes.append("power 1 W nominal (the file holds none; --power W)")
        bundle = read_pyrth(path, cal, 1.0 if power_w is None else power_w, tref_c=tref_c)
        return Source(path, "pyrth", bundle, tuple(notes + _anchor_note(bundle)))
    if suffix == ".raw":
        bundle = read_t3ster(path, tref_c=tref_c)
        if cal is not None:
            bundle = bundle.with_(calibration=cal)
            notes.append(f"calibration replaced: {cal}")
        return Source(path, "t3ster", bundle, tuple(notes + _anchor_note(bundle)))
    kind, bundle, notes_csv, rth_given = read_curve_csv(path, cal, tref_c, power_w, rth_k_per_w)
    return Source(path, kind, bundle, notes_csv, rth_given)


def k_factor_recipe(bundle: Bundle, index: int, ref_c: float) -> str:
    """How to anchor cooling curve ``index``'s calibration at its reference: the bundle.json
    keys of a K-factor calibration (docs/bundle-format.md) with this record's numbers, and the
    command-line options that do the same.

    >>> v = 0.65 - 0.002 * np.array([13.0, 5.0, 0.0])  # ends near 0.64 V, 40 mV above the table
    >>> from spicethermal.io.bundle import CalibrationTable
    >>> b = Bundle(calibration=CalibrationTable(np.array([25.0, 75.0]), np.array([0.6, 0.5])),
    ...            cooling=(CoolingTable(np.array([1e-3, 1e-1, 10.0]), 1.0, v_tsp_v=v),))
    >>> k_factor_recipe(b, 0, 25.0).split("bundle.json, ")[1].split(" (docs")[0]
    '"format": "spicethermal-bundle/2" and "calibration": {"kind": "k-factor", \
"k_mv_per_k": -2, "v_ref_v": 0.638, "t_ref_c": 25}'
    """
    k = calibration_fit(bundle).k_factor_mv_per_k
    v_end = float(np.mean(bundle.cooling[index].v_tsp_v[-END_SAMPLES:]))
    v_table = float(calibration_fit(bundle).voltage(ref_c))
    return (f"The record ends at {v_end:.6g} V, {abs(v_end - v_table) * 1e3:.3g} mV off the "
            f"table's {v_table:.6g} V at {ref_c:g} degC (another sense current or "
            f"offset: only the slope transfers). Anchor the table's slope at the end of the "
            f"record, back at the reference: in bundle.json, \"format\": "
            f"\"spicethermal-bundle/2\" and \"calibration\": {{\"kind\": \"k-factor\", "
            f"\"k_mv_per_k\": {k:.4g}, \"v_ref_v\": {v_end:.6g}, \"t_ref_c\": {ref_c:g}}} "
            f"(docs/bundle-format.md); or on the command line "
            f"--k-factor {k:.4g} --ambient {ref_c:g}")


def _anchor_note(bundle: Bundle) -> list[str]:
    anchor = bundle.extra.get("source", {}).get("anchored")
    if anchor:
        return [f"calibration anchored: {anchor}"]
    return [f"the record ends at {bundle.cooling[0].tref_steady_c:.4g} degC through the "
            f"calibration as given (--ambient DEGC anchors it at the device's true temperature)"]


def _with_rth(bundle: Bundle, rth: float | None) -> Bundle:
    if rth is None or not bundle.zth:
        return bundle
    return bundle.with_(zth=tuple(replace(z, rth_k_per_w=rth) for z in bundle.zth))


def early_time_json(curve: ZthCurve) -> dict[str, Any] | None:
    """The early-time correction of ``curve`` for JSON outputs (``None`` without one).

    Parameters
    ----------
    curve : a curve from :meth:`Source.curve`.

    Returns
    -------
    dict or None
        ``masked_s``, ``fit_window_s``, ``fit_points``, ``tj0_c`` (the extrapolated Tj at the
        cut), ``slope_k_per_sqrt_s``, ``fit_rms_k``, ``detected``.

    Examples
    --------
    >>> from spicethermal.identify.curves import ZthCurve
    >>> t = np.geomspace(1e-6, 1.0, 300)
    >>> c = ZthCurve.from_cooling(t, 40 - 10 * np.sqrt(t), 1.0, tref_steady_c=25.0,
    ...                           mask_s=1e-4)
    >>> round(early_time_json(c)["tj0_c"], 9)
    40.0
    """
    e = curve.early
    if e is None:
        return None
    return {"masked_s": list(e.masked_s), "fit_window_s": list(e.fit_window_s),
            "fit_points": e.fit_points, "tj0_c": e.t0_c,
            "slope_k_per_sqrt_s": e.slope_k_per_sqrt_s, "fit_rms_k": e.fit_rms_k,
            "detected": e.detected}
