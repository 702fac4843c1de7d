"""A nonlinear Cauer ladder, integrated on its own (independent of :mod:`spicethermal.model`).

Node 0 is the junction; layer ``i`` (resistance ``R_i``) joins node ``i`` to node ``i + 1``,
the last one to the reference (the ambient or the case, held at ``tref_c``, optionally
drifting at ``tref_rate_k_per_s``). Every node has a heat capacity ``C_i`` to the thermal
ground. In absolute temperatures (°C), with heat flows ``q_i = (T_i − T_{i+1}) / R_i``::

    C_i(T_i) dT_i/dt = P(T_0)·[i = 0] + q_{i−1} − q_i

* ``R_i`` follows a :class:`~.laws.ResistanceLaw` of a *control* temperature: the layer's own
  mean temperature ``(T_i + T_{i+1})/2`` (``control="local"``) or the junction's
  (``"junction"``); linear ``R0 (1 + α (T − T0))`` (clipped at 5 % of R0), a power law in
  kelvin ``R0 ((T + 273.15)/(T0 + 273.15))^n`` (conductivity ``k ∝ T^−n``), or one of the
  forms that are in no catalogue (:mod:`.laws`);
* ``C_i(T) = C0_i (1 + β_i (T − T0))`` plus the latent heat of any :class:`~.laws.LatentHeat`
  at node ``i`` spread over a band (gaussian, logistic, plateau or skewed), with or without
  hysteresis (a cooling integrates the band's cooling branch, :meth:`Network.cooling_branch`);
* the heater may sag with temperature, ``P(T_0) = P (1 − γ (T_0 − T0))`` (an effect that is in
  no catalogue).

Time integration is stiff (``scipy.integrate.solve_ivp``, BDF by default, Radau on request)
with the analytic Jacobian of the right-hand side (:meth:`Network.jacobian`); it integrates the
deviation from the starting state, so that the tolerance applies to the change, not to the
absolute temperature. The linear network also has an exact Foster form (:meth:`Network.foster`).

>>> net = Network((1.0, 2.0), (1e-3, 1e-1))
>>> r, tau = net.foster()
>>> round(float(r.sum()), 12)
3.0
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import root

from .laws import KELVIN, LatentHeat, ResistanceLaw

__all__ = ["KELVIN", "LatentHeat", "Network", "ResistanceLaw"]

@dataclass(frozen=True)
class Network:
    """A Cauer ladder with temperature-dependent layers and nodes (module docstring).

    Parameters
    ----------
    r_k_per_w, c_j_per_k : ``R0`` of every layer and ``C0`` of every node, junction first.
    laws : one :class:`ResistanceLaw` per layer, or None (constant) for a layer.
    control : ``"local"`` or ``"junction"`` (which temperature the laws follow).
    c_slope_per_k : ``β_i`` of every node (heat capacity rising with T), or empty.
    latent : latent heats at any nodes.
    power_slope_per_k : ``γ``, heater power sag per kelvin of junction temperature.
    t0_c : temperature at which ``C = C0`` and ``P`` is nominal.

    Examples
    --------
    >>> net = Network((10.0,), (0.1,))
    >>> round(float(net.steady(1.0, 25.0)[0]), 9)
    35.0
    """

    r_k_per_w: Sequence[float]
    c_j_per_k: Sequence[float]
    laws: Sequence[ResistanceLaw | None] = ()
    control: str = "local"
    c_slope_per_k: Sequence[float] = ()
    latent: Sequence[LatentHeat] = ()
    power_slope_per_k: float = 0.0
    t0_c: float = 25.0
    method: str = field(default="BDF", repr=False)

    def __post_init__(self) -> None:
        n = len(self.r_k_per_w)
        if n == 0 or len(self.c_j_per_k) != n:
            raise ValueError("a network needs as many capacities as resistances (>= 1)")
        if self.control not in ("local", "junction"):
            raise ValueError(f"control {self.control!r}: expected 'local' or 'junction'")
        object.__setattr__(self, "laws", tuple(self.laws) or (None,) * n)
        object.__setattr__(self, "c_slope_per_k", tuple(self.c_slope_per_k) or (0.0,) * n)
        if len(self.laws) != n or len(self.c_slope_per_k) != n:
            raise ValueError("laws and c_slope_per_k need one entry per layer")
        for h in self.latent:
            if not 0 <= h.node < n:
                raise ValueError(f"latent heat at node {h.node}: the ladder has {n} nodes")

    @property
    def n(self) -> int:
        return len(self.r_k_per_w)

    @property
    def is_linear(self) -> bool:
        """True without any temperature dependence (the exact Foster form then holds)."""
        return (all(law is None for law in self.laws) and not any(self.c_slope_per_k)
                and not self.latent and self.power_slope_per_k == 0.0)

    def with_(self, **changes) -> Network:
        return replace(self, **changes)

    @property
    def hysteretic(self) -> tuple[LatentHeat, ...]:
        """The latent heats that melt and solidify at different temperatures."""
        return tuple(h for h in self.latent if h.gap_k > 0)

    def cooling_branch(self, start: np.ndarray) -> Network:
        """The network as it cools from ``start`` (a state reached by heating): every band with
        hysteresis replaced by its cooling branch (:meth:`~.laws.LatentHeat.cooling_branch`)."""
        if not self.hysteretic:
            return self
        return self.with_(latent=tuple(h.cooling_branch(float(start[h.node]))
                                       for h in self.latent))

    def pwm_network(self) -> Network:
        """The network in a PWM periodic state: a band with hysteresis exchanges no heat there
        as long as the ripple at its node stays within its gap (the melt fraction reached
        on the way up can then only grow on heating and only shrink on cooling, and neither
        branch is reached again), so it is left out (:func:`~.periodic.ripple_bound` checks
        the ripple)."""
        if not self.hysteretic:
            return self
        return self.with_(latent=tuple(h for h in self.latent if h.gap_k <= 0))

    # -- the right-hand side and its Jacobian ---------------------------------------------
    def _nodes(self, t: np.ndarray, tref: float) -> np.ndarray:
        return np.append(t, tref)

    def _control(self, x: np.ndarray, i: int) -> float:
        return x[0] if self.control == "junction" else 0.5 * (x[i] + x[i + 1])

    def flows(self, t: np.ndarray, tref: float) -> tuple[np.ndarray, np.ndarray]:
        """Heat flow ``q_i`` of every layer (W) and its resistance (K/W)."""
        x = self._nodes(t, tref)
        r = np.array([r0 * (law.factor(self._control(x, i)) if law else 1.0)
                      for i, (r0, law) in enumerate(zip(self.r_k_per_w, self.laws, strict=True))])
        return (x[:-1] - x[1:]) / r, r

    def capacities(self, t: np.ndarray) -> np.ndarray:
        """Heat capacity of every node (J/K) at node temperatures ``t``."""
        c = np.array([c0 * (1.0 + b * (ti - self.t0_c))
                      for c0, b, ti in zip(self.c_j_per_k, self.c_slope_per_k, t, strict=True)])
        for h in self.latent:
            c[h.node] += h.capacity(float(t[h.node]))
        return c

    def heater(self, power_w: float, tj_c: float) -> float:
        """Power dissipated at the junction (W) when ``power_w`` is nominal."""
        return power_w * max(0.0, 1.0 - self.power_slope_per_k * (tj_c - self.t0_c))

    def net_heat(self, t: np.ndarray, power_w: float, tref: float) -> np.ndarray:
        """Net heat flow into every node (W)."""
        q, _ = self.flows(t, tref)
        inflow = np.concatenate(([self.heater(power_w, float(t[0]))], q[:-1]))
        return inflow - q

    def flow_jacobian(self, t: np.ndarray, power_w: float, tref: float) -> np.ndarray:
        """``∂ net_heat / ∂T`` (W/K)."""
        n = self.n
        x = self._nodes(t, tref)
        q, r = self.flows(t, tref)
        dq = np.zeros((n, n + 1))  # dq_i/dx_k, x including the reference
        for i, law in enumerate(self.laws):
            dq[i, i] += 1.0 / r[i]
            dq[i, i + 1] -= 1.0 / r[i]
            if law is not None:
                dr = self.r_k_per_w[i] * law.slope(self._control(x, i))
                g = -q[i] * dr / r[i]
                if self.control == "junction":
                    dq[i, 0] += g
                else:
                    dq[i, i] += 0.5 * g
                    dq[i, i + 1] += 0.5 * g
        dq = dq[:, :n]
        jac = -dq
        jac[1:] += dq[:-1]
        if self.power_slope_per_k and self.heater(power_w, float(t[0])) > 0:
            jac[0, 0] -= power_w * self.power_slope_per_k
        return jac

    def rhs(self, t: np.ndarray, power_w: float, tref: float) -> np.ndarray:
        """``dT/dt`` of every node (K/s)."""
        return self.net_heat(t, power_w, tref) / self.capacities(t)

    def jacobian(self, t: np.ndarray, power_w: float, tref: float) -> np.ndarray:
        """Analytic ``∂(dT/dt)/∂T`` (1/s)."""
        c = self.capacities(t)
        dc = np.array([c0 * b for c0, b in zip(self.c_j_per_k, self.c_slope_per_k, strict=True)])
        for h in self.latent:
            dc[h.node] += h.capacity_slope(float(t[h.node]))
        jac = self.flow_jacobian(t, power_w, tref) / c[:, None]
        jac[np.diag_indices(self.n)] -= self.net_heat(t, power_w, tref) * dc / c ** 2
        return jac

    # -- states ---------------------------------------------------------------------------
    def steady(self, power_w: float, tref_c: float) -> np.ndarray:
        """Node temperatures (°C) in the steady state under ``power_w`` (Newton, analytic
        Jacobian, from the linear solution)."""
        x0 = tref_c + power_w * np.cumsum(np.asarray(self.r_k_per_w)[::-1])[::-1]
        sol = root(lambda t: self.net_heat(t, power_w, tref_c), x0,
                   jac=lambda t: self.flow_jacobian(t, power_w, tref_c), method="hybr",
                   options={"xtol": 1e-12})
        imbalance = np.max(np.abs(self.net_heat(sol.x, power_w, tref_c)))
        if not np.all(np.isfinite(sol.x)) or imbalance > 1e-9 * max(power_w, 1e-12):
            raise ArithmeticError(f"steady state under {power_w} W: {sol.message}")
        return sol.x

    def integrate(self, start: np.ndarray, duration_s: float, power_w: float, tref_c: float,
                  t_eval: np.ndarray | None = None, tref_rate_k_per_s: float = 0.0,
                  rtol: float = 1e-8) -> tuple[np.ndarray, np.ndarray | None]:
        """Node temperatures after ``duration_s`` at constant nominal power (and at the
        times ``t_eval``, shape ``(len(t_eval), n)``), from ``start``.

        The state integrated is the deviation from ``start`` (absolute tolerance 1e-10 K).
        """
        start = np.asarray(start, dtype=float)
        if duration_s <= 0:
            out = None if t_eval is None else np.tile(start, (len(t_eval), 1))
            return start.copy(), out

        def f(t, y):
            return self.rhs(start + y, power_w, tref_c + tref_rate_k_per_s * t)

        def jac(t, y):
            return self.jacobian(start + y, power_w, tref_c + tref_rate_k_per_s * t)

        sol = solve_ivp(f, (0.0, duration_s), np.zeros(self.n), method=self.method, jac=jac,
                        t_eval=t_eval, rtol=rtol, atol=1e-10,
                        first_step=min(duration_s, 1e-3 * min(self.time_scales())))
        if sol.status != 0:
            raise ArithmeticError(f"integration over {duration_s} s failed: {sol.message}")
        end = start + sol.y[:, -1]
        return end, None if t_eval is None else start + sol.y.T

    def time_scales(self) -> np.ndarray:
        """Time constants (s) of the linear network (``R0``, ``C0``)."""
        return self.foster()[1]

    # -- the linear network exactly --------------------------------------------------------
    def conductance(self) -> np.ndarray:
        """Nodal conductance matrix of ``R0`` (W/K), the reference eliminated."""
        g = 1.0 / np.asarray(self.r_k_per_w, dtype=float)
        mat = np.diag(g.copy())
        for i in range(self.n - 1):  # layer i joins node i and i + 1
            mat[i + 1, i + 1] += g[i]
            mat[i, i + 1] -= g[i]
            mat[i + 1, i] -= g[i]
        return mat

    def foster(self) -> tuple[np.ndarray, np.ndarray]:
        """Exact Foster form of the junction's response of the linear network (``R0``,
        ``C0``): ``Zth(t) = Σ r_k (1 − e^{−t/τ_k})``, ``τ`` descending.

        With ``C^{−1/2} G C^{−1/2} = V Λ Vᵀ`` (symmetric), ``τ_k = 1/λ_k`` and
        ``r_k = (V_{0k})² / (C_0 λ_k)``.
        """
        c = np.asarray(self.c_j_per_k, dtype=float)
        s = 1.0 / np.sqrt(c)
        lam, vec = np.linalg.eigh(s[:, None] * self.conductance() * s[None, :])
        return vec[0] ** 2 / (c[0] * lam), 1.0 / lam
