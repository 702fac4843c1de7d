"""Fast forward models of the ``temperature-coefficient`` forms (what the fits evaluate).

Form ``junction`` (every resistance on the junction temperature): closed forms in
:mod:`spicethermal.fit.tcjunction`.

Local forms (``local``, ``power-law``: each Cauer layer on its own mean temperature, a
subset of layers, capacities rising with T; see
:mod:`spicethermal.effects.temperature_coefficient`), on the ladder's exact Cauer equivalent
(a Foster ladder's inner nodes are not physical):

* steady state, exact: in a chain fed at the junction every layer carries the whole power,
  so from the reference inwards each layer's drop solves the scalar equation
  ``Δ = P R0 f(T_{i+1} + Δ/2)`` — linear for the linear law, Newton for the power law
  (:func:`local_steady_nodes`);
* cooling curve: ``C_i(T_i) dθ_i/dt = q_{i−1} − q_i`` integrated by a stiff solver (BDF) with
  the analytic tridiagonal Jacobian (:func:`local_cooling_rise`);
* PWM: every layer's R frozen at its mean temperature and every node's C at its temperature in
  the steady state under the mean power (:func:`local_frozen_ladder`, quasi-static like the
  junction form; checked against the shooting solution of
  :class:`~spicethermal.model.ThermalModel` in the tests).
"""

from __future__ import annotations

import contextvars
import math
import warnings
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from functools import lru_cache
from typing import TYPE_CHECKING

import numpy as np

from ..core.errors import SimulationError
from ..core.ladder import Cauer, Foster
from ..effects import Effect
from ..effects.temperature_coefficient import FLOOR, law, law_slope, size
from .tcjunction import as_foster, tc_cooling_rise, tc_frozen_ladder, tc_steady_scale

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import ArrayLike, NDArray

#: Tolerances of the cooling integration of the local forms (relative; absolute in K).
RTOL, ATOL_K = 1e-6, 1e-5
#: Integrated cooling curves kept (a fit that holds the ladder and the coefficient, such as
#: the fits of other effects after this one, asks for the same curves again and again).
CACHE_SIZE = 64
_SHARED: dict[tuple, NDArray] = {}
_CACHE: contextvars.ContextVar[dict[tuple, NDArray] | None] = contextvars.ContextVar(
    "tc_cache", default=None)
#: Right-hand-side evaluations allowed to one cooling integration (a few hundred are typical):
#: past it the trial point fails instead of crawling.
MAX_RHS = 5000


def as_cauer(ladder: Foster | Cauer) -> Cauer:
    """``ladder`` as a Cauer ladder with a heat capacity at every node (exact).

    Parameters
    ----------
    ladder : Foster or Cauer
        The ladder.

    Returns
    -------
    Cauer
        Its Cauer form (zero capacities merged,
        :meth:`~spicethermal.core.ladder.Cauer.with_capacitances`).
    """
    if isinstance(ladder, Cauer):
        return ladder.with_capacitances()
    return _foster_as_cauer(ladder)


@lru_cache(maxsize=CACHE_SIZE)
def _foster_as_cauer(ladder: Foster) -> Cauer:
    """:func:`as_cauer` of a Foster ladder, kept: the exact conversion (rational arithmetic)
    was three quarters of a PWM prediction with a local form, once per row of the grid on
    the same ladder."""
    return ladder.to_cauer().with_capacitances()


# --------------------------------------------------------------------------------------------
# local forms
# --------------------------------------------------------------------------------------------
def _mask(effect: Effect, n: int) -> NDArray:
    """1.0 on the layers (and nodes) of the effect's subset."""
    k = np.arange(n)
    return ((k >= effect.params["first_layer"]) & (k <= effect.params["last_layer"])) * 1.0


def local_steady_nodes(ladder: Foster | Cauer, effect: Effect, tref_c: float,
                       power_w: float) -> NDArray:
    """Node rises (K over ``tref_c``) of the Cauer ladder under constant ``power_w`` with a
    local form of ``effect`` (exact; module docstring).

    Parameters
    ----------
    ladder : Foster or Cauer
        The ladder at ``t0_c`` (converted to Cauer).
    effect : Effect
        A ``temperature-coefficient`` effect of form ``local`` or ``power-law``.
    tref_c, power_w : float
        Reference temperature (°C) and power (W).

    Returns
    -------
    ndarray
        Rise of every node, junction first.

    One layer of 10 K/W at α = 0.01/K and 2 W: ``Δ = 20 (1 + 0.01 Δ/2)``, so ``Δ = 20/0.9``:

    >>> e = Effect.create("temperature-coefficient", "local", alpha_per_k=0.01)
    >>> round(float(local_steady_nodes(Cauer([10.0], [1.0]), e, 25.0, 2.0)[0]), 9)
    22.222222222
    """
    cauer = as_cauer(ladder)
    r0 = np.asarray(cauer.r)
    mask = _mask(effect, cauer.order)
    p = effect.params
    theta = np.zeros(cauer.order + 1)
    for i in range(cauer.order - 1, -1, -1):
        lin = power_w * r0[i]
        if not mask[i] or lin == 0:
            theta[i] = theta[i + 1] + lin
            continue
        t_out = tref_c + theta[i + 1]
        if effect.form == "local":
            a = p["alpha_per_k"]
            den = 1 - 0.5 * a * lin
            d = lin * (1 + a * (t_out - p["t0_c"])) / den if den > 0 else math.inf
            if not (math.isfinite(d) and d > 0):
                raise SimulationError(f"temperature coefficient {a:g}/K at {power_w:g} W has "
                                      f"no steady state (thermal runaway)")
            if float(law(effect, t_out + 0.5 * d)) <= FLOOR:  # on the clipped branch
                d = lin * FLOOR
        else:
            d = lin * float(law(effect, t_out))
            for _ in range(60):
                g = d - lin * float(law(effect, t_out + 0.5 * d))
                dg = 1 - 0.5 * lin * float(law_slope(effect, t_out + 0.5 * d))
                if dg <= 0:
                    raise SimulationError(f"the {effect.form} law at {power_w:g} W has no "
                                          f"steady state (runaway)")
                d -= g / dg
                if abs(g) <= 1e-13 * abs(d):
                    break
            else:
                raise SimulationError(f"the {effect.form} law's steady state did not converge")
        theta[i] = theta[i + 1] + d
    return theta[:-1]


def _local_system(cauer: Cauer, effect: Effect, tref_c: float) -> tuple[Callable, Callable]:
    """``state(θ) -> (R_i, C_i, dR_i/dT, dC_i/dT)`` and ``rhs(θ) -> dθ/dt`` (power off) of
    the local forms."""
    r0, c0 = np.asarray(cauer.r), np.asarray(cauer.c)
    mask = _mask(effect, cauer.order)
    beta, t0 = effect.params["c_slope_per_k"], effect.params["t0_c"]

    def state(theta: NDArray) -> tuple[NDArray, NDArray, NDArray, NDArray]:
        ends = tref_c + np.append(theta, 0.0)
        t_layer = 0.5 * (ends[:-1] + ends[1:])
        r = r0 * np.where(mask > 0, law(effect, t_layer), 1.0)
        c = c0 * (1 + mask * beta * (ends[:-1] - t0))
        if np.any(c <= 0):
            raise SimulationError("a heat capacity falls to zero or below (capacity slope too "
                                  "steep for the temperatures reached)")
        dr = r0 * mask * law_slope(effect, t_layer)  # dR_i/dT of the layer
        return r, c, dr, c0 * mask * beta

    def rhs(theta: NDArray) -> NDArray:
        r, c, _, _ = state(theta)
        q = (theta - np.append(theta[1:], 0.0)) / r
        return (np.append(0.0, q[:-1]) - q) / c

    return state, rhs


def _local_jacobian(state: Callable, theta: NDArray) -> NDArray:
    """Analytic Jacobian of the local forms' right-hand side (tridiagonal)."""
    n = theta.size
    r, c, dr, dc = state(theta)
    diff = theta - np.append(theta[1:], 0.0)
    q = diff / r
    # dq_i/dθ_i and dq_i/dθ_{i+1}: 1/R ∓ ... the mean temperature moves by half of each
    corr = 0.5 * q * dr / r
    dq_self = 1 / r - corr
    dq_next = -1 / r - corr
    jac = np.zeros((n, n))
    for i in range(n):
        if i > 0:  # + q_{i-1}
            jac[i, i - 1] += dq_self[i - 1]
            jac[i, i] += dq_next[i - 1]
        jac[i, i] -= dq_self[i]
        if i + 1 < n:
            jac[i, i + 1] -= dq_next[i]
    inflow = np.append(0.0, q[:-1]) - q
    jac = jac / c[:, None]
    jac[np.arange(n), np.arange(n)] -= inflow * dc / c ** 2
    return jac


def local_cooling_rise(ladder: Foster | Cauer, effect: Effect, tref_c: float, power_w: float,
                       t_s: ArrayLike, check: Callable[[], None] | None = None) -> NDArray:
    """Junction rise (K) after ``power_w`` is cut, from the steady state, with a local form.

    Parameters
    ----------
    ladder : Foster or Cauer
        The ladder at ``t0_c`` (converted to Cauer).
    effect : Effect
        A local form of ``temperature-coefficient``.
    tref_c, power_w : float
        Reference temperature (°C) and the power before the cut (W).
    t_s : array_like
        Times after the cut (s).
    check : callable, optional
        Called at every evaluation (a time budget raises from it).

    Returns
    -------
    ndarray
        Junction rise over ``tref_c`` at ``t_s``.

    Without a coefficient it is the linear cooling curve:

    >>> f = Foster.from_tau([1.0, 2.0], [1e-3, 1.0])
    >>> e = Effect.create("temperature-coefficient", "local")
    >>> bool(np.allclose(local_cooling_rise(f, e, 25.0, 1.0, [0.01, 1.0]),
    ...                  f.cooling([0.01, 1.0]), atol=1e-4))
    True
    """
    from scipy.integrate import solve_ivp

    cauer = as_cauer(ladder)
    t = np.asarray(t_s, dtype=float)
    theta0 = local_steady_nodes(cauer, effect, tref_c, power_w)
    if t.size == 0 or float(t.max()) <= 0:
        return np.full(t.shape, float(theta0[0]))
    state, rhs = _local_system(cauer, effect, tref_c)

    calls = 0

    def fun(_t: float, theta: NDArray) -> NDArray:
        nonlocal calls
        calls += 1
        if calls > MAX_RHS:
            raise SimulationError(f"temperature-coefficient cooling integration needs more "
                                  f"than {MAX_RHS} evaluations (parameters too wild)")
        if check is not None:
            check()
        return rhs(theta)

    def jac(_t: float, theta: NDArray) -> NDArray:
        return _local_jacobian(state, theta)

    order = np.argsort(t)
    tau_min = float(np.min(np.asarray(cauer.r) * np.asarray(cauer.c)))
    with warnings.catch_warnings():  # a failed integration is reported by sol.success
        warnings.simplefilter("ignore")
        sol = solve_ivp(fun, (0.0, float(t.max())), theta0, method="BDF", jac=jac,
                        t_eval=t[order], rtol=RTOL,
                        atol=ATOL_K * max(1e-3, float(theta0[0])) / 10,
                        first_step=min(tau_min / 100, float(t.max()) / 10))
    if not sol.success or sol.y.shape[1] != t.size:
        raise SimulationError(f"temperature-coefficient cooling integration failed: "
                              f"{sol.message}")
    out = np.empty(t.shape)
    out[order] = sol.y[0]
    return out


def local_frozen_ladder(ladder: Foster | Cauer, effect: Effect, tref_c: float,
                        mean_power_w: float) -> Foster:
    """The junction's Foster equivalent of the Cauer ladder with every layer's R frozen at
    its mean temperature and every node's C at its temperature, in the steady state under
    ``mean_power_w`` (local forms).

    Parameters
    ----------
    ladder : Foster or Cauer
        The ladder at ``t0_c``.
    effect : Effect
        A local form of ``temperature-coefficient``.
    tref_c, mean_power_w : float
        Reference temperature (°C) and mean power (W).

    Returns
    -------
    Foster
        The frozen ladder.

    >>> e = Effect.create("temperature-coefficient", "local", alpha_per_k=0.01)
    >>> round(local_frozen_ladder(Cauer([10.0], [1.0]), e, 25.0, 2.0).rth, 6)
    11.111111
    """
    from scipy.linalg import eigh

    cauer = as_cauer(ladder)
    theta = local_steady_nodes(cauer, effect, tref_c, mean_power_w)
    state, _ = _local_system(cauer, effect, tref_c)
    r, c, _, _ = state(theta)
    _, g = Cauer(r, c).state_matrices()
    lam, v = eigh(g, np.diag(c))
    return Foster.from_tau(v[0, :] ** 2 / lam, 1 / lam)


# --------------------------------------------------------------------------------------------
# every form
# --------------------------------------------------------------------------------------------
def tc_cooling(ladder: Foster | Cauer, effect: Effect, tref_c: float, power_w: float,
               t_s: ArrayLike, check: Callable[[], None] | None = None) -> NDArray:
    """Junction rise (K) after ``power_w`` is cut, for any form of ``effect``.

    Parameters
    ----------
    ladder : Foster or Cauer
        The ladder at ``t0_c``.
    effect : Effect
        A ``temperature-coefficient`` effect.
    tref_c, power_w : float
        Reference temperature (°C) and the power before the cut (W).
    t_s : array_like
        Times after the cut (s).
    check : callable, optional
        Time-budget check for the integrated forms.

    Returns
    -------
    ndarray
        Junction rise over ``tref_c``.

    >>> e = Effect.create("temperature-coefficient", alpha_per_k=0.0)
    >>> float(tc_cooling(Foster.from_tau([2.0], [1.0]), e, 25.0, 1.0, [0.0])[0])
    2.0
    """
    if effect.form == "junction":
        return tc_cooling_rise(ladder, effect.params["alpha_per_k"], effect.params["t0_c"],
                               tref_c, power_w, t_s)
    if is_neutral(effect):  # switched off: the linear closed form, exactly
        return power_w * as_foster(ladder).cooling(t_s)
    t = np.asarray(t_s, dtype=float)
    f = as_foster(ladder)
    key = (f.r, f.tau, effect.form, tuple(effect.params.values()), float(tref_c),
           float(power_w), t.tobytes())
    cache = _CACHE.get()
    cache = _SHARED if cache is None else cache
    hit = cache.get(key)
    if hit is None:
        hit = local_cooling_rise(ladder, effect, tref_c, power_w, t, check)
        if len(cache) >= CACHE_SIZE:
            cache.pop(next(iter(cache)))
        cache[key] = hit
    return hit.copy()


@contextmanager
def own_cache() -> Iterator[None]:
    """A cache of integrated cooling curves of the block's own, empty at its start (the
    diagnosis's): what it computes, and so how much of its budget's work each fit spends, does
    not depend on what ran before it in the process.

    >>> with own_cache():
    ...     _CACHE.get() == {}
    True
    """
    token = _CACHE.set({})
    try:
        yield
    finally:
        _CACHE.reset(token)


def is_neutral(effect: Effect) -> bool:
    """True when ``effect`` changes nothing (no α, no exponent, no capacity slope).

    Parameters
    ----------
    effect : Effect
        A ``temperature-coefficient`` effect.

    Returns
    -------
    bool
        Whether every resistance and capacity is constant.

    >>> is_neutral(Effect.create("temperature-coefficient", "power-law"))
    True
    """
    p = effect.params
    return size(effect) == 0 and (effect.form == "junction" or p["c_slope_per_k"] == 0)


def tc_frozen(ladder: Foster | Cauer, effect: Effect, tref_c: float,
              mean_power_w: float) -> Foster:
    """The ladder frozen at the steady state under ``mean_power_w``, for any form.

    Parameters
    ----------
    ladder : Foster or Cauer
        The ladder at ``t0_c``.
    effect : Effect
        A ``temperature-coefficient`` effect.
    tref_c, mean_power_w : float
        Reference temperature (°C) and mean power (W).

    Returns
    -------
    Foster
        What the PWM prediction uses.

    >>> e = Effect.create("temperature-coefficient", alpha_per_k=0.01)
    >>> tc_frozen(Foster.from_tau([10.0], [1.0]), e, 25.0, 5.0).rth
    20.0
    """
    if effect.form == "junction":
        return tc_frozen_ladder(ladder, effect.params["alpha_per_k"], effect.params["t0_c"],
                                tref_c, mean_power_w)
    if is_neutral(effect):
        return as_foster(ladder)
    return local_frozen_ladder(ladder, effect, tref_c, mean_power_w)


def tc_steady_rise(ladder: Foster | Cauer, effect: Effect, tref_c: float,
                   power_w: float) -> float:
    """Junction rise (K) under constant ``power_w``, for any form.

    Parameters
    ----------
    ladder : Foster or Cauer
        The ladder at ``t0_c``.
    effect : Effect
        A ``temperature-coefficient`` effect.
    tref_c, power_w : float
        Reference temperature (°C) and power (W).

    Returns
    -------
    float
        The self-consistent junction rise.

    >>> e = Effect.create("temperature-coefficient", alpha_per_k=0.01)
    >>> tc_steady_rise(Foster.from_tau([10.0], [1.0]), e, 25.0, 5.0)
    100.0
    """
    if effect.form == "junction":
        f = as_foster(ladder)
        return power_w * f.rth * tc_steady_scale(f.rth, effect.params["alpha_per_k"],
                                                 effect.params["t0_c"], tref_c, power_w)
    return float(local_steady_nodes(ladder, effect, tref_c, power_w)[0])
