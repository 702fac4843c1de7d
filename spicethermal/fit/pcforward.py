"""Fast forward models of ``phase-change``: cooling curves with latent heat at a node, and the
ladder frozen at the mean temperature under PWM (see :mod:`spicethermal.fit.effectfit`)."""

from __future__ import annotations

from functools import lru_cache
from typing import TYPE_CHECKING

import numpy as np

from ..core.errors import SimulationError
from ..core.ladder import Cauer, Foster
from ..effects import Effect, phase_change
from ..model import Network
from .budget import PC_STEP_S, check_time
from .lsoda import lsoda_until
from .tcforward import as_cauer
from .tcjunction import as_foster, tc_cooling_rise, tc_steady_scale

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import ArrayLike, NDArray

__all__ = ["band_reached", "pc_cooling_rise", "pc_frozen_ladder"]

#: Tolerances of the phase-change cooling integration.
PC_RTOL, PC_ATOL_K = 1e-7, 1e-6
#: The PWM model's band capacity (:func:`pc_frozen_ladder`): at most this many secant steps,
#: stopped at this relative change, and none for a swing below this (K).
SECANT_STEPS, SECANT_RTOL, SECANT_MIN_SWING_K = 8, 1e-4, 1e-9
#: Ladders whose nodal matrices are kept (:func:`_nodal`).
CACHE_SIZE = 64


def band_reached(effect: Effect, t_lo_c: float, t_hi_c: float) -> bool:
    low, high = phase_change.band(effect)
    return effect.params["latent_j"] > 0 and t_hi_c > low and t_lo_c < high


def band_ladder(ladder: Foster | Cauer, effect: Effect) -> Foster | Cauer:
    """The ladder whose nodal network holds the band: ``ladder`` itself at the junction, its
    exact Cauer equivalent (physical layers) at a node further out."""
    return as_cauer(ladder) if effect.physical_nodes else ladder


def pc_cooling_rise(ladder: Foster | Cauer, effect: Effect, tref_c: float, power_w: float,
                    t_s: ArrayLike, tc: Effect | None = None) -> NDArray:
    """Junction rise (K) after ``power_w`` is cut, with the ``phase-change`` heat capacity
    (and, if given, the ``temperature-coefficient`` effect ``tc`` as well).

    The nodal network (the one :class:`~spicethermal.model.ThermalModel` and the SPICE export
    use) with the band's capacity at its node, ``M(θ) dθ/dt = −G θ / s(Tj)``, integrated by
    LSODA (:func:`~spicethermal.fit.lsoda.lsoda_until`) with an exact rank-one inverse of
    ``M`` (agrees with the model's Radau integration to < 1 mK, 10× faster); without ``tc``
    the network is linear again once the node has left the band, and exact modal steps finish
    the curve from the first reading below it; closed form when the curve stays outside the
    band (:func:`~spicethermal.effects.phase_change.band`; and there is no ``tc``).
    """

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
    net = Network.of(band_ladder(ladder, effect))
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

    capacity = phase_change.capacity_law(effect)
    ce_node, minus_g = float(ce[node]), -g

    def minv(theta: NDArray, y: NDArray) -> NDArray:
        cx = capacity(tref_c + float(theta[node]))
        cy = cinv @ y
        return cy - cx * ce * cy[node] / (1 + cx * ce_node)

    def rhs(_t: float, theta: NDArray) -> NDArray:
        check_time(PC_STEP_S)
        flow = minus_g @ theta
        return minv(theta, flow if tc is None else flow / scale(theta))

    def jac(_t: float, theta: NDArray) -> NDArray:  # the resistance's own slope left out
        return np.column_stack([minv(theta, -g[:, k] / scale(theta)) for k in range(net.n)])

    t_end = float(t.max()) if t.size else 0.0
    if t_end <= 0:
        return np.full(t.shape, float(theta0[0]))
    order = np.argsort(t)
    below = phase_change.band(effect)[0]

    def left_band(theta: NDArray) -> bool:
        return tc is None and tref_c + float(theta[node]) < below

    got, theta_exit = lsoda_until(rhs, jac, theta0, t[order], min(f.tau) / 1000, PC_RTOL,
                                  PC_ATOL_K, "phase-change cooling", left_band)
    out = np.empty(t.shape)
    out[order[:got.size]] = got
    if got.size < t.size:  # below the band the network is linear again: exact modal steps
        from scipy.linalg import eigh

        lam, v = eigh(g, net.capacitance())
        z0 = np.linalg.solve(v, theta_exit)
        rest = t[order[got.size:]] - t[order[got.size - 1]]
        out[order[got.size:]] = (z0 * np.exp(-lam * rest[:, None])) @ v[0, :]
    return out


def pc_frozen_ladder(ladder: Foster | Cauer, effect: Effect, tref_c: float, power_w: float,
                     freq_hz: float, duty: float) -> Foster:
    """The junction's Foster equivalent of the network under a PWM train (``power_w`` on for
    ``duty`` of each period) with the band's heat capacity frozen at the heat the node's swing
    in the periodic state exchanges.

    A heat capacity does not change a periodic state's mean (the enthalpy returns each
    period), only its ripple; this is what the PWM prediction uses when the ripple reaches
    the band (a quasi-static approximation, unlike the cooling curves). The capacity is the
    secant ``(H(T_hi) − H(T_lo)) / (T_hi − T_lo)`` of the band's heat ``H`` over the node's
    swing (its temperatures at the ends of the on and off phases), which this capacity sets in
    turn: a fixed point from the tangent at the mean temperature, :data:`SECANT_STEPS` at
    most. The swing takes the heat the band gives and takes back each period; the tangent at
    the mean is right only for a swing much narrower than the band (it overstates the
    capacity of a swing across a narrow band and understates one beside it).
    """
    node = int(effect.params["node"])
    g, cm, z = _nodal(band_ladder(ladder, effect))
    t_mean = tref_c + power_w * duty * float(z[node])
    extra = effect.extra_capacitance(node, t_mean)
    period = 1.0 / freq_hz
    for _ in range(SECANT_STEPS):
        lam, v = _modes(g, cm, node, extra)
        gain = v[node, :] * v[0, :] / lam * power_w  # each mode's share of the node's rise
        peak = gain * -np.expm1(-lam * duty * period) / -np.expm1(-lam * period)
        trough = peak * np.exp(-lam * (1.0 - duty) * period)
        ends = t_mean + np.array([peak.sum(), trough.sum()]) - gain.sum() * duty
        lo, hi = float(ends.min()), float(ends.max())
        if hi - lo <= SECANT_MIN_SWING_K:
            break
        secant = (effect.latent_heat(node, hi) - effect.latent_heat(node, lo)) / (hi - lo)
        done = abs(secant - extra) <= SECANT_RTOL * max(secant, extra, 1e-300)
        extra = secant
        if done:
            break
    lam, v = _modes(g, cm, node, extra)
    return Foster.from_tau(v[0, :] ** 2 / lam, 1 / lam)


@lru_cache(maxsize=CACHE_SIZE)
def _nodal(ladder: Foster | Cauer) -> tuple[NDArray, NDArray, NDArray]:
    """The ladder's nodal ``G`` and ``C`` and the steady rise of every node per watt at the
    junction (read-only, kept: every row of a PWM grid freezes the same ladder)."""
    net = Network.of(ladder)
    g, cm = net.conductance(), net.capacitance()
    unit = np.zeros(net.n)
    unit[0] = 1.0
    out = (g, cm, np.linalg.solve(g, unit))
    for a in out:
        a.flags.writeable = False
    return out


def _modes(g: NDArray, cm: NDArray, node: int, extra: float) -> tuple[NDArray, NDArray]:
    """Eigenvalues and ``C``-orthonormal modes of ``G v = λ C v`` with ``extra`` (J/K) added at
    ``node`` (by the Cholesky factor of ``C``, as LAPACK's generalised solver does; small
    matrices, so numpy's call costs less than scipy's)."""
    c = cm.copy()
    c[node, node] += extra
    li = np.linalg.inv(np.linalg.cholesky(c))
    lam, u = np.linalg.eigh(li @ g @ li.T)
    return lam, li.T @ u
