"""Any R/C network seen from one node: its exact Zth(t) as a Foster sum.

A network of resistors and capacitors whose boundary nodes (the reference, the thermal
ground) are held is ``C dθ/dt = −G θ + e_j P``; seen from node ``j`` its impedance is
``Z(s) = e_jᵀ (G + sC)⁻¹ e_j = r0 + Σ r_i / (1 + s τ_i)``: a Foster network, plus a pure
resistance ``r0`` when some heat path stores nothing. :func:`nodal_foster` computes it exactly
(to rounding) from ``G`` and ``C``: the directions without capacity are eliminated (a Schur
complement), the rest is the symmetric eigenproblem of ``C^-1/2 G C^-1/2``. A vendor's ladder
that is not a plain Foster chain or Cauer ladder (a branch, a bond-wire stub, a second path)
becomes its Foster form this way, and :func:`as_ladder` makes it a ladder object.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from .errors import DataFormatError
from .ladder import Cauer, Foster

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

#: An eigenvalue of C below this fraction of its largest is a direction without capacity.
NULL_CAPACITY = 1e-14
#: A Foster term whose R is below this fraction of the total is dropped (an unobservable mode).
NEGLIGIBLE_TERM = 1e-14


def dc_resistance(g: NDArray, port: int = 0) -> float:
    """Steady-state rise at node ``port`` per watt injected there (``e_jᵀ G⁻¹ e_j``).

    >>> from spicethermal.core.network import Network
    >>> net = Network(2, ((0, 1, 1.0), (1, 2, 2.0)), ())
    >>> dc_resistance(net.conductance())
    3.0
    """
    e = np.zeros(g.shape[0])
    e[port] = 1.0
    try:
        x = np.linalg.solve(g, e)
    except np.linalg.LinAlgError:
        raise DataFormatError("the network has no steady state: a node has no resistive path "
                              "to a held node") from None
    return float(x[port])


def nodal_foster(g: NDArray, c: NDArray, port: int = 0) -> tuple[float, NDArray, NDArray]:
    """Exact Foster form of the impedance seen from node ``port``.

    Parameters
    ----------
    g : ndarray
        Conductance matrix (W/K) of the free nodes, held nodes eliminated.
    c : ndarray
        Capacitance matrix (J/K), symmetric positive semi-definite.
    port : int
        The node heat is injected at and whose temperature is read.

    Returns
    -------
    (r0, r, tau)
        ``Z(s) = r0 + Σ r_i / (1 + s τ_i)``, terms sorted by ``τ``.

    Raises
    ------
    DataFormatError
        No steady state (heat stored somewhere it cannot leave).

    Examples
    --------
    >>> from spicethermal.core.network import Network
    >>> net = Network(1, ((0, 1, 2.0),), ((0, 1, 2.0),))
    >>> r0, r, tau = nodal_foster(net.conductance(), net.capacitance())
    >>> r0, r.round(12).tolist(), tau.round(12).tolist()
    (0.0, [2.0], [4.0])
    """
    n = g.shape[0]
    e = np.zeros(n)
    e[port] = 1.0
    sigma, u = np.linalg.eigh((c + c.T) / 2)
    big = float(np.max(sigma)) if n else 0.0
    if big <= 0:
        return dc_resistance(g, port), np.zeros(0), np.zeros(0)
    keep = sigma > NULL_CAPACITY * big
    ur, un = u[:, keep], u[:, ~keep]
    grr, grn, gnn = ur.T @ g @ ur, ur.T @ g @ un, un.T @ g @ un
    br, bn = ur.T @ e, un.T @ e
    r0 = 0.0
    if un.shape[1]:
        try:
            x = np.linalg.solve(gnn, np.column_stack([grn.T, bn]))
        except np.linalg.LinAlgError:
            raise DataFormatError("the network has no steady state: a node without heat "
                                  "capacity has no resistive path to a held node") from None
        grr = grr - grn @ x[:, :-1]
        br = br - grn @ x[:, -1]
        r0 = float(bn @ x[:, -1])
    s = 1.0 / np.sqrt(sigma[keep])
    lam, v = np.linalg.eigh(s[:, None] * ((grr + grr.T) / 2) * s[None, :])
    w = v.T @ (s * br)
    weight = w * w
    scale = max(float(np.max(np.abs(lam))), 1e-300)
    if np.any((lam <= 1e-13 * scale) & (weight > 0)):
        stuck = weight[lam <= 1e-13 * scale]
        if np.max(stuck) > NEGLIGIBLE_TERM * max(float(np.sum(weight)), 1e-300):
            raise DataFormatError("the network has no steady state: heat stored at some node "
                                  "has no resistive path to a held node")
    live = lam > 1e-13 * scale
    r = weight[live] / lam[live]
    tau = 1.0 / lam[live]
    total = r0 + float(np.sum(r))
    ok = r > NEGLIGIBLE_TERM * total
    order = np.argsort(tau[ok])
    return r0, r[ok][order], tau[ok][order]


def as_ladder(r0: float, r: NDArray, tau: NDArray) -> Foster | Cauer:
    """The ladder of a Foster sum with a pure resistance: a Foster network when ``r0`` is 0,
    else the exact Cauer equivalent whose junction node stores nothing (``r0`` first).

    >>> as_ladder(0.0, np.array([1.0]), np.array([2.0])).topology
    'foster'
    >>> lad = as_ladder(0.5, np.array([1.0]), np.array([2.0]))
    >>> lad.topology, lad.r, lad.c
    ('cauer', (0.5, 1.0), (0.0, 2.0))
    """
    if not len(r):
        raise DataFormatError("the network stores no heat: a Zth needs at least one capacitance")
    foster = Foster.from_tau(r, tau)
    if r0 <= 0:
        return foster
    cauer = foster.to_cauer()
    return Cauer([r0, *cauer.r], [0.0, *cauer.c])
