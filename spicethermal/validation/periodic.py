"""PWM readings of a :class:`~spicethermal.validation.network.Network` in the exact periodic
steady state.

A train of nominal power ``P``, frequency ``f`` and duty ``D`` is on for ``D/f`` and off for
``(1 − D)/f``. The bench reads the junction after a power-off *sample window* ``w`` that
starts when an on-phase ends: at its end (``mode="end"``, ``w = 0`` is the ripple's peak) or
averaged over it (``mode="average"``).

The periodic state is the fixed point of the period map ``Φ`` (node temperatures at the start of
an on-phase → one period later), found by shooting: a chord-Newton iteration ``x ← x − (M − I)⁻¹
(Φ(x) − x)`` with ``M`` the period map of the network linearised at the steady state under the
mean power (``M = e^{J_off t_off} e^{J_on t_on}``), from that steady state (when that
linearisation does not decay over a period, as under a long pulse across a band's steep
capacity, the damped iteration below starts at once). When a step does not halve the change (a
latent-heat band that the ripple crosses makes the period map far from that linearisation),
``M`` becomes the period map's own Jacobian at the current point, by finite differences
(Newton); if that does not converge either, a damped Newton iteration on the period map's own
Jacobian starts again from the steady state. A linear network takes the closed form of its
Foster stages instead. A band with hysteresis exchanges no heat in the periodic state while the
ripple stays within its gap (:meth:`~.network.Network.pwm_network`, :func:`ripple_bound`).

>>> from spicethermal.validation.network import Network
>>> net = Network((10.0,), (1e-3,))           # τ = 10 ms
>>> round(pwm_reading(net, 1.0, 1e3, 0.5, 25.0), 6)   # 1 kHz, 50 %: ripple peak
30.124974
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import expm

from .network import Network

__all__ = ["foster_reading", "periodic_start", "pwm_reading", "ripple_bound"]

#: Shooting stops when one period changes no node by more than this (K).
SHOOT_TOL_K = 1e-7
MAX_SHOTS = 30
#: Finite-difference step (K) of the period map's Jacobian.
FD_STEP_K = 1e-4


def foster_reading(r: np.ndarray, tau: np.ndarray, power_w: float, freq_hz: float,
                   duty: float, window_s: float = 0.0, mode: str = "end") -> float:
    """Reading (rise over the reference, K) of a linear ladder given by its Foster stages
    ``r`` (K/W) and ``tau`` (s), as :func:`pwm_reading` defines it.

    >>> round(foster_reading(np.array([10.0]), np.array([1e-2]), 1.0, 1e3, 1.0), 9)
    10.0
    """
    period = 1.0 / freq_hz
    peak = power_w * r * -np.expm1(-duty * period / tau) / -np.expm1(-period / tau)
    if window_s <= 0:
        return float(peak.sum())
    if mode == "average":
        return float((peak * tau / window_s * -np.expm1(-window_s / tau)).sum())
    return float((peak * np.exp(-window_s / tau)).sum())


def ripple_bound(net: Network, power_w: float, freqs_hz, duties, node: int = 0) -> float:
    """The largest peak-to-peak swing (K) of ``node`` of the linear network (``R0``, ``C0``)
    over a PWM grid in the periodic state (exact modal solution on 400 instants per period; a
    band's capacity only lowers it).

    >>> round(ripple_bound(Network((10.0,), (1e-3,)), 1.0, [1e3], [0.5]), 6)
    0.249948
    """
    c = np.asarray(net.c_j_per_k, dtype=float)
    s = 1.0 / np.sqrt(c)
    lam, vec = np.linalg.eigh(s[:, None] * net.conductance() * s[None, :])
    w = s[node] * vec[node] * s[0] * vec[0] / lam  # rise per watt of each mode at ``node``
    tau = 1.0 / lam
    worst = 0.0
    for f, d in zip(freqs_hz, duties, strict=True):
        period = 1.0 / f
        t = np.linspace(0.0, period, 401)[:, None]
        on = d * period
        peak = power_w * w * -np.expm1(-on / tau) / -np.expm1(-period / tau)
        trough = peak * np.exp(-(period - on) / tau)
        heating = power_w * w + (trough - power_w * w) * np.exp(-np.minimum(t, on) / tau)
        cooling = peak * np.exp(-np.maximum(t - on, 0.0) / tau)
        theta = np.where(t <= on, heating, cooling).sum(axis=1)
        worst = max(worst, float(theta.max() - theta.min()))
    return worst


def periodic_start(net: Network, power_w: float, freq_hz: float, duty: float,
                   tref_c: float) -> np.ndarray:
    """Node temperatures (°C) at the start of an on-phase in the periodic steady state.

    Parameters
    ----------
    net : the network; power_w, freq_hz, duty : the train; tref_c : the reference (°C).

    Returns
    -------
    numpy.ndarray
        The fixed point of the period map (module docstring).

    Examples
    --------
    >>> from spicethermal.validation.network import Network
    >>> x = periodic_start(Network((10.0,), (1e-3,)).with_(power_slope_per_k=1e-9),
    ...                    1.0, 1e3, 0.5, 25.0)
    >>> round(float(x[0]), 5)    # closed form: 25 + 10 (1 − e^{−0.05}) e^{−0.05} / (1 − e^{−0.1})
    29.87503
    """
    period = 1.0 / freq_hz
    on, off = duty * period, (1.0 - duty) * period
    x = net.steady(power_w * duty, tref_c)
    with np.errstate(all="ignore"):
        m = (expm(net.jacobian(x, 0.0, tref_c) * off)
             @ expm(net.jacobian(x, power_w, tref_c) * on))

    def period_map(x0: np.ndarray) -> np.ndarray:
        mid, _ = net.integrate(x0, on, power_w, tref_c)
        return net.integrate(mid, off, 0.0, tref_c)[0]

    last = np.inf
    # a linearisation that grows over a period (a band's capacity slope under a long pulse)
    # is no chord: straight to the damped Newton iteration below
    chord = bool(np.all(np.isfinite(m)) and np.max(np.abs(np.linalg.eigvals(m))) < 1.0)
    step = np.linalg.inv(m - np.eye(net.n)) if chord else None
    for _ in range(MAX_SHOTS if chord else 0):
        end = period_map(x)
        change = end - x
        size = float(np.max(np.abs(change)))
        if size < SHOOT_TOL_K:
            return x
        if size > 0.5 * last:  # the chord stalls: Newton on the period map's own Jacobian
            m = np.column_stack([(period_map(x + FD_STEP_K * e) - end) / FD_STEP_K
                                 for e in np.eye(net.n)])
            step = np.linalg.inv(m - np.eye(net.n))
        last = size
        x = x - step @ change
    # the chord wandered (a wide band the ripple crosses at its sharp edge): damped Newton on
    # the period map's own Jacobian from the steady state
    x = net.steady(power_w * duty, tref_c)
    for _ in range(MAX_SHOTS):
        end = period_map(x)
        change = end - x
        size = float(np.max(np.abs(change)))
        if size < SHOOT_TOL_K:
            return x
        m = np.column_stack([(period_map(x + FD_STEP_K * e) - end) / FD_STEP_K
                             for e in np.eye(net.n)])
        step = np.linalg.solve(m - np.eye(net.n), change)
        damp = 1.0
        while damp > 1e-3 and np.max(np.abs(period_map(x - damp * step) - x + damp * step)) \
                >= size:
            damp /= 2.0
        x = x - damp * step
    raise ArithmeticError(f"shooting at {freq_hz} Hz, duty {duty}: no periodic state after "
                          f"{MAX_SHOTS} periods and as many Newton steps (last change "
                          f"{size:.3g} K)")


def pwm_reading(net: Network, power_w: float, freq_hz: float, duty: float, tref_c: float,
                window_s: float = 0.0, mode: str = "end") -> float:
    """What the bench reads (°C) in the periodic steady state (module docstring).

    Parameters
    ----------
    net : the network; power_w, freq_hz, duty : the train; tref_c : the reference (°C).
    window_s, mode : the sample window and how it is read (``"end"`` or ``"average"``).

    Returns
    -------
    float
        The reading in °C.
    """
    if mode not in ("end", "average"):
        raise ValueError(f"mode {mode!r}: expected 'end' or 'average'")
    net = net.pwm_network()
    if net.is_linear:
        r, tau = net.foster()
        return tref_c + foster_reading(r, tau, power_w, freq_hz, duty, window_s, mode)
    x = periodic_start(net, power_w, freq_hz, duty, tref_c)
    peak, _ = net.integrate(x, duty / freq_hz, power_w, tref_c)
    if window_s <= 0:
        return float(peak[0])
    if mode == "end":
        return float(net.integrate(peak, window_s, 0.0, tref_c)[0][0])
    t = np.linspace(0.0, window_s, 201)
    _, path = net.integrate(peak, window_s, 0.0, tref_c, t_eval=t)
    return float(np.trapezoid(path[:, 0], t) / window_s)
