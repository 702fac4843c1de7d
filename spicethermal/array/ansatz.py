"""The Cauer-like network of an array of cells, and the derivatives of its Z(t).

:class:`Layout` is the structure both the simulated array (the truth) and the fitted model
share: per cell a chain of ``levels`` nodes from its junction (level 0, the port) down to its
base (the chain's last resistor joins the base to a common **substrate** node), coupling
conductances between cells at given levels (through the substrate plate at the base, through
the air and housing above it), optionally a conductance from each base to the reference
(``air``), and the substrate's resistance to the reference (the heat sink). Every node has a
heat capacity to the thermal ground. The parameters are the logarithms of every conductance
and capacity, in the order of :attr:`Layout.conductances` and :attr:`Layout.capacitor_nodes`.

:func:`response` gives Z(t) and, for the fit, its derivative with respect to every parameter
in closed form (first-order perturbation of ``(G + sC)⁻¹`` in modal coordinates, with the
divided differences of the modal integrals taken by their limits where two rates coincide,
as they do in an array of equal cells).

>>> from spicethermal.array.model import Port
>>> lay = Layout.of([Port("A", 0, 0), Port("B", 2.5, 0)], levels=2)
>>> lay.n_nodes, len(lay.conductances), lay.lateral
(5, 9, ((1, 0, 1), (0, 0, 1)))
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ..core.errors import DataFormatError
from .modal import Modes
from .model import ArrayModel, Port

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

__all__ = ["SUBSTRATE", "Layout", "neighbours", "response"]

#: Name of the common substrate node.
SUBSTRATE = "SUB"
#: Curves that share their times: ``(t_s, [(i, j), ...])``.
Group = tuple["NDArray", Sequence[tuple[int, int]]]
#: Two cells are neighbours when closer than this many times the closest pair's distance
#: (the nearest and the diagonal ones of a Braille grid).
NEIGHBOUR_RANGE = 1.5


def neighbours(ports: Sequence[Port]) -> list[tuple[int, int]]:
    """Pairs ``(i, j)``, ``i < j``, of neighbouring ports (every pair when positions are
    unknown).

    Parameters
    ----------
    ports : sequence of Port
        The ports with their positions.

    Returns
    -------
    list of (int, int)

    Examples
    --------
    >>> ps = [Port(f"D{k}", 2.5 * (k % 2), 2.5 * (k // 2)) for k in range(6)]  # a 2 x 3 cell
    >>> len(neighbours(ps))      # 3 across, 4 down, 4 diagonal
    11
    """
    n = len(ports)
    pairs = [(i, j) for i in range(n) for j in range(i + 1, n)]
    if any(p.x_mm is None for p in ports) or n < 2:
        return pairs
    d = {(i, j): math.dist((ports[i].x_mm, ports[i].y_mm), (ports[j].x_mm, ports[j].y_mm))
         for i, j in pairs}
    near = min(d.values())
    if near <= 0:
        raise DataFormatError("array ports: two ports at the same position")
    return [pq for pq in pairs if d[pq] < NEIGHBOUR_RANGE * near]


@dataclass(frozen=True)
class Layout:
    """The structure of a Cauer-like array network (see the module docstring).

    Attributes
    ----------
    ports : tuple of Port
        The cells' ports.
    levels : int
        Chain nodes per cell (level 0 is the port, ``levels − 1`` the base).
    lateral : tuple of (int, int, int)
        Coupling conductances ``(level, i, j)`` between cells ``i`` and ``j``.
    air : bool
        Each cell's base also has a conductance to the reference.
    """

    ports: tuple[Port, ...]
    levels: int
    lateral: tuple[tuple[int, int, int], ...]
    air: bool = True

    @classmethod
    def of(cls, ports: Sequence[Port], levels: int, air: bool = True) -> Layout:
        """The fit's layout: coupling between every pair of bases, and between neighbours one
        level above the base.

        Parameters
        ----------
        ports : sequence of Port
            The cells.
        levels : int
            Chain nodes per cell (the order of the fit).
        air : bool
            Include a conductance from each base to the reference.

        Returns
        -------
        Layout
        """
        if levels < 1:
            raise DataFormatError("array layout: at least one level per cell")
        n = len(ports)
        base = [(levels - 1, i, j) for i in range(n) for j in range(i + 1, n)]
        above = [(levels - 2, i, j) for i, j in neighbours(ports)] if levels > 1 else []
        return cls(tuple(ports), levels, tuple(base + above), air)

    @property
    def n_cells(self) -> int:
        """Number of cells (ports)."""
        return len(self.ports)

    @property
    def n_nodes(self) -> int:
        """Nodes: every level of every cell, then the substrate."""
        return self.n_cells * self.levels + 1

    def node(self, cell: int, level: int) -> int:
        """Index of the node of ``cell`` at ``level`` (ports first, then the deeper levels).

        Parameters
        ----------
        cell, level : int
            The cell and the level.

        Returns
        -------
        int
        """
        if level == 0:
            return cell
        return self.n_cells + cell * (self.levels - 1) + level - 1

    @property
    def substrate(self) -> int:
        """Index of the substrate node."""
        return self.n_nodes - 1

    @property
    def conductances(self) -> list[tuple[int, int]]:
        """Every conductance's ``(a, b)`` (``b = -1``: the reference), in parameter order:
        the chains (cell by cell, the base's to the substrate last), the lateral couplings,
        the bases' air paths, the substrate's path to the reference."""
        out = [(self.node(i, lv), self.node(i, lv + 1) if lv + 1 < self.levels
                else self.substrate) for i in range(self.n_cells) for lv in range(self.levels)]
        out += [(self.node(i, lv), self.node(j, lv)) for lv, i, j in self.lateral]
        if self.air:
            out += [(self.node(i, self.levels - 1), -1) for i in range(self.n_cells)]
        out.append((self.substrate, -1))
        return out

    @property
    def capacitor_nodes(self) -> list[int]:
        """The node of every capacity, in parameter order (cell by cell, then the substrate)."""
        return [self.node(i, lv) for i in range(self.n_cells)
                for lv in range(self.levels)] + [self.substrate]

    def names(self) -> tuple[str, ...]:
        """Node names: the ports', ``PORT.k`` for level k of a cell, then ``SUB``."""
        out = [""] * self.n_nodes
        for i, p in enumerate(self.ports):
            for lv in range(self.levels):
                out[self.node(i, lv)] = p.name if lv == 0 else f"{p.name}.{lv}"
        out[self.substrate] = SUBSTRATE
        return tuple(out)

    def incidence(self) -> NDArray:
        """``A`` with ``G = Aᵀ diag(g) A``: one row per conductance, +1 at ``a``, −1 at ``b``."""
        pairs = self.conductances
        a = np.zeros((len(pairs), self.n_nodes))
        for k, (i, j) in enumerate(pairs):
            a[k, i] = 1.0
            if j >= 0:
                a[k, j] = -1.0
        return a

    def model(self, g: Sequence[float], c: Sequence[float], reference: str = "ambient",
              provenance: dict[str, Any] | None = None) -> ArrayModel:
        """The :class:`ArrayModel` with conductances ``g`` (W/K) and capacities ``c`` (J/K).

        Parameters
        ----------
        g : sequence of float
            One per :attr:`conductances`.
        c : sequence of float
            One per :attr:`capacitor_nodes`.
        reference : str
            ``ambient`` or ``case``.
        provenance : dict, optional
            Stored with the model.

        Returns
        -------
        ArrayModel
        """
        res = tuple((a, b, 1.0 / float(gk)) for (a, b), gk
                    in zip(self.conductances, g, strict=True))
        caps = tuple((a, float(ck)) for a, ck in zip(self.capacitor_nodes, c, strict=True))
        return ArrayModel(self.ports, self.names(), res, caps, reference, provenance or {})


def _divided(f: NDArray, lam: NDArray, limit: NDArray) -> NDArray:
    """``(f_k − f_l)/(λ_l − λ_k)`` for every pair, ``limit`` where the rates coincide."""
    d = lam[None, :] - lam[:, None]
    close = np.abs(d) <= 1e-6 * np.maximum(lam[:, None], lam[None, :])
    with np.errstate(invalid="ignore", over="ignore"):
        out = (f[:, :, None] - f[:, None, :]) / np.where(close, 1.0, d)
    return np.where(close, limit, out)


def response(layout: Layout, p: NDArray, groups: Sequence[Group], jacobian: bool = True
             ) -> tuple[list[NDArray], list[NDArray] | None]:
    """Z(t) of the layout with parameters ``p`` for groups of curves, and its derivatives.

    Parameters
    ----------
    layout : Layout
        The structure.
    p : NDArray
        Log conductances then log capacities.
    groups : sequence of (t, pairs)
        Curves that share their times: ``t`` (s) and the ``(i, j)`` elements read at them.
    jacobian : bool
        Also return the derivatives.

    Returns
    -------
    z : list of NDArray
        Per group, ``(len(pairs), len(t))`` in K/W.
    dz : list of NDArray or None
        Per group, ``(len(p), len(pairs), len(t))``: ∂Z/∂p.
    """
    n_g = len(layout.conductances)
    g, cv = np.exp(p[:n_g]), np.exp(p[n_g:])
    inc = layout.incidence()
    cnode = np.zeros(layout.n_nodes)
    cnode[layout.capacitor_nodes] = cv
    modes = Modes.of((inc.T * g) @ inc, cnode, layout.n_cells, check=False)
    v = modes.v
    u = np.concatenate([inc @ v, v[layout.capacitor_nodes]])   # (P, K): u_e per parameter
    with np.errstate(over="ignore", under="ignore", invalid="ignore"):
        return _curves(modes, g, cv, u, n_g, len(p), groups, jacobian)


def _curves(modes: Modes, g: NDArray, cv: NDArray, u: NDArray, n_g: int, n_p: int,
            groups: Sequence[Group], jacobian: bool) -> tuple[list[NDArray], list[NDArray] | None]:
    lam, w = modes.lam, modes.w
    scale = np.concatenate([g, cv])
    zs, dzs = [], []
    for t, pairs in groups:
        t = np.asarray(t, dtype=float)
        e = np.exp(-np.outer(t, lam))
        f = -np.expm1(-np.outer(t, lam)) / lam
        ii = np.array([i for i, _ in pairs])
        jj = np.array([j for _, j in pairs])
        zs.append(np.einsum("ck,ck,tk->ct", w[ii], w[jj], f, optimize=True))
        if not jacobian:
            continue
        mid = 0.5 * (lam[:, None] + lam[None, :])
        em = np.exp(-t[:, None, None] * mid)
        f1 = _divided(f, lam, (1.0 - em - mid * t[:, None, None] * em) / mid ** 2)
        f2 = _divided(e, lam, t[:, None, None] * em)
        out = np.empty((n_p, len(pairs), t.size))
        for block, kernel in ((slice(0, n_g), f1), (slice(n_g, None), f2)):
            ub = u[block]
            for i in np.unique(ii):  # one row at a time: (E, T, K) in memory, not (E, C, T, K)
                sel = np.flatnonzero(ii == i)
                q = np.einsum("ek,tkl->etl", ub * w[i], kernel, optimize=True)
                right = w[jj[sel]][None, :, :] * ub[:, None, :]      # (E, C, K)
                out[block, sel] = -np.einsum("etl,ecl->ect", q, right, optimize=True)
        dzs.append(out * scale[:, None, None])
    return zs, (dzs if jacobian else None)
