"""Reading ``bundle.json``: the format versions, the sections and their files, checked one key
at a time; every problem names the file and key (``docs/bundle-format.md``).
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from ..core.errors import DataFormatError, where
from .columns import Columns, read_columns, scalar
from .datasets import (
    CalibrationTable,
    CoolingTable,
    ForwardTable,
    KFactorLaw,
    PwmTable,
    ZthTable,
)
from .files import read_json

FORMAT = "spicethermal-bundle/2"
#: The version that adds the ``forward`` section (the heater's Vf(I, T) points).
FORMAT_FORWARD = "spicethermal-bundle/3"
#: The version that adds the ``coupling`` section of an array (:mod:`spicethermal.io.coupling`).
FORMAT_COUPLING = "spicethermal-bundle/4"
#: Versions read; a bundle is written with the lowest one that holds it (a /1 reader still
#: reads every bundle whose calibration is a table). /2 adds calibration kinds, /3 the
#: ``forward`` section, /4 the ``coupling`` section.
FORMATS = ("spicethermal-bundle/1", FORMAT, FORMAT_FORWARD, FORMAT_COUPLING)
#: Calibration kinds of ``bundle.json`` (``docs/bundle-format.md``).
CALIBRATION_KINDS = ("table", "k-factor", "polynomial")
MANIFEST = "bundle.json"


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
        coupling = doc.get("coupling")
        extra = coupling.get("curves") if isinstance(coupling, dict) else None
        for key in ("calibration", "cooling", "pwm", "zth", "forward", "curves"):
            entries = extra if key == "curves" else doc.get(key)
            for entry in entries if isinstance(entries, list) else [entries]:
                if isinstance(entry, dict) and isinstance(entry.get("file"), str):
                    names.add(entry["file"])
    return names


class ManifestReader:
    """The checked sections of one bundle directory's ``bundle.json``.

    Parameters
    ----------
    path : Path
        The bundle directory.
    doc : dict
        Its parsed ``bundle.json``.

    Attributes
    ----------
    path : Path
        The bundle directory.
    doc : dict
        The parsed ``bundle.json``.
    label : str
        The manifest's path, as error messages name it.
    format : str
        The document's format version (one of :data:`FORMATS`).
    """

    def __init__(self, path: Path, doc: dict) -> None:
        self.path, self.doc = path, doc
        self.label = str(path / MANIFEST)
        self.format = doc.get("format")

    @classmethod
    def open(cls, path: str | os.PathLike) -> ManifestReader:
        """Read the manifest of the bundle directory ``path`` (or its ``bundle.json``).

        Parameters
        ----------
        path : str or os.PathLike
            The bundle directory or its ``bundle.json``.

        Returns
        -------
        ManifestReader
            The reader; the format version is checked, the sections not yet.
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
        return cls(path, doc)

    # -- the pieces every section uses ------------------------------------------------------
    def section(self, key: str) -> dict:
        """The object under ``key``."""
        value = self.doc.get(key)
        if not isinstance(value, dict):
            raise DataFormatError(f"{self.label}, key {key}: must be an object")
        return value

    def sections(self, key: str) -> list[dict]:
        """The list of objects under ``key`` (one object counts as a list of one)."""
        value = self.doc.get(key)
        if isinstance(value, dict):
            value = [value]
        if not isinstance(value, list):
            raise DataFormatError(f"{self.label}, key {key}: must be a list of objects")
        for i, v in enumerate(value):
            if not isinstance(v, dict):
                raise DataFormatError(f"{self.label}, key {key}[{i}]: must be an object")
        return value

    def table(self, entry: dict, key: str, required, optional=()) -> tuple[str, Columns]:
        """The file named by ``entry`` (inside the bundle) and its columns."""
        name = entry.get("file")
        if not isinstance(name, str) or not name:
            raise DataFormatError(f"{self.label}, key {key}.file: missing or not a file name")
        target = (self.path / name)
        if Path(name).is_absolute() or ".." in Path(name).parts:
            raise DataFormatError(f"{self.label}, key {key}.file: {name!r} must be a file "
                                  f"inside the bundle")
        return name, read_columns(target, required, optional, label=str(target),
                                  root=self.path)

    def num(self, entry: dict, key: str, name: str, **kw) -> float | None:
        """The number ``entry[name]``, checked as :func:`~spicethermal.io.columns.scalar` does."""
        return scalar(entry.get(name), f"{self.label}, key {key}.{name}", **kw)

    @staticmethod
    def known(entry: dict, keys: Iterable[str]) -> dict:
        """The keys of ``entry`` that are neither ``keys`` nor ``file`` (kept as extras)."""
        return {k: v for k, v in entry.items() if k not in set(keys) | {"file"}}

    def wrap(self, make, fname: str):
        """``make()``, its errors naming the file on disk rather than its basename."""
        try:
            return make()
        except DataFormatError as exc:
            text = str(exc)
            if text.startswith(fname) and not text.startswith(str(self.path / fname)):
                text = str(self.path / fname) + text[len(fname):]
            raise DataFormatError(text) from None

    # -- the sections ------------------------------------------------------------------------
    def calibration(self) -> CalibrationTable | KFactorLaw | None:
        """The ``calibration`` section, any kind, or None when there is none."""
        if self.doc.get("calibration") is None:
            return None
        entry = self.section("calibration")

        kind = entry.get("kind", "table")
        key = f"{self.label}, key calibration"
        if "kind" in entry and self.format == FORMATS[0]:
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
            k = scalar(entry[given[0]], f"{key}.{given[0]}", optional=False)
            v = scalar(entry["v_ref_v"], f"{key}.v_ref_v", optional=False)
            t = scalar(entry["t_ref_c"], f"{key}.t_ref_c", temperature=True, optional=False)
            if k == 0:
                raise DataFormatError(f"{key}.{given[0]}: zero, the TSP does not depend on T")
            return KFactorLaw(k * (1e-3 if given[0] == "k_mv_per_k" else 1.0), v, t, key)
        name, cols = self.table(entry, "calibration", ["temp_c", "v_tsp_v"])
        coefficients = None
        if kind == "polynomial":
            coefficients = entry.get("coefficients_v")
            if not isinstance(coefficients, list) or any(
                    isinstance(c, bool) or not isinstance(c, int | float) for c in coefficients):
                raise DataFormatError(f"{key}.coefficients_v: a polynomial calibration needs a "
                                      f"list of numbers (V per degC^k, ascending)")
        return self.wrap(lambda: CalibrationTable(
            cols["temp_c"], cols["v_tsp_v"], file=name, rows=cols.rows,
            extra=self.known(entry, ("kind", "coefficients_v")), coefficients=coefficients), name)

    def cooling(self, calibration: CalibrationTable | KFactorLaw | None
                ) -> tuple[CoolingTable, ...]:
        """The ``cooling`` sections (TSP voltages need ``calibration`` to convert them)."""
        cooling = []
        if self.doc.get("cooling") is None:
            return ()
        label = self.label
        for i, entry in enumerate(self.sections("cooling")):
            key = f"cooling[{i}]"
            name, cols = self.table(entry, key, ["t_s", ("tj_c", "v_tsp_v")], ["tref_c"])
            power = self.num(entry, key, "power_w", positive=True, optional=False)
            tjs = self.num(entry, key, "tj_steady_c", temperature=True)
            trs = self.num(entry, key, "tref_steady_c", temperature=True)
            if "v_tsp_v" in cols and "tj_c" not in cols and calibration is None:
                raise DataFormatError(f"{label}, key {key}: {name} gives v_tsp_v but the "
                                      f"bundle has no calibration to convert it (add one, "
                                      f"docs/bundle-format.md, or pass --calibration CSV "
                                      f"or --k-factor MV_PER_K with --ambient DEGC)")
            cooling.append(self.wrap(lambda cols=cols, name=name, entry=entry, power=power,
                                     tjs=tjs, trs=trs: CoolingTable(
                t_s=cols["t_s"], power_w=power, tj_c=cols.get("tj_c"),
                v_tsp_v=None if "tj_c" in cols else cols.get("v_tsp_v"),
                tref_c=cols.get("tref_c"), tj_steady_c=tjs, tref_steady_c=trs, file=name,
                rows=cols.rows,
                extra=self.known(entry, ("power_w", "tj_steady_c", "tref_steady_c"))), name))
        return tuple(cooling)

    def pwm(self) -> PwmTable | None:
        """The ``pwm`` section, or None when there is none."""
        if self.doc.get("pwm") is None:
            return None
        entry = self.section("pwm")
        name, cols = self.table(entry, "pwm", ["freq_hz", "duty", "tj_c"], ["tref_c", "power_w"])
        power = self.num(entry, "pwm", "power_w", positive=True)
        window = self.num(entry, "pwm", "sample_window_s", nonnegative=True)
        if power is None and "power_w" not in cols:
            raise DataFormatError(f"{self.label}, key pwm.power_w: missing, and {name} has no "
                                  f"power_w column")
        return self.wrap(lambda: PwmTable(
            freq_hz=cols["freq_hz"], duty=cols["duty"], tj_c=cols["tj_c"], power_w=power,
            tref_c=cols.get("tref_c"), row_power_w=cols.get("power_w"),
            sample_window_s=0.0 if window is None else window, file=name, rows=cols.rows,
            extra=self.known(entry, ("power_w", "sample_window_s"))), name)

    def zth(self) -> tuple[ZthTable, ...]:
        """The ``zth`` sections (measured or datasheet Zth(t) curves)."""
        if self.doc.get("zth") is None:
            return ()
        zth = []
        label = self.label
        for i, entry in enumerate(self.sections("zth")):
            key = f"zth[{i}]"
            name, cols = self.table(entry, key, ["t_s", ("zth_k_per_w", "r")])
            rth = self.num(entry, key, "rth_k_per_w", positive=True)
            norm = entry.get("normalized")
            if norm is not None and not isinstance(norm, bool):
                raise DataFormatError(f"{label}, key {key}.normalized: {norm!r} must be "
                                      f"true or false")
            if "zth_k_per_w" in cols and "r" in cols:
                raise DataFormatError(f"{where(str(self.path / name))}has both zth_k_per_w and "
                                      f"r; keep one")
            has_r = "r" in cols
            if norm is not None and norm != has_r:
                col = "r" if norm else "zth_k_per_w"
                raise DataFormatError(f"{label}, key {key}.normalized: {norm} but {name} "
                                      f"has no column {col}")
            zth.append(self.wrap(lambda cols=cols, name=name, entry=entry, rth=rth: ZthTable(
                t_s=cols["t_s"], zth_k_per_w=cols.get("zth_k_per_w"), r=cols.get("r"),
                rth_k_per_w=rth, file=name, rows=cols.rows,
                extra=self.known(entry, ("rth_k_per_w", "normalized"))), name))
        return tuple(zth)

    def forward(self) -> ForwardTable | None:
        """The ``forward`` section (``spicethermal-bundle/3`` on), or None when there is none."""
        if self.doc.get("forward") is None:
            return None
        if self.format not in (FORMAT_FORWARD, FORMAT_COUPLING):
            raise DataFormatError(f"{self.label}, key forward: forward-voltage points need "
                                  f"format {FORMAT_FORWARD!r}")
        entry = self.section("forward")
        name, cols = self.table(entry, "forward", ["temp_c", "i_a", "vf_v"], ["t_pulse_s"])
        sense = self.num(entry, "forward", "sense_current_a", positive=True)
        return self.wrap(lambda: ForwardTable(
            cols["temp_c"], cols["i_a"], cols["vf_v"], cols.get("t_pulse_s"), sense,
            file=name, rows=cols.rows, extra=self.known(entry, ("sense_current_a",))), name)

    def top_level(self) -> dict[str, Any]:
        """``device``, ``reference``, ``ambient_c`` and the unknown top-level keys (``extra``)."""
        doc = self.doc
        ambient = self.num(doc, "", "ambient_c", temperature=True) if "ambient_c" in doc else None
        extra = {k: v for k, v in doc.items() if k not in (
            "format", "device", "reference", "ambient_c", "calibration", "cooling", "pwm",
            "zth", "forward", "coupling")}
        return {"device": doc.get("device", ""), "reference": doc.get("reference", "ambient"),
                "ambient_c": ambient, "extra": extra}
