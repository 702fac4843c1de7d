"""The one network simulator: a Cauer ladder with its device effects, many at a time.

A batch holds ``B`` Cauer ladders of ``n`` nodes (node 0 the junction, layer ``i`` from node
``i`` to node ``i + 1``, the last layer to the reference, every node's heat capacity ``c_i``
to the thermal ground) and the device effects of the model, each with ``B`` parameter sets
(:mod:`spicethermal.effects.base`: a factor on each layer's resistance, heat stored at each
node beyond its linear capacity). A fit evaluates its trial points side by side in one batch;
:class:`~spicethermal.model.ThermalModel` is a batch of one.

The network, node rises ``θ`` over the reference at ``tref``, temperatures ``T = tref + θ``::

    d/dt (c_i θ_i + H_i(T_i)) = P·[i = 0] + q_{i−1} − q_i,   q_i = (θ_i − θ_{i+1}) / (R_i s_i(T))

* **steady state** (:meth:`NetworkBatch.steady`): every layer carries the whole power, so
  ``θ_i = Σ_{j ≥ i} P R_j s_j(T)``, solved by Newton's method (exact);
* **transients** (:meth:`NetworkBatch.response`): exponential steps. Over a step the network
  is linear with its resistances frozen at the step's mean temperature and each node's
  capacity at the *secant* of its stored heat between the step's ends (so the heat a band
  absorbs is conserved whatever the step), solved exactly in its modes; a predictor (the
  network at the start) and a corrector (at the mean of both ends) give the step's error,
  and a step whose error exceeds :data:`TOL_REL` of the largest rise is halved. Under power
  the state the frozen network tends to moves with its resistances; it is taken as moving
  linearly across the step, so the fast nodes, which follow it, end where it ends (held at
  the step's middle, they lag by half a step: an error of the first order, which made a
  heating transient take hundreds of steps). A linear network is one exact step;
* **PWM** (:meth:`NetworkBatch.frozen_foster`): the periodic steady state of the network
  frozen at the mean temperatures under the mean power (resistances there, capacities at the
  secant over each node's ripple), in closed form; exact for a linear ladder, quasi-static
  (first order in the ripple) otherwise. Where the junction swings by tens of kelvin (a
  strong temperature coefficient or a band crossed at a few hertz) the frozen peak is off
  by tenths of a kelvin; :class:`~spicethermal.model.ThermalModel` shoots the true periodic
  state, and the fits and comparisons add its difference as a correction
  (:func:`spicethermal.fit.forward.pwm_correction`).

A linear network's Foster form (:meth:`NetworkBatch.foster`) comes from the same modes:
``τ_k = 1/λ_k``, ``R_k = v_{0k}² / (c_0 λ_k)``.

Every response, steady state aside, goes through the modes of frozen networks, a batch at a
time: the number of those *solves* (one member's network, in its modes) and of the batched
*steps* they are done in is the simulator's work, which :mod:`~spicethermal.engines.meter`
counts; its cost is proportional to the CPU time it takes, whatever the network's order and
the effects (a model evaluation takes one step or thousands).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np

from ..core.ladder import Cauer, Foster
from ..effects.base import DeviceEffect, overrides, scalar_params
from .cauer import as_cauer
from .meter import charge

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

    from ..effects import Effect

__all__ = ["TOL_REL", "DeviceTerm", "NetworkBatch"]

#: A transient step is accepted when its predictor and corrector agree within this fraction
#: of the largest node rise (and :data:`TOL_ABS_K`).
TOL_REL = 3e-5
TOL_ABS_K = 1e-6
#: Newton iterations of the steady state, and its tolerance (fraction of the rise).
STEADY_ITER, STEADY_TOL = 40, 1e-12
#: Steps of one transient before the members still unresolved fail, the most a step may
#: grow, and the rejections in a row (a step 5^-25 shorter) after which the members that
#: still exceed the tolerance fail and the others go on.
MAX_STEPS, GROWTH, MAX_REJECTED = 20000, 4.0, 25
#: Steps of one transient after which a minority of its members can no longer hold the
#: batch's step: when fewer than half of the members still computed exceed their tolerance in
#: a step, those members fail and the others go on. A physical network's
#: transient over the records of a bundle takes a few hundred steps; a batch held far longer
#: by a few members is waiting on trial points far from any physical ladder (a fit's
#: finite-difference member with a layer of 10²⁶ K/W), which would otherwise cost the batch
#: thousands of steps for every member.
SHARED_STEPS = 1000
#: numpy's generalized ufunc behind ``linalg.eigh`` (lower triangle), when it has one.
_EIGH_LO = getattr(getattr(np.linalg, "_umath_linalg", None), "eigh_lo", None)


@dataclass(frozen=True, eq=False)
class DeviceTerm:
    """One device effect of a batch: its plugin, form and ``B`` parameter sets ``(B, 1)``."""

    plugin: DeviceEffect
    form: str
    params: Mapping[str, NDArray]

    def repeat(self, k: int) -> DeviceTerm:
        """Each parameter set repeated ``k`` times in a row (a batch ``k`` times longer)."""
        return DeviceTerm(self.plugin, self.form,
                          {n: np.repeat(v, k, axis=0) for n, v in self.params.items()})


def _eigh(s: NDArray) -> tuple[NDArray, NDArray]:
    """:func:`numpy.linalg.eigh` of a stack of real symmetric matrices (their lower triangle),
    called as its generalized ufunc when numpy exposes it: the same LAPACK routine and the
    same results, without the checks and the type dispatch of its wrapper, a tenth of a
    transient step's time on small ladders. A matrix whose eigenvalues do not converge gives
    NaN (the wrapper raised instead), which :meth:`NetworkBatch._modes` fails as a member."""
    if _EIGH_LO is None:  # pragma: no cover - another numpy
        return np.linalg.eigh(s)
    return _EIGH_LO(s, signature="d->dd")


def _reverse_cumsum(x: NDArray) -> NDArray:
    return np.flip(np.cumsum(np.flip(x, axis=-1), axis=-1), axis=-1)


class NetworkBatch:
    """``B`` Cauer ladders (``r``, ``c``: ``(B, n)``) with their device effects; transients
    accept a step within ``tol_rel`` of each member's largest rise (or ``tol_k`` kelvin, if
    larger).

    >>> net = NetworkBatch.of(Foster.from_tau([2.0, 3.0], [1e-3, 1.0]))
    >>> r, tau = net.foster()
    >>> np.round(r[0], 9).tolist(), np.round(tau[0], 9).tolist()  # fastest first
    ([2.0, 3.0], [0.001, 1.0])
    """

    def __init__(self, r: NDArray, c: NDArray, terms: Sequence[DeviceTerm] = (),
                 tol_rel: float = TOL_REL, tol_k: float = 0.0) -> None:
        self.tol_rel, self.tol_k = tol_rel, tol_k
        self.r = np.atleast_2d(np.asarray(r, dtype=float))
        self.c = np.atleast_2d(np.asarray(c, dtype=float))
        self.terms = tuple(terms)
        self.size, self.n = self.r.shape
        self._scaled = any(overrides(t.plugin, DeviceEffect.resistance_scale)
                           for t in self.terms)
        self._storing = tuple(t for t in self.terms
                              if overrides(t.plugin, DeviceEffect.stored_heat))

    @classmethod
    def of(cls, ladder: Foster | Cauer, effects: Sequence[Effect] = ()) -> NetworkBatch:
        """A batch of one: ``ladder`` (its Cauer form, exact) with the device effects of
        ``effects``."""
        cauer = as_cauer(ladder)
        terms = [DeviceTerm(e.plugin, e.form, scalar_params(e))  # type: ignore[arg-type]
                 for e in effects if isinstance(e.plugin, DeviceEffect)]
        return cls(np.array([cauer.r]), np.array([cauer.c]), terms)

    @property
    def device_effects(self) -> frozenset[tuple[str, str]]:
        """The names and forms of the batch's device effects."""
        return frozenset((t.plugin.name, t.form) for t in self.terms)

    @property
    def linear(self) -> bool:
        """True without device effects (every response in closed form)."""
        return not self.terms

    def repeat(self, k: int) -> NetworkBatch:
        """Each ladder repeated ``k`` times in a row."""
        return NetworkBatch(np.repeat(self.r, k, axis=0), np.repeat(self.c, k, axis=0),
                            [t.repeat(k) for t in self.terms], self.tol_rel, self.tol_k)

    def unique(self) -> tuple[NetworkBatch, NDArray]:
        """The distinct members (ladder and device parameters alike) and, for each member,
        its row among them: ``(batch, rows)``, so that ``batch``'s results ``[rows]`` are
        this batch's. A fit that moves only measurement effects simulates one network."""
        params = [{n: np.broadcast_to(np.asarray(v, dtype=float).reshape(-1, 1),
                                      (self.size, 1)) for n, v in t.params.items()}
                  for t in self.terms]
        keys = np.concatenate([self.r, self.c, *(v for p in params for v in p.values())],
                              axis=1)
        _, first, rows = np.unique(keys, axis=0, return_index=True, return_inverse=True)
        if first.size == self.size:
            return self, np.arange(self.size)
        return NetworkBatch(self.r[first], self.c[first],
                            [DeviceTerm(t.plugin, t.form, {n: v[first] for n, v in p.items()})
                             for t, p in zip(self.terms, params, strict=True)],
                            self.tol_rel, self.tol_k), rows.ravel()

    # -- the effects' terms ---------------------------------------------------------------
    def scale(self, theta: NDArray, tref: NDArray | float) -> NDArray:
        """Factor on every layer's resistance ``(B, n)`` at node rises ``theta``."""
        if not self._scaled:
            return np.ones_like(theta)
        t = tref + theta
        t_next = np.concatenate([t[:, 1:], np.zeros((t.shape[0], 1)) + tref], axis=1)
        layer = 0.5 * (t + t_next)
        out = np.ones_like(theta)
        for term in self.terms:
            s = term.plugin.resistance_scale(term.form, term.params, layer, t[:, :1])
            if s is not None:
                out = out * s
        return out

    def stored(self, temps: NDArray) -> tuple[NDArray, NDArray]:
        """Heat stored beyond the linear capacities and its derivative, ``(B, n)`` each."""
        h = dh = None
        for term in self._storing:
            got = term.plugin.stored_heat(term.form, term.params, temps, self.c)
            if got is not None:
                h, dh = got if h is None else (h + got[0], dh + got[1])
        if h is None:
            return np.zeros_like(temps), np.zeros_like(temps)
        return h, dh

    def _capacity(self, heat_a: tuple[NDArray, NDArray], heat_b: tuple[NDArray, NDArray],
                  dtheta: NDArray | float) -> NDArray:
        """Capacity ``(B, n)`` over a step: the linear one plus the secant of the stored heat
        between its ends (``heat_a``, ``heat_b``: :meth:`stored` there; ``dtheta`` the change
        of temperature); a member whose capacity falls to zero or below (a capacity slope too
        steep for the temperatures reached) fails in :meth:`_modes`."""
        if not self._storing:
            return self.c
        (h_a, dh_a), (h_b, dh_b) = heat_a, heat_b
        d = np.asarray(dtheta)  # (B, n) or a scalar: the where below broadcasts it
        small = np.abs(d) < 1e-9
        sec = (np.where(small, 0.5 * (dh_a + dh_b), (h_b - h_a) / np.where(small, 1.0, d))
               if small.any() else (h_b - h_a) / d)  # the same without the wheres
        return self.c + sec

    def _secant(self, t_a: NDArray, t_b: NDArray) -> NDArray:
        """:meth:`_capacity` between the temperatures ``t_a`` and ``t_b``."""
        if not self._storing:
            return self.c
        return self._capacity(self.stored(t_a), self.stored(t_b), t_b - t_a)

    # -- linear algebra of one frozen network ----------------------------------------------
    @cached_property
    def _fixed_conductances(self) -> NDArray | None:
        """The layers' conductances ``1/r`` of a batch whose resistances do not move, once,
        when every one is positive and finite (None otherwise)."""
        if self._scaled:
            return None
        g = 1.0 / self.r
        return g if g.min() > 0 and g.max() < np.inf else None

    def _modes(self, scale: NDArray, cap: NDArray) -> tuple[NDArray, NDArray, NDArray]:
        """``(λ, V, √cap)`` of ``S = cap^{-1/2} G cap^{-1/2}``: ``(B, n)``, ``(B, n, n)``;
        NaN for a member whose resistances or capacities are not positive and finite."""
        charge(self.size, self.n)
        # positive and finite (NaN fails both, min and max carry it); member by member if not
        lo, hi = cap.min(), cap.max()
        g = self._fixed_conductances  # checked once (scale is 1 without resistance effects)
        if g is None:
            g = 1.0 / (self.r * scale)
            lo, hi = np.minimum(lo, g.min()), np.maximum(hi, g.max())
        ok = None  # every member is
        if not (lo > 0 and hi < np.inf):
            ok = (np.minimum(g.min(axis=1), cap.min(axis=1)) > 0) \
                & (np.maximum(g.max(axis=1), cap.max(axis=1)) < np.inf)
            g = np.where(ok[:, None], g, 1.0)
            cap = np.where(ok[:, None], cap, 1.0)
        diag = g.copy()
        diag[:, 1:] += g[:, :-1]
        root = np.sqrt(cap)
        # eigh reads the lower triangle only: the diagonal and the band below it
        n = self.n
        s = np.zeros((self.size, n * n))
        s[:, ::n + 1] = diag / cap
        if n > 1:
            s[:, n::n + 1] = -g[:, :-1] / (root[:, :-1] * root[:, 1:])
        lam, v = _eigh(s.reshape(self.size, n, n))
        if ok is None and lam.min() > 0:
            return lam, v, root
        ok = (lam > 0).all(axis=1) & (True if ok is None else ok)
        return np.where(ok[:, None], lam, np.nan), v, root

    def foster(self, scale: NDArray | None = None,
               cap: NDArray | None = None) -> tuple[NDArray, NDArray]:
        """Foster stages ``(R, τ)``, ``(B, n)`` each, of the network (frozen at ``scale`` and
        ``cap`` when given), fastest first."""
        lam, v, root = self._modes(np.ones_like(self.r) if scale is None else scale,
                                   self.c if cap is None else cap)
        r, tau = v[:, 0, :] ** 2 / (root[:, :1] ** 2 * lam), 1.0 / lam
        return r[:, ::-1], tau[:, ::-1]

    @staticmethod
    def _frozen(modes: tuple[NDArray, NDArray, NDArray], theta: NDArray, dt: NDArray,
                power: NDArray) -> NDArray:
        """The frozen network's (``modes``, :meth:`_modes`) exact states ``(B, m, n)`` at the
        delays ``dt`` ``(m,)`` from ``theta`` at ``power`` ``(B, 1)``."""
        lam, v, root = modes
        z = np.matmul((root * theta)[:, None, :], v)  # (B, 1, n): the state in the modes
        decay = np.exp(-lam[:, None, :] * dt[None, :, None])
        if power.any():
            src = (v[:, :1, :] / root[:, :1, None]) * (power / lam)[:, None, :]
            zz = src + (z - src) * decay
        else:  # cooling: no source
            zz = z * decay
        return np.matmul(zz, np.swapaxes(v, 1, 2)) / root[:, None, :]

    @staticmethod
    def _held(modes: tuple[NDArray, NDArray, NDArray], theta: NDArray, dt: NDArray,
              q_a: NDArray, q_b: NDArray, h: float) -> NDArray:
        """The frozen network's (``modes``) states ``(B, m, n)`` at the delays ``dt``
        ``(m,)`` from ``theta`` when the state it tends to moves linearly from ``q_a`` to
        ``q_b`` ``(B, n)`` over ``h``: ``q(t) + e^{−St}(θ − q_a) − (1 − e^{−St})/(S h)
        (q_b − q_a)`` in the modes. With ``q_a = q_b`` the steady state under a constant
        power, it is :meth:`_frozen`."""
        lam, v, root = modes
        z = np.matmul((root * (theta - q_a))[:, None, :], v)  # (B, 1, n)
        dz = np.matmul((root * (q_b - q_a))[:, None, :], v)
        e = np.exp(-lam[:, None, :] * dt[None, :, None])
        zz = e * z + np.expm1(-lam[:, None, :] * dt[None, :, None]) / (lam[:, None, :] * h) * dz
        frac = (dt / h)[None, :, None]
        return (q_a[:, None, :] + frac * (q_b - q_a)[:, None, :]
                + np.matmul(zz, np.swapaxes(v, 1, 2)) / root[:, None, :])

    def _tends(self, theta: NDArray, tref: NDArray | float, power: NDArray) -> NDArray:
        """The state the network at ``theta`` tends to under ``power`` ``(B, 1)``: its
        resistances held there, ``θ_i = Σ_{j ≥ i} P R_j s_j`` (capacities play no part)."""
        return _reverse_cumsum(power * self.r * self.scale(theta, tref))

    # -- steady state ----------------------------------------------------------------------
    def steady(self, power: NDArray | float, tref: NDArray | float) -> NDArray:
        """Node rises ``(B, n)`` under constant ``power`` (W, scalar or ``(B, 1)``)."""
        p = np.broadcast_to(np.asarray(power, dtype=float), (self.size, 1))
        theta = _reverse_cumsum(p * self.r)
        if not self._scaled:
            return theta
        n = self.n
        eye = np.eye(n)
        big = self.repeat(n)
        tref_big = np.repeat(np.broadcast_to(tref, (self.size, 1)), n, axis=0) \
            if np.ndim(tref) else tref
        # each member's tolerance, of its own rise (as a transient's)
        with np.errstate(invalid="ignore"):
            top = np.maximum(np.nanmax(np.abs(theta), axis=1, initial=0.0), 1e-12)[:, None]
        for _ in range(STEADY_ITER):
            s = self.scale(theta, tref)
            f = theta - _reverse_cumsum(p * self.r * s)
            if np.all(np.isfinite(f)) and np.all(np.abs(f) <= STEADY_TOL * top):
                return theta
            charge(self.size, self.n)  # a Newton step: the members' Jacobians and solves
            delta = 1e-7 * (1.0 + np.abs(theta))
            pert = np.repeat(theta, n, axis=0) + (np.tile(eye, (self.size, 1))
                                                  * np.repeat(delta, n, axis=0))
            ds = (big.scale(pert, tref_big).reshape(self.size, n, n) - s[:, None, :]) \
                / delta[:, :, None]
            # J[i, j] = δ_ij − Σ_{k ≥ i} P r_k ∂s_k/∂θ_j
            dq = p[:, :, None] * self.r[:, None, :] * ds  # (B, j, k)
            jac = eye[None] - np.flip(np.cumsum(np.flip(np.swapaxes(dq, 1, 2), 1), 1), 1)
            ok = np.all(np.isfinite(jac), axis=(1, 2)) & np.all(np.isfinite(f), axis=1)
            jac = np.where(ok[:, None, None], jac, eye)
            step = np.linalg.solve(jac, np.where(ok[:, None], f, 0.0)[:, :, None])[:, :, 0]
            theta = np.where(ok[:, None], theta - step, np.nan)
        s = self.scale(theta, tref)
        f = theta - _reverse_cumsum(p * self.r * s)
        # a member that does not converge (thermal runaway) is NaN, the others stand
        ok = np.all(np.isfinite(f), axis=1) & (np.max(np.abs(np.nan_to_num(f, nan=np.inf)),
                                                      axis=1) <= 1e-8 * top[:, 0])
        return np.where(ok[:, None], theta, np.nan)

    # -- transients ------------------------------------------------------------------------
    def response(self, theta0: NDArray, t_s: NDArray, power: NDArray | float,
                 tref: NDArray | float) -> NDArray:
        """Node rises ``(B, N, n)`` at the sorted times ``t_s`` (s, from 0, ≥ 0) from the
        state ``theta0`` ``(B, n)`` under constant ``power`` (W, scalar or ``(B, 1)``).

        Steps grow and shrink with the predictor–corrector error (second order: a step's
        error scales as its length squared); the readings within a step are the corrector's
        frozen network at their delays, so the steps need not stop at them.
        """
        t = np.asarray(t_s, dtype=float)
        p = np.broadcast_to(np.asarray(power, dtype=float), (self.size, 1))
        if self.linear:
            return self._frozen(self._modes(np.ones_like(self.r), self.c), theta0, t, p)
        # each member's tolerance, of its own largest rise: a member far from any physical
        # ladder (a rise of 10²³ K) leaves the others' accuracy as it is
        with np.errstate(invalid="ignore"):
            top = np.fmax(np.nanmax(np.abs(theta0), axis=1, initial=0.0),
                          np.nanmax(p * np.sum(self.r, axis=1, keepdims=True), axis=1,
                                    initial=0.0))
        tol = np.maximum(np.maximum(self.tol_rel * np.maximum(top, 1e-12), TOL_ABS_K),
                         self.tol_k)
        out = np.empty((self.size, t.size, self.n))
        theta, a = np.array(theta0, dtype=float), 0.0
        k = int(np.searchsorted(t, 0.0, side="right"))
        out[:, :k] = theta[:, None, :]
        h = float(t[k]) if k < t.size else 0.0
        heat_a = self.stored(tref + theta)
        # the predictor runs on the last accepted corrector's network (at the start: the
        # network at the start state)
        guess = self._modes(self.scale(theta, tref), self._capacity(heat_a, heat_a, 0.0))
        # under power, the state the network tends to moves with its resistances: it is
        # taken as moving linearly over a step (from where it is at the start to where it is
        # at the predicted end), so that the fast nodes, which follow it, end where it ends
        # (held at the step's middle, they would lag by half a step, an error of the first
        # order); the predictor extrapolates its last step's motion
        powered = bool(np.any(p != 0)) and self._scaled
        if powered:
            q_a, slope = self._tends(theta, tref, p), np.zeros_like(theta)
        steps = rejected = 0
        while k < t.size:
            b = min(a + h, float(t[-1]))
            if b >= t[-1] * (1 - 1e-12):
                b = float(t[-1])
            span = np.array([b - a])
            pred = (self._held(guess, theta, span, q_a, q_a + slope * (b - a), b - a)
                    if powered else self._frozen(guess, theta, span, p))[:, 0]
            heat_b = self.stored(tref + pred)
            modes = self._modes(self.scale(0.5 * (theta + pred), tref),
                                self._capacity(heat_a, heat_b, pred - theta))
            inside = int(np.searchsorted(t, b, side="right"))
            at = np.concatenate((t[k:inside] - a, span))
            states = (self._held(modes, theta, at, q_a, self._tends(pred, tref, p), b - a)
                      if powered else self._frozen(modes, theta, at, p))
            err = np.abs(states[:, -1] - pred).max(axis=1) / tol  # in each one's tolerance
            err_max = float(np.fmax.reduce(err, initial=0.0))  # NaN members aside; all NaN: 0
            steps += 1
            if steps > MAX_STEPS:  # what is left does not resolve: those members fail
                out[:, k:] = np.nan
                return out
            over = err > 1.0
            if rejected >= MAX_REJECTED or (
                    steps > SHARED_STEPS and err_max > 1.0
                    and 2 * int(np.count_nonzero(over)) < int(np.count_nonzero(err == err))):
                # a member that no step short of a rounding error resolves, or a minority
                # that holds the batch past SHARED_STEPS (trial points far from any physical
                # ladder), fails; the others go on
                states[over] = np.nan
                err_max = 0.0
            ratio = math.sqrt(1.0 / err_max) if err_max > 0 else GROWTH
            if err_max <= 1.0:
                out[:, k:inside] = states[:, :-1]
                h = (b - a) * min(GROWTH, 0.9 * ratio)
                if powered:
                    q_b = self._tends(states[:, -1], tref, p)
                    q_a, slope = q_b, (q_b - q_a) / (b - a)
                theta, a, k, guess = states[:, -1], b, inside, modes
                heat_a = self.stored(tref + theta)
                rejected = 0
            else:
                h = (b - a) * max(0.2, 0.9 * ratio)
                rejected += 1
        return out

    def cooling(self, power: NDArray | float, tref: NDArray | float, t_s: NDArray,
                theta0: NDArray | None = None) -> NDArray:
        """Junction rise ``(B, N)`` at ``t_s`` after cutting ``power`` held until the steady
        state (``theta0``, :meth:`steady`, when already known)."""
        if theta0 is None:
            theta0 = self.steady(power, tref)
        if self.linear:
            r, tau = self.foster()
            p = np.broadcast_to(np.asarray(power, dtype=float), (self.size, 1))
            return p * np.einsum("bk,bnk->bn", r, np.exp(-np.asarray(t_s)[None, :, None]
                                                         / tau[:, None, :]))
        return self.response(theta0, t_s, 0.0, tref)[:, :, 0]

    # -- PWM -------------------------------------------------------------------------------
    def frozen_foster(self, power: NDArray, freq_hz: NDArray, duty: NDArray,
                      tref: NDArray) -> tuple[NDArray, NDArray]:
        """Foster stages ``(R, τ)``, ``(B, N, n)``, of the network frozen at each of ``N``
        PWM rows (power, frequency, duty, reference): resistances at the steady state under
        the mean power, capacities at the secant over each node's ripple."""
        rows = len(power)
        if self.linear:
            r, tau = self.foster()
            return (np.broadcast_to(r[:, None, :], (self.size, rows, self.n)),
                    np.broadcast_to(tau[:, None, :], (self.size, rows, self.n)))
        big = self.repeat(rows)
        p_mean = np.tile(np.asarray(power * duty, float), self.size)[:, None]
        tr = np.tile(np.asarray(tref, float), self.size)[:, None]
        theta = big.steady(p_mean, tr)
        scale = big.scale(theta, tr)
        cap = big._secant(tr + theta, tr + theta)
        if big._storing:
            # the ripple of every node in the network frozen at its mean: each mode swings
            # by its peak minus valley, seen at every node through the mode's shape
            lam, v, root = big._modes(scale, cap)
            period = np.tile(1.0 / np.asarray(freq_hz, float), self.size)[:, None]
            d = np.tile(np.asarray(duty, float), self.size)[:, None]
            pw = np.tile(np.asarray(power, float), self.size)[:, None]
            amp = pw * (v[:, 0, :] / root[:, :1]) / lam
            on, off = -np.expm1(-lam * d * period), -np.expm1(-lam * (1 - d) * period)
            swing = amp * on * off / -np.expm1(-lam * period)
            half = 0.5 * np.einsum("bij,bj->bi", np.abs(v), np.abs(swing)) / root
            cap = big._secant(tr + theta - half, tr + theta + half)
        r, tau = big.foster(scale, cap)
        return r.reshape(self.size, rows, self.n), tau.reshape(self.size, rows, self.n)
