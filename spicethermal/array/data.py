"""Measured coupling of an array: the self and mutual step responses Z_ij(t).

"Heat one, read all": heater ``j`` is held at a constant power until the array is steady,
then cut, and every port ``i`` is read at log-spaced times after the cut. By superposition
the cooling of port ``i`` is the step response to the heating: ``Z_ij(t) = (T_i(0) − T_i(t))
/ P_j``. :class:`CouplingData` holds those curves, each at its own times (the ports of one scan
are read one after the other), and :func:`coupling_from_bundle` makes them from a bundle's
``coupling`` section (``docs/bundle-format.md``) through the same early-time correction as a
single cooling curve (:meth:`spicethermal.identify.curves.ZthCurve.from_cooling`) for the
heated port, whose junction falls fast right after the cut.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..core.errors import DataFormatError
from ..identify.curves import ZthCurve
from .model import Port

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

    from ..io.bundle import Bundle

__all__ = ["CouplingData", "Element", "coupling_from_bundle"]


@dataclass(frozen=True, eq=False)
class Element:
    """One measured element: the rise of port ``i`` per watt into port ``j``.

    Attributes
    ----------
    i, j : int
        Read port and heated port.
    t_s : NDArray
        Times after the power step, s, increasing.
    z_k_per_w : NDArray
        Z_ij at those times, K/W.
    """

    i: int
    j: int
    t_s: NDArray
    z_k_per_w: NDArray

    def __post_init__(self) -> None:
        t = np.asarray(self.t_s, dtype=float)
        z = np.asarray(self.z_k_per_w, dtype=float)
        if t.ndim != 1 or t.shape != z.shape or t.size < 2:
            raise DataFormatError(f"coupling element ({self.i}, {self.j}): times and values "
                                  f"must be equally long, at least 2")
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(z))) or np.any(t <= 0) \
                or np.any(np.diff(t) <= 0):
            raise DataFormatError(f"coupling element ({self.i}, {self.j}): times must be "
                                  f"positive and increasing, values finite")
        object.__setattr__(self, "t_s", t)
        object.__setattr__(self, "z_k_per_w", z)


@dataclass(frozen=True, eq=False)
class CouplingData:
    """Every measured Z_ij(t) of an array (see the module docstring).

    Attributes
    ----------
    ports : tuple of Port
        The ports.
    elements : tuple of Element
        One per measured (read, heated) pair; every diagonal element is needed.
    reference : str
        ``ambient`` or ``case``.
    source : str
        Where the data came from (for messages).

    Examples
    --------
    >>> from spicethermal.array.model import ArrayModel
    >>> from spicethermal.core.ladder import Foster
    >>> from spicethermal.model import ThermalModel
    >>> m = ArrayModel.from_thermal_model(ThermalModel(Foster.from_tau([1.0], [1.0])))
    >>> d = CouplingData.of_model(m, np.geomspace(1e-2, 10, 5))
    >>> len(d.elements), d.final().round(4).tolist()
    (1, [[1.0]])
    """

    ports: tuple[Port, ...]
    elements: tuple[Element, ...]
    reference: str = "ambient"
    source: str = "coupling data"

    def __post_init__(self) -> None:
        n = len(self.ports)
        seen = set()
        for e in self.elements:
            if not (0 <= e.i < n and 0 <= e.j < n) or (e.i, e.j) in seen:
                raise DataFormatError(f"{self.source}: element ({e.i}, {e.j}) is outside the "
                                      f"{n} ports or given twice")
            seen.add((e.i, e.j))
        missing = [k for k in range(n) if (k, k) not in seen]
        if missing:
            raise DataFormatError(f"{self.source}: no self curve of port "
                                  f"{self.ports[missing[0]].name} (heat it and read it)")

    @property
    def n_ports(self) -> int:
        """Number of ports."""
        return len(self.ports)

    @classmethod
    def of_model(cls, model, t_s: Sequence[float], noise_k_per_w: float = 0.0,
                 seed: int = 0) -> CouplingData:
        """Every element of ``model`` (an :class:`~spicethermal.array.model.ArrayModel`) at
        ``t_s``, with Gaussian noise: synthetic data for tests and studies.

        Parameters
        ----------
        model : ArrayModel
            The truth.
        t_s : sequence of float
            Times, s.
        noise_k_per_w : float
            Standard deviation of the noise added to every value.
        seed : int
            Seed of the noise.

        Returns
        -------
        CouplingData
        """
        t = np.asarray(t_s, dtype=float)
        z = model.zth(t)
        rng = np.random.default_rng(seed)
        n = model.n_ports
        elements = tuple(Element(i, j, t, z[:, i, j] + rng.normal(0, noise_k_per_w, t.size)
                                 if noise_k_per_w else z[:, i, j])
                         for j in range(n) for i in range(n))
        return cls(model.ports, elements, model.reference, "synthetic coupling data")

    def element(self, i: int, j: int) -> Element | None:
        """The element (``i`` read, ``j`` heated), None when not measured.

        Parameters
        ----------
        i, j : int
            Ports.

        Returns
        -------
        Element or None
        """
        return next((e for e in self.elements if e.i == i and e.j == j), None)

    def final(self) -> NDArray:
        """The last value of every measured element, ``(N, N)`` (NaN where not measured): the
        steady matrix as far as the record reaches."""
        out = np.full((self.n_ports, self.n_ports), np.nan)
        for e in self.elements:
            out[e.i, e.j] = e.z_k_per_w[-1]
        return out

    def groups(self) -> list[tuple[NDArray, list[int]]]:
        """Elements that share their times: ``(t_s, indices into elements)``.

        Returns
        -------
        list of (NDArray, list of int)
        """
        out: list[tuple[NDArray, list[int]]] = []
        for k, e in enumerate(self.elements):
            for t, members in out:
                if t.shape == e.t_s.shape and np.array_equal(t, e.t_s):
                    members.append(k)
                    break
            else:
                out.append((e.t_s, [k]))
        return out

    @property
    def span_s(self) -> tuple[float, float]:
        """The earliest and the latest time of any element, s."""
        return (min(float(e.t_s[0]) for e in self.elements),
                max(float(e.t_s[-1]) for e in self.elements))


def coupling_from_bundle(bundle: Bundle) -> CouplingData:
    """Every measured Z_ij(t) of a bundle's ``coupling`` section.

    The heated port's curve goes through the early-time correction of a single cooling curve
    (its junction at the cut extrapolated back by the √t law after the electrical transient,
    :meth:`~spicethermal.identify.curves.ZthCurve.from_cooling`); every other port starts
    from its steady reading before the cut (read through the sample window, in which it
    barely moves). Port ``i`` of a scan was read ``i · scan_s`` after port 0.

    Parameters
    ----------
    bundle : Bundle
        A bundle with a ``coupling`` section.

    Returns
    -------
    CouplingData
    """
    sec = bundle.coupling
    where = bundle.source or "bundle"
    if sec is None:
        raise DataFormatError(f"{where}: no coupling section (measure it with 'spicethermal "
                              f"bench coupling')")
    elements = []
    for table in sec.curves:
        j = table.heated
        for i in range(len(sec.ports)):
            steady = None if i == j or table.tj_steady_c is None else table.tj_steady_c[i]
            tref_steady = table.tref_steady_c if table.tref_steady_c is not None \
                else bundle.ambient_c
            z = ZthCurve.from_cooling(
                sec.times(table, i), table.tj_c[:, i], table.power_w, tj_steady_c=steady,
                tref_c=table.tref_c, tref_steady_c=tref_steady,
                label=f"{table.file}, port {sec.ports[i].name}")
            elements.append(Element(i, j, z.t_s, z.zth_k_per_w))
    return CouplingData(tuple(sec.ports), tuple(elements), bundle.reference, where)

