"""Measurement bundles (``spicethermal-bundle/4``, ``docs/bundle-format.md``), read and written.

A bundle is a directory with ``bundle.json`` and CSV files (a header row, SI units in the
column names, ``#`` comments allowed). :class:`Bundle` is its immutable in-memory form; each
section is one table: :class:`CalibrationTable`, :class:`CoolingTable`, :class:`PwmTable`,
:class:`ZthTable`, :class:`ForwardTable`. Every problem found on reading (or on building one in
memory) raises :class:`~spicethermal.core.errors.DataFormatError` naming the file, the row (the
line number in the file, the header being line 1 of a file without comments) and the column,
or the key of ``bundle.json``.

>>> import tempfile, pathlib
>>> b = Bundle(device="diode", reference="case", ambient_c=25.0,
...            cooling=(CoolingTable(t_s=[1e-4, 1e-3], tj_c=[38.0, 36.5], power_w=10.0,
...                                  tj_steady_c=40.1, tref_steady_c=25.0),))
>>> path = b.write(pathlib.Path(tempfile.mkdtemp()) / "run1")
>>> Bundle.read(path).cooling[0].tj_c.tolist()
[38.0, 36.5]
"""

from __future__ import annotations

import os
import shutil
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..core.errors import DataFormatError
from .bundle_read import (
    CALIBRATION_KINDS,
    FORMAT,
    FORMAT_COUPLING,
    FORMAT_FORWARD,
    FORMATS,
    MANIFEST,
    ManifestReader,
    manifest_files,
)
from .columns import (
    COLUMNS,
    Columns,
    format_columns,
    parse_columns,
    parse_number,
    read_columns,
    scalar,
    set_fields,
)
from .coupling import CouplingSection
from .datasets import (
    CalibrationTable,
    CoolingTable,
    ForwardTable,
    KFactorLaw,
    PwmTable,
    ZthTable,
)
from .files import (
    clean_leftovers,
    dumps_json,
    link_tree,
    locked,
    replace_dir,
    temp_dir_for,
)

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

#: Names of the bundle's pieces, importable from here as before the split.
__all__ = ["CALIBRATION_KINDS", "COLUMNS", "FORMAT", "FORMATS", "MANIFEST", "Bundle",
           "CalibrationTable", "Columns", "CoolingTable", "ForwardTable", "KFactorLaw",
           "PwmTable", "ZthTable", "format_columns", "manifest_files", "parse_columns",
           "parse_number", "read_columns"]


# --------------------------------------------------------------------------------------------
# the bundle
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class Bundle:
    """A measurement bundle (``spicethermal-bundle/4``, /3, /2 or /1); every section is
    optional.

    Build it from tables (as the bench does), read it with :meth:`read`, write it with
    :meth:`write`. Unknown keys of ``bundle.json`` are kept in ``extra`` (and in each
    table's ``extra``) and written back.

    Attributes
    ----------
    device : str
        The device's name (``""`` when not given).
    reference : str
        The reference node of every temperature: ``"case"``, ``"ambient"`` (default), ...
    ambient_c : float or None
        The ambient temperature (degC), when known.
    calibration : CalibrationTable, KFactorLaw or None
        The TSP calibration as read (points, or a K-factor's law); its converter is
        :func:`spicethermal.identify.readings.calibration_fit`.
    cooling : tuple of CoolingTable
        The cooling curves.
    pwm : PwmTable or None
        The PWM grid of junction temperatures.
    zth : tuple of ZthTable
        Zth(t) curves given as such (datasheet or measured).
    forward : ForwardTable or None
        The heater's forward voltage at a few currents and temperatures (its Vf(I, T); format
        version 3).
    coupling : CouplingSection or None
        "Heat one, read all" on an array of devices (format version 4).
    extra : Mapping
        Unknown keys of ``bundle.json``, kept and written back.
    source : str or None
        The directory the bundle was read from (None when built in memory).

    >>> b = Bundle(calibration=CalibrationTable([25, 75], [0.60, 0.50]))
    >>> b.calibration.kind, b.manifest()["format"]
    ('table', 'spicethermal-bundle/1')
    """

    device: str = ""
    reference: str = "ambient"
    ambient_c: float | None = None
    calibration: CalibrationTable | KFactorLaw | None = None
    cooling: tuple[CoolingTable, ...] = ()
    pwm: PwmTable | None = None
    zth: tuple[ZthTable, ...] = ()
    forward: ForwardTable | None = None
    extra: Mapping[str, Any] = field(default_factory=dict, repr=False)
    source: str | None = field(default=None, compare=False)
    coupling: CouplingSection | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.device, str):
            raise DataFormatError(f"{MANIFEST}, key device: {self.device!r} is not a string")
        if self.reference not in ("ambient", "case"):
            raise DataFormatError(f"{MANIFEST}, key reference: {self.reference!r} must be "
                                  f"'ambient' or 'case'")
        ambient = scalar(self.ambient_c, f"{MANIFEST}, key ambient_c", temperature=True)
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
        if self.forward is not None and not isinstance(self.forward, ForwardTable):
            raise DataFormatError(f"{MANIFEST}, key forward: not a ForwardTable")
        set_fields(self, ambient_c=ambient, cooling=cooling, zth=zth, extra=dict(self.extra))
        names = [n for n, _ in self._named_tables()]
        dups = {n for n in names if names.count(n) > 1}
        if dups:
            raise DataFormatError(f"{MANIFEST}: two sections use the file {sorted(dups)[0]}")

    # -- helpers for users of the bundle -------------------------------------------------
    def cooling_reference_c(self, index: int = 0) -> tuple[NDArray | None, float | None]:
        """``(tref_c, tref_steady_c)`` of cooling curve ``index`` after the DESIGN rule:
        without ``tref_c`` the reference is ``tref_steady_c``, else ``ambient_c``."""
        c = self.cooling[index]
        steady = c.tref_steady_c
        if steady is None and c.tref_c is None:
            steady = self.ambient_c
        return c.tref_c, steady

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
        if self.forward is not None:
            out.append((self.forward.file or "forward.csv", self.forward))
        for i, c in enumerate(self.coupling.curves if self.coupling else (), start=1):
            out.append((c.file or f"coupling_{i}.csv", c))
        return out

    # -- reading -------------------------------------------------------------------------
    @classmethod
    def read(cls, path: str | os.PathLike,
             calibration: CalibrationTable | KFactorLaw | None = None) -> Bundle:
        """Read and validate the bundle directory ``path`` (or its ``bundle.json``).

        ``calibration`` replaces the bundle's own (or supplies a missing one). Raises
        :class:`DataFormatError` naming the file, row and column (or the key of
        ``bundle.json``) of the first problem.
        """
        reader = ManifestReader.open(path)
        if calibration is None:
            calibration = reader.calibration()
        cooling = reader.cooling(calibration)
        pwm, zth, forward = reader.pwm(), reader.zth(), reader.forward()
        return cls(calibration=calibration, cooling=cooling, pwm=pwm, zth=zth, forward=forward,
                   source=str(reader.path), coupling=CouplingSection.read(reader),
                   **reader.top_level())

    # -- writing -------------------------------------------------------------------------
    def manifest(self) -> dict[str, Any]:
        """The ``bundle.json`` document (file names as :meth:`write` uses them)."""
        v1 = isinstance(self.calibration, CalibrationTable | None) and (
            self.calibration is None or self.calibration.kind == "table")
        version = (FORMAT_COUPLING if self.coupling is not None
                   else FORMAT_FORWARD if self.forward is not None
                   else FORMATS[0] if v1 else FORMAT)
        doc: dict[str, Any] = {"format": version, "device": self.device,
                               "reference": self.reference}
        if self.ambient_c is not None:
            doc["ambient_c"] = self.ambient_c
        named = dict((id(t), n) for n, t in self._named_tables())
        if isinstance(self.calibration, KFactorLaw):
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
        if self.forward is not None:
            doc["forward"] = {"file": named[id(self.forward)], **self.forward.manifest(),
                              **self.forward.extra}
        if self.coupling is not None:
            doc["coupling"] = self.coupling.manifest([named[id(c)]
                                                      for c in self.coupling.curves])
        for k, v in self.extra.items():
            doc.setdefault(k, v)
        return doc

    def write(self, path: str | os.PathLike, *, overwrite: bool = True,
              wait: bool = False) -> Path:
        """Write the bundle to directory ``path`` atomically and return the path.

        Under the bundle's lock (:func:`spicethermal.io.files.locked`: another writer is a
        :class:`~spicethermal.core.errors.BusyError`, or is waited for with ``wait``) every file is
        written and fsynced into a new directory beside ``path``, which then replaces
        ``path`` in one step (:func:`spicethermal.io.files.replace_dir`): at every instant
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

