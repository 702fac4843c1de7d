"""An array's heaters under PWM: averaged dynamics, the exact switched period map, the hold.

Every cell's heater is switched at ``f_pwm`` with amplitude ``P_max``, all periods starting
together with their on-phases; a duty per cell is the control. :class:`ArrayDynamics` holds
the model's modes (:mod:`.modal`) and answers what the drive needs: the averaged state after a
step at given duties, the duties that hold given cells at a target with every other heater off
(coupling included), and the junction peaks. The peak of a cell is its temperature at the end
of its own on-phase; :class:`SwitchedMap` gives it exactly, period by period, for a linear
network (the multi-input form of :class:`spicethermal.drive.dynamics.PeriodMap`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..core.errors import DataFormatError
from ..drive.dynamics import Dynamics
from .model import ArrayModel

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

__all__ = ["ArrayDynamics", "SwitchedMap"]


class ArrayDynamics:
    """The array's network under PWM (see the module docstring).

    Parameters
    ----------
    model : ArrayModel
        The array.
    p_max_w : float
        Heater power when on, W (every cell).
    f_pwm_hz : float
        PWM frequency, Hz.

    Attributes
    ----------
    model : ArrayModel
    modes : Modes
        Its modal form.
    p : float
        Heater power when on, W.
    period : float
        PWM period, s.
    n : int
        Number of cells.

    Examples
    --------
    >>> from spicethermal.bench.array_devices import ArrayGeometry
    >>> dyn = ArrayDynamics(ArrayGeometry(rows=1, cols=2).model(), 1.0, 1000.0)
    >>> d = dyn.hold_duties([True, False], 40.0)
    >>> round(float(dyn.steady_rise(d)[0]), 9), float(d[1])
    (40.0, 0.0)
    """

    def __init__(self, model: ArrayModel, p_max_w: float, f_pwm_hz: float) -> None:
        if not (p_max_w > 0 and f_pwm_hz > 0):
            raise DataFormatError("array drive: power and PWM frequency must be positive")
        self.model = model
        self.modes = model.modes
        self.p = float(p_max_w)
        self.period = 1.0 / float(f_pwm_hz)
        self.n = model.n_ports
        self._dc = self.modes.dc()
        self._single: list[Dynamics] | None = None
        self._table: tuple[NDArray, NDArray] | None = None

    # -- averaged --------------------------------------------------------------------------
    def advance(self, z: NDArray, h: float, duty: NDArray) -> NDArray:
        """The averaged modal state ``h`` seconds after ``z`` at constant duties.

        Parameters
        ----------
        z : NDArray
            Modal state.
        h : float
            Duration, s.
        duty : NDArray
            Duty of every cell.

        Returns
        -------
        NDArray
        """
        return self.modes.advance(z, h, self.p * np.asarray(duty, dtype=float))

    def ports(self, z: NDArray) -> NDArray:
        """Port rises (K) of modal state(s) ``z``.

        Parameters
        ----------
        z : NDArray
            ``(..., K)``.

        Returns
        -------
        NDArray
            ``(..., N)``.
        """
        return np.asarray(z) @ self.modes.w.T

    def steady_rise(self, duty: NDArray) -> NDArray:
        """Steady port rises (K) at constant duties.

        Parameters
        ----------
        duty : NDArray
            Duty of every cell.

        Returns
        -------
        NDArray
        """
        return self._dc @ (self.p * np.asarray(duty, dtype=float))

    def hold_duties(self, up: list[bool] | NDArray, rise_k: float) -> NDArray:
        """Duties that hold every ``up`` cell at ``rise_k`` in the steady state, the others off.

        Parameters
        ----------
        up : sequence of bool
            Which cells are held.
        rise_k : float
            Their rise over the reference, K.

        Returns
        -------
        NDArray
            One duty per cell (0 for the others). A duty outside [0, 1] means the hold is
            impossible (the caller says why).
        """
        up = np.asarray(up, dtype=bool)
        d = np.zeros(self.n)
        if up.any():
            d[up] = np.linalg.solve(self._dc[np.ix_(up, up)], np.full(up.sum(), rise_k)) / self.p
        return d

    # -- ripple ----------------------------------------------------------------------------
    def ripple(self, duty: NDArray) -> NDArray:
        """Periodic-steady-state junction peak minus mean (K) of every cell at its duty, from
        its own self impedance (the neighbours' ripple is filtered out by the network).

        Parameters
        ----------
        duty : NDArray
            Duty of every cell (or ``(..., N)``).

        Returns
        -------
        NDArray
        """
        if self._single is None:
            self._single = [Dynamics(self.model.self_model(i), 0.0, self.p, 1 / self.period)
                            for i in range(self.n)]
        d = np.asarray(duty, dtype=float)
        return np.stack([self._single[i].ripple(d[..., i]) for i in range(self.n)], axis=-1)


    def ripple_table(self) -> tuple[NDArray, NDArray]:
        """Duties on a 1/200 grid and every cell's :meth:`ripple` there (computed once).

        Returns
        -------
        grid : NDArray
            ``(G,)`` duties.
        ripple : NDArray
            ``(G, N)``, K.
        """
        if self._table is None:
            grid = np.linspace(0.0, 1.0, 201)
            self._table = grid, self.ripple(np.repeat(grid[:, None], self.n, axis=1))
        return self._table


class SwitchedMap:
    """Exact switched response of the linear array at constant duties, period by period.

    Every period starts with every on-phase; cell ``i`` is on for ``duty[i]`` of it. The
    period map is affine, ``z -> a z + c``, so the state at the start of period ``j`` is
    ``z* + (z0 − z*) a^j`` and the temperature of cell ``i`` at the end of its on-phase
    follows in closed form.

    Parameters
    ----------
    dyn : ArrayDynamics
        The network.
    duty : NDArray
        Duty of every cell.

    Examples
    --------
    >>> from spicethermal.bench.array_devices import ArrayGeometry
    >>> dyn = ArrayDynamics(ArrayGeometry(rows=1, cols=2).model(), 1.0, 1000.0)
    >>> sm = SwitchedMap(dyn, np.array([1.0, 0.0]))  # always on: the peak is the average
    >>> z = sm.start(np.zeros(dyn.modes.lam.size), 500)  # its on-phase ends at 0.501 s
    >>> bool(np.isclose(sm.peaks(z)[0], dyn.ports(dyn.advance(np.zeros_like(z), 0.501,
    ...                                                       [1.0, 0.0]))[0], rtol=1e-9))
    True
    """

    def __init__(self, dyn: ArrayDynamics, duty: NDArray) -> None:
        lam, w = dyn.modes.lam, dyn.modes.w
        period = dyn.period
        d = np.clip(np.asarray(duty, dtype=float), 0.0, 1.0)
        self.dyn, self.d = dyn, d
        self.a = np.exp(-lam * period)
        # modal input of each cell over one period (on, then decaying to the period's end)
        on = -np.expm1(-np.outer(d * period, lam)) / lam                    # (N, K)
        tail = np.exp(-np.outer((1 - d) * period, lam))
        self.c = (dyn.p * w * on * tail).sum(axis=0)
        self.z_star = self.c / -np.expm1(-lam * period)
        # each cell's temperature at the end of its own on-phase, from the period start
        tau = d * period                                                      # (N,)
        self._decay = np.exp(-np.outer(tau, lam))                             # (N_i, K)
        overlap = np.minimum.outer(tau, tau)                                  # (i, j)
        heat = -np.expm1(-overlap[..., None] * lam) / lam * np.exp(
            -(tau[:, None, None] - overlap[..., None]) * lam)                 # (i, j, K)
        self._forced = dyn.p * np.einsum("ik,ijk,jk->i", w, heat, w)

    def start(self, z0: NDArray, j: int | NDArray) -> NDArray:
        """Modal state at the start of period(s) ``j`` from ``z0`` at period 0.

        Parameters
        ----------
        z0 : NDArray
            Modal state at the start of period 0.
        j : int or NDArray
            Period index(es).

        Returns
        -------
        NDArray
            ``(K,)`` or ``(len(j), K)``.
        """
        aj = self.a ** np.asarray(j, dtype=float)[..., None]
        return self.z_star + (z0 - self.z_star) * aj

    def peaks(self, z: NDArray) -> NDArray:
        """Every cell's rise at the end of its own on-phase of the period starting at ``z``.

        Parameters
        ----------
        z : NDArray
            Modal state(s) at period starts, ``(..., K)``.

        Returns
        -------
        NDArray
            ``(..., N)``, K.
        """
        w = self.dyn.modes.w
        return np.einsum("...k,ik,ik->...i", z, self._decay, w) + self._forced
