"""Fast forward models of ``phase-change``: cooling curves with latent heat at a node, and the
ladder frozen at the mean temperature under PWM (see :mod:`spicethermal.fit.effectfit`)."""

from __future__ import annotations

import warnings
from typing import TYPE_CHECKING

import numpy as np

from ..core.errors import SimulationError
from ..core.ladder import Cauer, Foster
from ..effects import CATALOGUE, Effect, phase_change
from ..model import Network
from .budget import check_time
from .tcjunction import as_foster, tc_cooling_rise, tc_steady_scale

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import ArrayLike, NDArray

__all__ = ["band_reached", "pc_cooling_rise", "pc_frozen_ladder"]

#: Tolerances of the phase-change cooling integration.
PC_RTOL, PC_ATOL_K = 1e-7, 1e-6
def band_reached(effect: Effect, t_lo_c: float, t_hi_c: float) -> bool:
    low, high = phase_change.band(effect)
    return effect.params["latent_j"] > 0 and t_hi_c > low and t_lo_c < high


def pc_cooling_rise(ladder: Foster | Cauer, effect: Effect, tref_c: float, power_w: float,
                    t_s: ArrayLike, tc: Effect | None = None) -> NDArray:
    """Junction rise (K) after ``power_w`` is cut, with the ``phase-change`` heat capacity
    (and, if given, the ``temperature-coefficient`` effect ``tc`` as well).

    The nodal network (the one :class:`~spicethermal.model.ThermalModel` and the SPICE export
    use) with the band's capacity at its node, ``M(θ) dθ/dt = −G θ / s(Tj)``, integrated by
    LSODA with an exact rank-one inverse of ``M`` (agrees with the model's Radau integration
    to < 1 mK, 10× faster); without ``tc`` the network is linear again once the node has left
    the band, and exact modal steps finish the curve; closed form when the curve stays more
    outside the band (:func:`~spicethermal.effects.phase_change.band`; and there is no ``tc``).
    """
    from scipy.integrate import solve_ivp


    if tc is not None and tc.form != "junction":
        raise SimulationError(f"phase-change together with temperature-coefficient form "
                              f"{tc.form} has no fast forward model")
    f = as_foster(ladder)
    t = np.asarray(t_s, dtype=float)
    alpha = 0.0 if tc is None else tc.params["alpha_per_k"]
    t0 = 0.0 if tc is None else tc.params["t0_c"]
    s_ss = tc_steady_scale(f.rth, alpha, t0, tref_c, power_w) if tc is not None else 1.0
    rise0 = power_w * f.rth * s_ss
    if not band_reached(effect, tref_c, tref_c + rise0):
        if tc is not None:
            return tc_cooling_rise(ladder, alpha, t0, tref_c, power_w, t)
        return power_w * f.cooling(t)
    net = Network.of(ladder)
    g = net.conductance()
    cinv = np.linalg.inv(net.capacitance())
    p = effect.params
    node = int(p["node"])
    ce = cinv[:, node]
    b = np.zeros(net.n)
    b[0] = power_w
    theta0 = np.linalg.solve(g, b) * s_ss

    def scale(theta: NDArray) -> float:
        return max(0.05, 1.0 + alpha * (tref_c + float(theta[0]) - t0))

    capacity = CATALOGUE[effect.name].extra_capacitance

    def minv(theta: NDArray, y: NDArray) -> NDArray:
        cx = capacity(effect, node, tref_c + float(theta[node]))
        cy = cinv @ y
        return cy - cx * ce * cy[node] / (1 + cx * ce[node])

    def rhs(_t: float, theta: NDArray) -> NDArray:
        check_time()
        return minv(theta, -g @ theta / scale(theta))

    def jac(_t: float, theta: NDArray) -> NDArray:  # the resistance's own slope left out
        return np.column_stack([minv(theta, -g[:, k] / scale(theta)) for k in range(net.n)])

    t_end = float(t.max()) if t.size else 0.0
    if t_end <= 0:
        return np.full(t.shape, float(theta0[0]))
    order = np.argsort(t)
    below = phase_change.band(effect)[0]

    def left_band(_t: float, theta: NDArray) -> float:
        return tref_c + theta[node] - below

    left_band.terminal = True  # type: ignore[attr-defined]
    left_band.direction = -1  # type: ignore[attr-defined]
    with warnings.catch_warnings():  # a failed integration is reported by sol.success
        warnings.simplefilter("ignore")
        sol = solve_ivp(rhs, (0.0, t_end), theta0, method="LSODA", jac=jac, t_eval=t[order],
                        rtol=PC_RTOL, atol=PC_ATOL_K, first_step=min(f.tau) / 1000,
                        events=left_band if tc is None else None)
    if not sol.success:
        raise SimulationError(f"phase-change cooling integration failed: {sol.message}")
    out = np.empty(t.shape)
    got = np.asarray(sol.y[0]) if len(sol.t) else np.zeros(0)
    out[order[:got.size]] = got
    if got.size < t.size:  # below the band the network is linear again: exact modal steps
        from scipy.linalg import eigh

        t_exit, theta_exit = float(sol.t_events[0][0]), sol.y_events[0][0]
        lam, v = eigh(g, net.capacitance())
        z0 = np.linalg.solve(v, theta_exit)
        rest = t[order[got.size:]] - t_exit
        out[order[got.size:]] = (z0 * np.exp(-lam * rest[:, None])) @ v[0, :]
    return out


def pc_frozen_ladder(ladder: Foster | Cauer, effect: Effect, tref_c: float,
                     mean_power_w: float) -> Foster:
    """The junction's Foster equivalent of the network with the band's heat capacity frozen
    at the node's mean temperature under ``mean_power_w``.

    A heat capacity does not change a periodic state's mean (the enthalpy returns each
    period), only its ripple; this is what the PWM prediction uses when the ripple reaches
    the band (a quasi-static approximation, unlike the cooling curves).
    """
    from scipy.linalg import eigh


    net = Network.of(ladder)
    g, cm = net.conductance(), net.capacitance()
    b = np.zeros(net.n)
    b[0] = mean_power_w
    node = int(effect.params["node"])
    cm[node, node] += effect.extra_capacitance(node, tref_c + float(np.linalg.solve(g, b)[node]))
    lam, v = eigh(g, cm)
    return Foster.from_tau(v[0, :] ** 2 / lam, 1 / lam)
