"""The exact response of an N-port RC network: modes, Z(t), piecewise-constant port powers.

A network of resistors and grounded heat capacities whose first ``N`` nodes are the ports
(heat goes in there, temperatures are read there) is ``C dθ/dt = −G θ + B P``. With the
generalized eigenproblem ``G v = λ C v`` (``vᵀ C v = I``) every mode is a scalar exponential:
``θ = V z``, ``dz/dt = −λ z + Wᵀ P`` with ``W = V[:N]``. So the step-response matrix is

    Z(t) = Σ_k w_k w_kᵀ (1 − e^{−λ_k t}) / λ_k

— symmetric, with time constants shared by every element, and positive semidefinite at every
time (a sum of rank-one PSD terms with non-negative weights): the properties a multi-port
thermal impedance must have. :class:`Modes` holds this form; :class:`ArraySchedule` is a
piecewise-constant power per port, and :meth:`Modes.response` the exact node rises under it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..core.errors import DataFormatError

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import ArrayLike, NDArray

__all__ = ["ArraySchedule", "Modes"]


@dataclass(frozen=True)
class Modes:
    """Modal form of an N-port RC network (see the module docstring).

    Attributes
    ----------
    lam : NDArray
        Decay rates ``λ_k`` (1/s), ascending.
    v : NDArray
        Mode shapes, ``(n_nodes, K)``, normalised ``vᵀ C v = I``.
    n_ports : int
        The ports are nodes ``0 .. n_ports − 1``.

    Examples
    --------
    >>> g = np.array([[1.0]]); c = np.array([2.0])     # one node: 1 K/W, 2 J/K
    >>> m = Modes.of(g, c, 1)
    >>> float(m.step([2.0])[0, 0, 0]).__round__(6)      # 1 − e^{−1}
    0.632121
    """

    lam: NDArray
    v: NDArray
    n_ports: int

    @classmethod
    def of(cls, g: NDArray, c: NDArray, n_ports: int, check: bool = True) -> Modes:
        """The modes of conductance matrix ``g`` (W/K) and node capacities ``c`` (J/K).

        Parameters
        ----------
        g : NDArray
            Symmetric conductance matrix of the free nodes (the reference eliminated).
        c : NDArray
            Heat capacity of every node to the thermal ground, all positive.
        n_ports : int
            How many of the first nodes are ports.
        check : bool
            Refuse a network without a steady state (a fit's trial steps skip the check).

        Returns
        -------
        Modes
        """
        c = np.asarray(c, dtype=float)
        if c.ndim != 1 or c.size != g.shape[0] or not np.all(c > 0):
            raise DataFormatError("array network: every node needs a positive heat capacity")
        s = 1.0 / np.sqrt(c)
        lam, u = np.linalg.eigh(s[:, None] * (g + g.T) / 2 * s[None, :])
        if check and lam[0] <= 1e-14 * max(lam[-1], 1e-300):
            raise DataFormatError("array network: no steady state (some heat has no resistive "
                                  "path to the reference)")
        return cls(lam, s[:, None] * u, int(n_ports))

    @property
    def w(self) -> NDArray:
        """Port rows of the mode shapes, ``(N, K)``: the modal input and output of the ports."""
        return self.v[:self.n_ports]

    @property
    def tau(self) -> NDArray:
        """Time constants ``1/λ_k`` (s), descending."""
        return 1.0 / self.lam

    def step(self, t: ArrayLike) -> NDArray:
        """Step-response matrix ``Z(t)`` (K/W), shape ``(len(t), N, N)``.

        Parameters
        ----------
        t : array_like
            Times after the power step, s.

        Returns
        -------
        NDArray
            ``Z[k, i, j]``: rise of port ``i`` per watt stepped into port ``j`` at ``t[k]``.
        """
        t = np.atleast_1d(np.asarray(t, dtype=float))
        f = -np.expm1(-np.outer(t, self.lam)) / self.lam
        w = self.w
        return np.einsum("ik,jk,tk->tij", w, w, f, optimize=True)

    def dc(self) -> NDArray:
        """Steady-state matrix ``Z(∞)`` (K/W), ``(N, N)``."""
        w = self.w
        return (w / self.lam) @ w.T

    def advance(self, z: NDArray, h: float | NDArray, power_w: NDArray) -> NDArray:
        """Modal state ``h`` seconds after ``z`` at constant port powers ``power_w`` (W).

        Parameters
        ----------
        z : NDArray
            Modal state ``(K,)`` (or ``(..., K)``).
        h : float or NDArray
            Duration, s.
        power_w : NDArray
            Power into each port, ``(N,)`` (or ``(..., N)``).

        Returns
        -------
        NDArray
            The modal state at the end.
        """
        h = np.asarray(h, dtype=float)[..., None]
        decay = np.exp(-self.lam * h)
        return z * decay + (np.asarray(power_w) @ self.w) / self.lam * -np.expm1(-self.lam * h)

    def steady(self, power_w: NDArray) -> NDArray:
        """Modal state of the steady state under constant port powers.

        Parameters
        ----------
        power_w : NDArray
            Power into each port, W.

        Returns
        -------
        NDArray
            ``(K,)``.
        """
        return (np.asarray(power_w, dtype=float) @ self.w) / self.lam

    def response(self, schedule: ArraySchedule, t: ArrayLike, z0: NDArray | None = None
                 ) -> NDArray:
        """Exact modal states under a piecewise-constant schedule, at times ``t``.

        Parameters
        ----------
        schedule : ArraySchedule
            Port powers.
        t : array_like
            Times, s (any order).
        z0 : NDArray, optional
            Modal state at time 0 (default: everything at the reference).

        Returns
        -------
        NDArray
            ``(len(t), K)``; node rises are ``z @ v.T``, port rises ``z @ w.T``.
        """
        t = np.atleast_1d(np.asarray(t, dtype=float))
        z = np.zeros(self.lam.size) if z0 is None else np.asarray(z0, dtype=float)
        starts = np.asarray(schedule.t_s, dtype=float)
        powers = np.asarray(schedule.power_w, dtype=float)
        at_start = [z]
        for k in range(len(starts) - 1):
            z = self.advance(z, starts[k + 1] - starts[k], powers[k])
            at_start.append(z)
        k = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(starts) - 1)
        dt = np.maximum(t - starts[k], 0.0)
        return self.advance(np.array(at_start)[k], dt, powers[k])


@dataclass(frozen=True)
class ArraySchedule:
    """Piecewise-constant port powers: ``power_w[k]`` (one value per port) from ``t_s[k]``
    until ``t_s[k + 1]`` (the last one forever). ``t_s[0]`` is 0.

    Attributes
    ----------
    t_s : tuple of float
        Start of every piece, s, increasing from 0.
    power_w : tuple of tuple of float
        Power into every port during each piece, W.

    Examples
    --------
    >>> s = ArraySchedule.of([0.0, 1.0], [[0.5, 0.0], [0.0, 0.0]])
    >>> s.n_ports, s.power_at(0.5).tolist()
    (2, [0.5, 0.0])
    """

    t_s: tuple[float, ...]
    power_w: tuple[tuple[float, ...], ...]

    @classmethod
    def of(cls, t_s: ArrayLike, power_w: ArrayLike) -> ArraySchedule:
        """A checked schedule from arrays.

        Parameters
        ----------
        t_s : array_like
            Piece starts, s: ``0`` first, increasing.
        power_w : array_like
            ``(len(t_s), N)`` port powers, W, non-negative.

        Returns
        -------
        ArraySchedule
        """
        t = np.atleast_1d(np.asarray(t_s, dtype=float))
        p = np.atleast_2d(np.asarray(power_w, dtype=float))
        if t.size == 0 or p.shape[0] != t.size:
            raise DataFormatError("array schedule: one row of port powers per time, at least "
                                  "one")
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(p))):
            raise DataFormatError("array schedule: times and powers must be finite")
        if t[0] != 0 or np.any(np.diff(t) <= 0):
            raise DataFormatError("array schedule: times must start at 0 and increase")
        if np.any(p < 0):
            raise DataFormatError("array schedule: powers must not be negative")
        return cls(tuple(map(float, t)), tuple(tuple(map(float, row)) for row in p))

    @property
    def n_ports(self) -> int:
        """Number of ports."""
        return len(self.power_w[0])

    def power_at(self, t: float) -> NDArray:
        """Port powers at time ``t`` (W).

        Parameters
        ----------
        t : float
            Time, s.

        Returns
        -------
        NDArray
        """
        k = max(0, int(np.searchsorted(self.t_s, t, side="right")) - 1)
        return np.asarray(self.power_w[k])
