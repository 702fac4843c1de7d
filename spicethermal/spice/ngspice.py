"""Running SPICE decks in ngspice: the :class:`Simulator` interface and its two backends.

:class:`NgspiceBatch` runs the ``ngspice -b`` binary in a scratch directory (it proves that a
written ``.lib`` works on its own); :class:`NgspiceShared` runs PySpice over
``libngspice.so.0`` in process. Both return :class:`Waveforms`. PSPICE and LTspice dialects run
under ngspice's compatibility modes (``set ngbehavior=ps`` / ``lt`` in ``.spiceinit``).
"""

from __future__ import annotations

import logging
import os
import re
import shutil
import subprocess
import tempfile
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import TYPE_CHECKING, Protocol

import numpy as np

from ..core.errors import DataFormatError, SimulationError

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

__all__ = ["COMPAT_MODE", "NgspiceBatch", "NgspiceShared", "Simulator", "Waveforms",
           "sanitize_comment", "simulator"]

#: ngspice's compatibility mode per dialect.
COMPAT_MODE = {"ngspice": None, "pspice": "ps", "ltspice": "lt"}


def sanitize_comment(text: object, limit: int = 200) -> str:
    """One printable line safe inside a ``*`` comment (no line breaks or control characters).

    >>> sanitize_comment("ok\\n.control\\nshell rm -rf /")
    'ok .control shell rm -rf /'
    """
    line = re.sub(r"[\x00-\x1f\x7f\u2028\u2029\x85]+", " ", str(text))
    line = re.sub(r"\s+", " ", line).strip()
    return line[:limit]



@dataclass(frozen=True)
class Waveforms:
    """Simulated vectors against time."""

    t_s: NDArray
    values: Mapping[str, NDArray]

    def __getitem__(self, key: str) -> NDArray:
        return self.values[key.lower()]


class Simulator(Protocol):
    """What every simulator backend offers."""

    name: str

    def run(self, netlist: str, vectors: Sequence[str], dialect: str = "ngspice",
            cwd: str | os.PathLike | None = None) -> Waveforms:
        """Run the transient in ``netlist`` and return ``vectors`` (e.g. ``["V(TJ)"]``)."""


def _spiceinit(dialect: str) -> str:
    mode = COMPAT_MODE[dialect]
    return f"set ngbehavior={mode}\n" if mode else ""


class NgspiceBatch:
    """The ``ngspice`` binary in batch mode, in a scratch directory with its own ``.spiceinit``."""

    name = "ngspice"

    def __init__(self, executable: str = "ngspice", timeout_s: float = 600) -> None:
        self.executable = executable
        self.timeout_s = timeout_s

    def run(self, netlist: str, vectors: Sequence[str], dialect: str = "ngspice",
            cwd: str | os.PathLike | None = None) -> Waveforms:
        exe = shutil.which(self.executable)
        if exe is None:
            raise SimulationError(f"{self.executable}: not found; install ngspice (make setup)")
        with tempfile.TemporaryDirectory(prefix="spicethermal-") as tmp:
            work = Path(tmp)
            (work / ".spiceinit").write_text(_spiceinit(dialect))
            out = work / "out.txt"
            body = netlist.rstrip()
            if body.lower().endswith(".end"):
                body = body[: -len(".end")]
            deck = (f"{body}\n.control\nset wr_singlescale\nset wr_vecnames\noption numdgt=17\n"
                    f"run\nwrdata {out} {' '.join(vectors)}\nquit 0\n.endc\n.end\n")
            (work / "deck.cir").write_text(deck)
            env = dict(os.environ, HOME=str(work))  # no user ~/.spiceinit interferes
            try:
                proc = subprocess.run([exe, "-b", "deck.cir"], cwd=work, env=env, text=True,
                                      capture_output=True, timeout=self.timeout_s)
            except subprocess.TimeoutExpired:
                raise SimulationError(
                    f"ngspice did not finish within {self.timeout_s:g} s") from None
            log = proc.stdout + proc.stderr
            if proc.returncode != 0 or not out.exists() or _ABORTED.search(log):
                msg = _first_error(log)
                raise SimulationError(f"ngspice failed (exit {proc.returncode}): {msg}")
            return _read_wrdata(out, vectors)


class NgspiceShared:
    """ngspice in process through PySpice and ``libngspice.so.0``."""

    name = "pyspice"

    def run(self, netlist: str, vectors: Sequence[str], dialect: str = "ngspice",
            cwd: str | os.PathLike | None = None) -> Waveforms:
        ng = _shared_ngspice()
        ng.destroy()
        mode = COMPAT_MODE[dialect]
        ng.exec_command(f"set ngbehavior={mode}" if mode else "unset ngbehavior")
        body = netlist.rstrip()
        if not body.lower().endswith(".end"):
            body += "\n.end"
        try:
            ng.load_circuit(body)
            ng.run()
        except Exception as exc:  # PySpice raises bare exceptions for ngspice errors
            raise SimulationError(f"ngspice (shared) failed: {exc}") from None
        plot = ng.plot(None, ng.last_plot)
        try:
            t = np.asarray(plot["time"]._data, dtype=float).real
            vals = {v.lower(): np.asarray(_vector(plot, v), dtype=float).real for v in vectors}
        except KeyError as exc:
            raise SimulationError(f"ngspice (shared): no vector {exc}") from None
        return Waveforms(t, vals)


def _vector(plot, name: str):
    m = re.fullmatch(r"v\((.+)\)", name.strip(), re.I)
    key = m.group(1) if m else name
    for k in (key, key.lower(), name, name.lower()):
        if k in plot:
            return plot[k]._data
    raise KeyError(name)


@lru_cache(maxsize=1)
def _shared_ngspice():
    logging.getLogger("PySpice").setLevel(logging.ERROR)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        from PySpice.Spice.NgSpice.Shared import NgSpiceShared

        NgSpiceShared.LIBRARY_PATH = "libngspice.so.0"
        try:
            return NgSpiceShared.new_instance()
        except OSError as exc:
            raise SimulationError(f"libngspice.so.0 cannot be loaded ({exc}); "
                                  "install libngspice0 (make setup)") from None


def simulator(engine: str) -> Simulator:
    """The backend named ``engine``: ``ngspice`` (binary) or ``pyspice`` (in process).

    Parameters
    ----------
    engine : str
        ``"ngspice"`` (the ``ngspice -b`` binary) or ``"pyspice"`` (libngspice in process).

    Returns
    -------
    Simulator
        An object with ``run(netlist, vectors, dialect)``.
    """
    if engine in ("ngspice", "batch"):
        return NgspiceBatch()
    if engine in ("pyspice", "shared"):
        return NgspiceShared()
    raise DataFormatError(f"engine {engine!r}: expected ngspice or pyspice")


_ABORTED = re.compile(r"simulation\(s\) aborted|timestep too small|singular matrix", re.I)


def _first_error(text: str) -> str:
    for line in text.splitlines():
        if re.search(r"error|fatal|unknown|can't|cannot|too small|singular", line, re.I):
            return sanitize_comment(line)
    return sanitize_comment(text.strip().splitlines()[-1] if text.strip() else "no output")


def _read_wrdata(path: Path, vectors: Sequence[str]) -> Waveforms:
    with path.open() as fh:
        first = fh.readline()
    if not first.strip():
        raise SimulationError("ngspice wrote no data")
    # numpy's C reader on the file itself (a list of lines goes through Python)
    # the header names the scale: time, or v-sweep for a .dc analysis
    data = np.loadtxt(path, skiprows=int(first.strip()[:1].isalpha()), ndmin=2)
    if data.shape[1] != len(vectors) + 1:
        raise SimulationError(f"ngspice wrote {data.shape[1]} columns, expected "
                              f"{len(vectors) + 1}")
    return Waveforms(data[:, 0], {v.lower(): data[:, k + 1] for k, v in enumerate(vectors)})
