"""One device of a batch: its input (a bundle or a curve file, read once into memory and hashed)
and the work done on it (fit, diagnose, export), which runs on a Dask worker.

A :class:`Source` carries the bytes of its files, so a worker needs no shared file system: it
lays them out in a temporary directory and reads them with the same functions as
``spicethermal fit``, ``diagnose`` and ``export``. :func:`characterize` never raises for a bad
input: the error becomes the row's ``error`` (naming the source's own path, not the worker's
temporary copy), so one bad input never stops a batch.
"""

from __future__ import annotations

import hashlib
import math
import re
import tempfile
import time
import traceback
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .. import __version__
from ..analysis.diagnose import diagnose
from ..core.errors import SpiceThermalError
from ..fit.ladder import fit_model
from ..identify.sources import read_source
from ..io.bundle import Bundle
from ..spice.lib import check_name, render_lib

__all__ = ["COLUMNS", "Options", "Source", "characterize", "make_row", "subckt_name"]

#: Columns of the results table, in order (``results.csv``; docs/batch.md explains each).
COLUMNS = ("source", "device", "name", "rth_k_per_w", "order", "tau_min_s", "tau_max_s",
           "fit_rms_k", "fit_rms_k_per_w", "power_w", "verdict", "improvement", "wall_s",
           "error", "sha256", "duplicate_of")
#: Curves longer than this are stored resampled (20 points per decade) in ``result.json``.
STORED_POINTS = 400


@dataclass(frozen=True)
class Options:
    """What to do with each device: fit (``max_order``), diagnose (``diagnose``, candidate
    ``effects``, default every catalogued one) and export (``dialect``, ``topology``)."""

    max_order: int = 10
    diagnose: bool = True
    effects: tuple[str, ...] | None = None
    dialect: str = "ngspice"
    topology: str | None = None


@dataclass(frozen=True)
class Source:
    """One input of a batch, in memory: ``kind`` ``"bundle"`` (a directory's files) or
    ``"curve"`` (one Zth CSV file), ``name`` its output name, ``sha256`` its content hash
    (over a bundle's file names and bytes, a curve file's bytes: the key of ``--resume`` and
    of duplicates), ``error`` if it could not be read."""

    path: str
    name: str
    kind: str
    files: dict[str, bytes] = field(default_factory=dict, repr=False)
    sha256: str = ""
    error: str = ""

    @classmethod
    def read(cls, path: str | Path, name: str) -> Source:
        """Read a bundle directory (its top-level files) or a curve file.

        >>> import tempfile, pathlib
        >>> p = pathlib.Path(tempfile.mkdtemp()) / "a.csv"
        >>> _ = p.write_text("t_s,zth_k_per_w")
        >>> s = Source.read(p, "a")
        >>> s.kind, s.sha256 == Source.read(p.rename(p.with_name("b.csv")), "b").sha256
        ('curve', True)
        """
        path = Path(path)
        kind = "bundle" if path.is_dir() else "curve"
        try:
            if kind == "bundle":
                files = {p.name: p.read_bytes() for p in sorted(path.iterdir()) if p.is_file()}
            else:
                files = {path.name: path.read_bytes()}
        except OSError as exc:
            return cls(str(path), name, kind, error=f"{path}: {exc.strerror or exc}")
        digest = hashlib.sha256()
        for file, data in sorted(files.items()):  # a curve's content is its bytes, not its name
            key = file if kind == "bundle" else ""
            digest.update(key.encode() + b"\0" + len(data).to_bytes(8, "little") + data)
        return cls(str(path), name, kind, files, digest.hexdigest())


def subckt_name(name: str) -> str:
    """A valid subcircuit name for a device name (letters, digits, ``_``; not a SPICE
    keyword: see :func:`spicethermal.spice.lib.check_name`).

    >>> subckt_name("device-007"), subckt_name("12 V rail"), subckt_name("end")
    ('DEVICE_007', '12_V_RAIL', 'D_END')
    """
    text = re.sub(r"[^A-Za-z0-9_]", "_", name).upper()[:60] or "D"
    try:
        return check_name(text)
    except SpiceThermalError:
        return f"D_{text}"


def make_row(source: Source, **values: Any) -> dict[str, Any]:
    """A results-table row of ``source`` with the given values (the others empty)."""
    row: dict[str, Any] = dict.fromkeys(COLUMNS)
    row.update(source=source.path, name=source.name, sha256=source.sha256, error="")
    row.update(values)
    return row


def characterize(source: Source, options: Options) -> dict[str, Any]:
    """Fit, diagnose and export one device; return ``{"row", "model", "lib", "curve"}``.

    ``row`` has the :data:`COLUMNS`; ``model`` is the ``spicethermal-model/3`` document (a
    dict) and ``lib`` the subcircuit text (both ``None`` on error); ``curve`` the measured
    Zth(t) (``t_s``, ``zth_k_per_w``, ``rth_k_per_w``) for the population's envelope.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "bad.csv"
    >>> _ = p.write_text("t_s,zth_k_per_w\\n1e-3,oops\\n")
    >>> characterize(Source.read(p, "bad"), Options())["row"]["error"].split("/")[-1]
    "bad.csv, row 2, column zth_k_per_w: malformed number 'oops'"
    """
    t0 = time.perf_counter()
    result: dict[str, Any] = {"row": make_row(source), "model": None, "lib": None, "curve": None}
    if source.error:
        result["row"]["error"] = source.error
        return result
    with tempfile.TemporaryDirectory(prefix="spicethermal-batch-") as tmp:
        local = Path(tmp) / (Path(source.path).name or source.name)
        try:
            if source.kind == "bundle":
                local.mkdir()
                for file, data in source.files.items():
                    (local / file).write_bytes(data)
            else:
                local.write_bytes(next(iter(source.files.values())))
            result.update(_work(local, source, options))
        except Exception as exc:  # noqa: BLE001 - any failure is this device's error row
            text = str(exc)
            if not isinstance(exc, SpiceThermalError):
                at = traceback.extract_tb(exc.__traceback__)[-1]
                text = f"{type(exc).__name__}: {exc} (in {at.name}, line {at.lineno})"
            result["row"]["error"] = text.replace(str(local), source.path).replace(tmp, "")
    result["row"]["wall_s"] = round(time.perf_counter() - t0, 4)
    return result


def _work(local: Path, source: Source, options: Options) -> dict[str, Any]:
    read = read_source(local)
    curve, held, reference = read.curve(0), read.rth_held(0), read.bundle.reference
    model, fit = fit_model(curve, max_order=options.max_order, reference=reference,
                           rth_k_per_w=curve.rth_k_per_w if held else None, hold_rth=held,
                           provenance={"tool": f"spicethermal {__version__} batch",
                                       "source": source.path, "sha256": source.sha256})
    device = source.name
    verdict, improvement = "", None
    if source.kind == "bundle":
        bundle = Bundle.read(local)
        device = bundle.device or source.name
        if options.diagnose and bundle.cooling:
            diagnosis = diagnose(bundle, None, options.effects)
            verdict = diagnosis.verdict_effect or "none"
            best = diagnosis.best or (diagnosis.candidates[0] if diagnosis.candidates else None)
            if best is not None and math.isfinite(best.improvement):
                improvement = round(best.improvement, 4)
    if options.topology and options.topology != model.ladder.topology:
        model = model.with_topology(options.topology)
    name = subckt_name(source.name)
    lib = render_lib(model, options.dialect, None, name, f"{source.name}.lib")
    tau = fit.foster.tau
    power = getattr(curve, "power_w", None)
    row = make_row(source, device=device, rth_k_per_w=fit.rth_k_per_w, order=fit.order,
                   tau_min_s=min(tau), tau_max_s=max(tau),
                   fit_rms_k=fit.rms_k_per_w * power if power else None,
                   fit_rms_k_per_w=fit.rms_k_per_w, power_w=power, verdict=verdict,
                   improvement=improvement)
    stored = curve.resample_log(20) if len(curve) > STORED_POINTS else curve
    return {"row": row, "model": model.to_dict(), "lib": lib,
            "curve": {"t_s": stored.t_s.tolist(), "zth_k_per_w": stored.zth_k_per_w.tolist(),
                      "rth_k_per_w": curve.rth_k_per_w}}
