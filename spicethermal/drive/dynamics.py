"""The heater's network under PWM: period-averaged dynamics and the exact switched map.

:class:`Dynamics` is the averaged system ``Cm dx/dt = -G x + e0 P_max d`` of the model's
nodal network (frozen at the current state when the model has device effects), with the
closed-form periodic ripple of :mod:`spicethermal.engines.pwm` on top of the junction mean.
:class:`PeriodMap` is the exact switched response of a linear network, period by period, and
:func:`switched_peaks` the junction at the end of every on-phase of a whole schedule.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..core.errors import SimulationError
from ..core.ladder import Foster
from ..engines.pwm import stage_peaks
from ..model import ThermalModel

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

#: A duty profile: ``(first_period, periods, duty)`` steps on the grid of whole PWM periods.
Steps = list[tuple[int, int, float]]


class Dynamics:
    """Period-averaged dynamics ``Cm dx/dt = -G x + e0 P_max d`` of the model's network.

    ``modes(x)`` gives ``(λ, V, Vᵀ Cm)`` of the network (frozen at state ``x`` when the model
    is nonlinear): ``x = V z``, ``dz/dt = -λ z + V[0] P``.

    Parameters
    ----------
    model : ThermalModel
        The heater (its ladder as a nodal network, junction first).
    ambient_c : float
        Reference temperature, °C.
    p_max_w : float
        Heater power when on, W.
    f_pwm_hz : float
        PWM frequency, Hz.

    Attributes
    ----------
    model : ThermalModel
    net : Network
        The model's nodal network.
    n : int
        Its number of nodes.
    tref, p, period : float
        Ambient (°C), heater power (W) and PWM period (s).
    r, tau : NDArray
        The model's Foster stages (for the ripple).
    linear : bool
        Whether the model has no device effects.

    Examples
    --------
    >>> dyn = Dynamics(ThermalModel(Foster.from_tau([10.0, 90.0], [1e-3, 1.0])), 25.0, 1.0,
    ...                1000.0)
    >>> round(float(dyn.steady(1.0)[0]), 9), bool(dyn.ripple(1.0) == 0.0)  # Rth · P; no ripple
    (100.0, True)
    """

    def __init__(self, model: ThermalModel, ambient_c: float, p_max_w: float,
                 f_pwm_hz: float) -> None:
        self.model = model
        self.net = model.network()
        self.n = self.net.n
        self.tref = ambient_c
        self.p = p_max_w
        self.period = 1.0 / f_pwm_hz
        lad = model.ladder
        foster = lad if isinstance(lad, Foster) else lad.to_foster()
        self.r = np.asarray(foster.r)
        self.tau = np.asarray(foster.tau)
        self.linear = model.is_linear
        self._fixed = self._eig(self.net.capacitance(), self.net.conductance())

    @staticmethod
    def _eig(cm: NDArray, g: NDArray) -> tuple[NDArray, NDArray, NDArray]:
        from scipy.linalg import eigh

        lam, v = eigh(g, cm)
        return lam, v, v.T @ cm

    def modes(self, x: NDArray) -> tuple[NDArray, NDArray, NDArray]:
        """``(λ, V, Vᵀ Cm)`` of the network at state ``x`` (node rises, K)."""
        if self.linear:
            return self._fixed
        cm, g = self.model._matrices(x, self.tref, self.net)
        return self._eig(cm, g)

    def scale(self, junction_k: float) -> float:
        """Resistance factor of the temperature coefficient at a junction rise (1 if none):
        the mean over the layers of each layer's factor with the layer at the junction
        temperature (exact for the junction form, an upper bound on the change otherwise)."""
        tj = self.tref + junction_k
        n = self.model.ladder.order
        factors = np.ones(n)
        for e in self.model.device_effects:
            factors *= np.array(e.resistance_scales([tj] * n, tj))
        return float(np.mean(factors))

    def ripple(self, duty: NDArray | float, junction_k: float = 0.0) -> NDArray:
        """Periodic-steady-state junction peak minus mean (K) at ``duty``."""
        s = self.scale(junction_k) if not self.linear else 1.0
        d = np.asarray(duty, dtype=float)
        peaks = stage_peaks(self.r * s, self.tau * s, self.period, d[..., None]).sum(axis=-1)
        return self.p * (peaks - d * s * self.r.sum())

    def advance(self, x: NDArray, h: float, duty: float,
                modes: tuple[NDArray, NDArray, NDArray]) -> NDArray:
        """The averaged state ``h`` seconds after ``x`` at constant ``duty``."""
        if self.linear:
            lam, v, vinv = modes
            e = np.exp(-lam * h)
            z = (vinv @ x) * e + self.p * duty * v[0] / lam * -np.expm1(-lam * h)
            return v @ z
        # one piece of the nonlinear network, at a looser tolerance than a final prediction
        end, _ = self.model._integrate(self.net, x, [(0.0, h, self.p * duty)], self.tref,
                                       rtol=1e-7, atol=1e-8)
        return end

    def steady(self, power_w: float) -> NDArray:
        """Node rises under constant average power."""
        b = np.zeros(self.n)
        b[0] = power_w
        lin = np.linalg.solve(self.net.conductance(), b)
        if self.linear or power_w == 0:
            return lin
        # every resistance scales with the junction temperature (capacitance, hence a phase
        # change, does not matter in steady state): solve the scalar  x = s(x) · lin[0]
        from scipy.optimize import brentq

        def f(x: float) -> float:
            return x - self.scale(x) * lin[0]

        hi = lin[0]
        for _ in range(60):
            if f(hi) > 0:
                break
            hi *= 2
        else:
            raise SimulationError(f"no steady state at {power_w:g} W: the temperature "
                                  "coefficient makes the junction run away")
        x = brentq(f, 0.0, hi, xtol=1e-13, rtol=1e-14)
        return self.scale(x) * lin


class PeriodMap:
    """Exact switched response of the linear network, period by period, in modal coordinates.

    A period starts with its on-phase. At constant duty the period map is affine,
    ``z -> a z + c``, so the state at the start of period j is ``z* + (z0 - z*) a^j`` and the
    junction at the end of its on-phase follows in closed form. ``duty`` may be an array
    (leading axis of every result).

    Parameters
    ----------
    dyn : Dynamics
        The (linear) network.
    duty : NDArray or float
        Duty cycle(s).

    Examples
    --------
    >>> from spicethermal.engines.pwm import steady_state
    >>> foster = Foster.from_tau([10.0], [1.0])
    >>> dyn = Dynamics(ThermalModel(foster), 25.0, 1.0, 1000.0)
    >>> late = PeriodMap(dyn, 0.5).peaks(np.zeros(1), np.array([10**5]))[0]  # periodic state
    >>> bool(np.isclose(late, steady_state(foster, 1.0, 1000.0, 0.5).peak_k, rtol=1e-12))
    True
    """

    def __init__(self, dyn: Dynamics, duty: NDArray | float) -> None:
        lam, v, _ = dyn.modes(np.zeros(dyn.n))
        period = dyn.period
        d = np.asarray(duty, dtype=float)[..., None]
        self.a = np.exp(-lam * period)
        self.v0 = v[0]
        self.e_on = np.exp(-lam * d * period)
        self.c_on = dyn.p * v[0] / lam * -np.expm1(-lam * d * period)
        self.z_star = self.c_on * np.exp(-lam * (1 - d) * period) / -np.expm1(-lam * period)

    def start(self, z0: NDArray, j: NDArray | int) -> NDArray:
        """Modal state at the start of period(s) ``j`` (shape ``duty + j + (n,)``)."""
        aj = self.a ** np.asarray(j, dtype=float)[..., None]
        zs = np.expand_dims(self.z_star, -2) if np.ndim(j) else self.z_star
        return zs + (z0 - zs) * aj

    def peaks(self, z0: NDArray, j: NDArray) -> NDArray:
        """Junction rise at the end of the on-phase of periods ``j``."""
        zj = self.start(z0, j)
        return (zj * np.expand_dims(self.e_on, -2) + np.expand_dims(self.c_on, -2)) @ self.v0


def switched_peaks(dyn: Dynamics, intervals: Steps, hold_duty: float, hold_periods: int,
                   dense: int = 3000) -> tuple[NDArray, NDArray]:
    """Exact junction rise at the end of every on-phase (linear model), sampled.

    Every period is available in closed form (:class:`PeriodMap`); long intervals are
    sampled densely first, then logarithmically.

    Parameters
    ----------
    dyn : Dynamics
        The linear network.
    intervals : list of (int, int, float)
        The profile ``(first_period, periods, duty)``; the hold follows the last one.
    hold_duty : float
        Duty after the profile.
    hold_periods : int
        Periods of the hold to include.
    dense : int
        Periods of an interval taken one by one before the sampling turns logarithmic.

    Returns
    -------
    t_s, peak_k : NDArray
        Times of the ends of the on-phases, s, and the junction rise there, K.

    Examples
    --------
    >>> dyn = Dynamics(ThermalModel(Foster.from_tau([10.0], [1.0])), 25.0, 1.0, 1000.0)
    >>> t, pk = switched_peaks(dyn, [(0, 2, 1.0)], 0.0, 1)  # 2 periods on, then off
    >>> t.tolist(), bool(np.allclose(pk, 10 * -np.expm1(-np.array([1e-3, 2e-3, 2e-3]))))
    ([0.001, 0.002, 0.002], True)
    """
    period = dyn.period
    z = np.zeros(dyn.n)
    ts, peaks = [], []
    end = intervals[-1][0] + intervals[-1][1] if intervals else 0
    for first, n, d in [*intervals, (end, hold_periods, hold_duty)]:
        pm = PeriodMap(dyn, d)
        if n <= 2 * dense:
            j = np.arange(n)
        else:
            j = np.unique(np.concatenate([np.arange(dense),
                                          np.geomspace(dense, n - 1, dense).astype(int)]))
        peaks.append(pm.peaks(z, j))
        ts.append((first + j + d) * period)
        z = pm.start(z, n)
    return np.concatenate(ts), np.concatenate(peaks)
