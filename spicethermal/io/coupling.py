"""The ``coupling`` section of a bundle: "heat one, read all" on an array of heated devices.

One :class:`CouplingTable` per heated port: the scans after the power cut (``t_s`` of port 1's
reading; port ``k`` is read ``(k − 1) · scan_s`` later), every port's junction temperature
(``tj1_c`` ... ``tjN_c``), the reference (``tref_c``), the heating power and the steady
temperatures just before the cut. :class:`CouplingSection` holds them with the ports (names
and positions) and the scan spacing. ``docs/bundle-format.md`` (version 4) is the contract.

>>> sec = CouplingSection((Port("D1"), Port("D2")), 2e-5, (CouplingTable(
...     0, [1e-4, 1e-3], [[40.0, 27.0], [39.0, 27.1]], 0.25, file="coupling_1.csv"),))
>>> sec.manifest(["coupling_1.csv"])["curves"][0]["heated"]
'D1'
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from ..core.errors import DataFormatError, where
from .bundle_read import FORMAT_COUPLING, ManifestReader
from .columns import check_temperatures, check_times, frozen, scalar, set_fields

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

__all__ = ["CouplingSection", "CouplingTable", "Port", "port_column"]

_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.\-]{0,31}")


@dataclass(frozen=True)
class Port:
    """A port of an array: the heater (and temperature sensor) of one cell.

    Attributes
    ----------
    name : str
        Its name (letters, digits, ``_ . -``; e.g. ``D1`` for Braille dot 1).
    x_mm, y_mm : float or None
        Its position on the substrate, mm (None when not known).
    """

    name: str
    x_mm: float | None = None
    y_mm: float | None = None

    def to_dict(self) -> dict:
        """The ``ports[]`` entry of a document.

        Returns
        -------
        dict
        """
        out: dict[str, Any] = {"name": self.name}
        if self.x_mm is not None and self.y_mm is not None:
            out.update(x_mm=self.x_mm, y_mm=self.y_mm)
        return out

    @classmethod
    def from_dict(cls, entry: object, at: str) -> Port:
        """A port from a document's entry; errors name ``at``.

        Parameters
        ----------
        entry : object
            The parsed entry.
        at : str
            Where it is (for messages).

        Returns
        -------
        Port
        """
        if not isinstance(entry, Mapping) or not isinstance(entry.get("name"), str) \
                or not _NAME.fullmatch(entry["name"]):
            raise DataFormatError(f"{at}: a port needs a name (letters, digits, '_', '.', '-')")
        x, y = entry.get("x_mm"), entry.get("y_mm")
        if (x is None) != (y is None):
            raise DataFormatError(f"{at}: give both x_mm and y_mm, or neither")
        if x is None:
            return cls(entry["name"])
        return cls(entry["name"], scalar(x, f"{at}.x_mm", optional=False),
                   scalar(y, f"{at}.y_mm", optional=False))


def port_column(k: int) -> str:
    """The CSV column of port ``k`` (0-based): ``tj1_c``, ``tj2_c``, ...

    Parameters
    ----------
    k : int
        Port index.

    Returns
    -------
    str
    """
    return f"tj{k + 1}_c"


@dataclass(frozen=True, eq=False)
class CouplingTable:
    """Every port's cooling after one heater's steady state (see the module docstring).

    Attributes
    ----------
    heated : int
        The heated port (index).
    t_s : NDArray
        Port 1's reading time of each scan, s from the cut.
    tj_c : NDArray
        ``(scans, N)``: every port's junction, °C.
    power_w : float
        The heater's power before the cut, W.
    tref_c : NDArray or None
        The reference temperature at each scan, °C.
    tj_steady_c : tuple of float or None
        Every port's junction just before the cut (read through the sample window).
    tref_steady_c : float or None
        The reference just before the cut, °C.
    file : str or None
        The CSV file's name.
    rows : NDArray or None
        The file row of each scan.
    extra : Mapping
        Unknown keys of the entry, kept.
    """

    heated: int
    t_s: NDArray
    tj_c: NDArray
    power_w: float
    tref_c: NDArray | None = None
    tj_steady_c: tuple[float, ...] | None = None
    tref_steady_c: float | None = None
    file: str | None = None
    rows: NDArray | None = field(default=None, repr=False)
    extra: Mapping[str, Any] = field(default_factory=dict, repr=False)

    def __post_init__(self) -> None:
        f = self.file or "coupling.csv"
        t = frozen(self.t_s)
        check_times(t, f, self.rows)
        tj = np.array(self.tj_c, dtype=float)
        if tj.ndim != 2 or tj.shape[0] != t.size or not np.all(np.isfinite(tj)):
            raise DataFormatError(f"{where(f)}one finite temperature per port and scan needed")
        for k in range(tj.shape[1]):
            check_temperatures(tj[:, k], f, self.rows, port_column(k))
        tj.setflags(write=False)
        tref = None if self.tref_c is None else frozen(self.tref_c)
        if tref is not None:
            check_temperatures(tref, f, self.rows, "tref_c")
        steady = self.tj_steady_c
        if steady is not None:
            if len(steady) != tj.shape[1]:
                raise DataFormatError(f"{f}: tj_steady_c needs one value per port")
            steady = tuple(scalar(v, f"{f}: tj_steady_c", temperature=True, optional=False)
                           for v in steady)
        if not 0 <= self.heated < tj.shape[1]:
            raise DataFormatError(f"{f}: the heated port is not one of its {tj.shape[1]} ports")
        set_fields(self, t_s=t, tj_c=tj, tref_c=tref, tj_steady_c=steady,
                   power_w=scalar(self.power_w, f"{f}: power_w", positive=True, optional=False),
                   tref_steady_c=scalar(self.tref_steady_c, f"{f}: tref_steady_c",
                                        temperature=True))

    @property
    def n_ports(self) -> int:
        """Number of ports read."""
        return int(self.tj_c.shape[1])

    def columns(self) -> dict[str, NDArray]:
        """The CSV columns, in order.

        Returns
        -------
        dict of str to NDArray
        """
        cols = {"t_s": self.t_s}
        cols.update({port_column(k): self.tj_c[:, k] for k in range(self.n_ports)})
        if self.tref_c is not None:
            cols["tref_c"] = self.tref_c
        return cols


@dataclass(frozen=True, eq=False)
class CouplingSection:
    """The ``coupling`` section: the ports, the scan spacing and one table per heated port.

    Attributes
    ----------
    ports : tuple of Port
        The array's ports, in order.
    scan_s : float
        Port ``k`` of a scan is read ``k · scan_s`` after port 0, s.
    curves : tuple of CouplingTable
        One per heated port.
    extra : Mapping
        Unknown keys of the section, kept.
    """

    ports: tuple[Port, ...]
    scan_s: float
    curves: tuple[CouplingTable, ...]
    extra: Mapping[str, Any] = field(default_factory=dict, repr=False)

    def __post_init__(self) -> None:
        names = [p.name for p in self.ports]
        if len(names) < 1 or len(set(names)) != len(names):
            raise DataFormatError("coupling: the ports need distinct names")
        scan = scalar(self.scan_s, "coupling.scan_s", nonnegative=True, optional=False)
        for c in self.curves:
            if c.n_ports != len(names):
                raise DataFormatError(f"{c.file or 'coupling'}: {c.n_ports} ports read, the "
                                      f"section lists {len(names)}")
        set_fields(self, scan_s=scan, ports=tuple(self.ports), curves=tuple(self.curves),
                   extra=dict(self.extra))

    def times(self, table: CouplingTable, port: int) -> NDArray:
        """When ``port`` was read in each scan of ``table``, s from the cut.

        Parameters
        ----------
        table : CouplingTable
            One of :attr:`curves`.
        port : int
            Port index.

        Returns
        -------
        NDArray
        """
        return table.t_s + port * self.scan_s

    def manifest(self, files: Sequence[str]) -> dict[str, Any]:
        """The ``coupling`` entry of ``bundle.json`` (``files``: each curve's file name).

        Parameters
        ----------
        files : sequence of str
            The file of each curve, in order.

        Returns
        -------
        dict
        """
        curves = []
        for c, name in zip(self.curves, files, strict=True):
            entry: dict[str, Any] = {"file": name, "heated": self.ports[c.heated].name,
                                     "power_w": c.power_w}
            if c.tj_steady_c is not None:
                entry["tj_steady_c"] = list(c.tj_steady_c)
            if c.tref_steady_c is not None:
                entry["tref_steady_c"] = c.tref_steady_c
            curves.append({**entry, **c.extra})
        return {"ports": [p.to_dict() for p in self.ports], "scan_s": self.scan_s,
                "curves": curves, **self.extra}

    @classmethod
    def read(cls, reader: ManifestReader) -> CouplingSection | None:
        """The ``coupling`` section of a bundle's manifest, its files read and checked.

        Parameters
        ----------
        reader : ManifestReader
            The bundle's manifest.

        Returns
        -------
        CouplingSection or None
            None when the bundle has none.
        """
        if reader.doc.get("coupling") is None:
            return None
        key = f"{reader.label}, key coupling"
        sec = reader.section("coupling")
        if reader.format != FORMAT_COUPLING:
            raise DataFormatError(f"{key}: the coupling section needs format {FORMAT_COUPLING!r}")
        entries = sec.get("ports")
        if not isinstance(entries, list) or not entries:
            raise DataFormatError(f"{key}.ports: must be a non-empty list of ports")
        ports = tuple(Port.from_dict(e, f"{key}.ports[{i}]") for i, e in enumerate(entries))
        index = {p.name: i for i, p in enumerate(ports)}
        curves = []
        items = sec.get("curves")
        if not isinstance(items, list):
            raise DataFormatError(f"{key}.curves: must be a list")
        wanted = [port_column(k) for k in range(len(ports))]
        for i, entry in enumerate(items):
            at = f"coupling.curves[{i}]"
            if not isinstance(entry, dict):
                raise DataFormatError(f"{key}.curves[{i}]: must be an object")
            heated = entry.get("heated")
            if heated not in index:
                raise DataFormatError(f"{key}.curves[{i}].heated: {heated!r} is not one of the "
                                      f"ports")
            name, cols = reader.table(entry, at, ["t_s", *wanted], ["tref_c"])
            steady = entry.get("tj_steady_c")
            if steady is not None and not isinstance(steady, list):
                raise DataFormatError(f"{key}.curves[{i}].tj_steady_c: one number per port")
            power = reader.num(entry, at, "power_w", positive=True, optional=False)
            tref_steady = reader.num(entry, at, "tref_steady_c", temperature=True)
            extra = reader.known(entry, ("heated", "power_w", "tj_steady_c", "tref_steady_c"))

            def make(cols=cols, name=name, heated=heated, steady=steady, power=power,
                     tref_steady=tref_steady, extra=extra) -> CouplingTable:
                return CouplingTable(heated=index[heated], t_s=cols["t_s"],
                                     tj_c=np.column_stack([cols[c] for c in wanted]),
                                     power_w=power, tref_c=cols.get("tref_c"),
                                     tj_steady_c=steady, tref_steady_c=tref_steady, file=name,
                                     rows=cols.rows, extra=extra)

            curves.append(reader.wrap(make, name))
        scan = sec.get("scan_s", 0.0)
        if isinstance(scan, bool) or not isinstance(scan, int | float) or not math.isfinite(
                scan) or scan < 0:
            raise DataFormatError(f"{key}.scan_s: {scan!r} must be a time >= 0 in s")
        return cls(ports, float(scan), tuple(curves),
                   {k: v for k, v in sec.items() if k not in ("ports", "scan_s", "curves")})
