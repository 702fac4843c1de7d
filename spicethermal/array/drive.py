"""The fastest safe change of an array's pattern: per-cell PWM duties under coupled limits.

A *transition* starts from any state of the array (cold, or holding the previous pattern) and
must bring every dot that is up in the new pattern into the band ``target ± tol`` (its heater
temperature, period average) and keep it there, while

* no cell's junction peak (the end of its on-phase, PWM ripple included) exceeds ``t_max``;
* no dot that must stay down reaches ``actuation − margin`` because of its neighbours (a dot
  that was up and goes down cools, its heater off, and is held to that once it is below).

Method: the single-actuator drive's greedy profile (:mod:`spicethermal.drive.profile`),
generalised to coupled cells. On a grid of whole PWM periods (fine at first, growing in
proportion to the elapsed time) each step chooses the duties of the raised cells by a small
linear programme — maximise their sum — under two families of linear constraints on a
look-ahead of the averaged network: (1) no raised dot overshoots its target even if every
heater were cut after the step (its free response, coupling included), (2) no lowered dot
crosses its limit if the hold followed the step. The junction peak (the period average at the
step's end plus the cell's periodic ripple, :meth:`.dynamics.ArrayDynamics.ripple`) bounds
each duty. The profile switches to the hold — the duties that keep the raised dots exactly at
the target with every coupling counted (:meth:`.dynamics.ArrayDynamics.hold_duties`) — as soon
as the hold keeps every raised dot in the band and every lowered one below its limit forever.
The whole schedule is then checked on every on-phase with the exact switched map
(:class:`.dynamics.SwitchedMap`); an excess tightens the peak limit for a new pass, as the
single drive's margin iteration does.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..core.errors import DataFormatError, SimulationError
from .dynamics import ArrayDynamics, SwitchedMap

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

__all__ = ["Limits", "Transition", "plan_transition"]

#: Steps grow by this fraction of the elapsed periods (at least one period).
GROWTH = 0.05
#: The exact switched peak is brought this far under the limit by the margin iteration, K.
SAFETY_K = 2e-3
#: Look-ahead points (the step's end, then logarithmic to ten slowest time constants).
LOOK_POINTS = 40
#: Periods of a step sampled for the exact peak (the first ones, then spread).
PEAK_SAMPLES = 8

#: One step of a profile: ``(first_period, periods, duties)``.
ArrayStep = tuple[int, int, tuple[float, ...]]


@dataclass(frozen=True)
class Limits:
    """What a pattern change must respect (°C unless stated).

    Attributes
    ----------
    ambient_c : float
        The reference temperature.
    t_max_c : float
        Junction limit of every cell, on the PWM peak.
    target_c, tol_k : float
        A raised dot settles within ``target_c ± tol_k`` (period average of its heater).
    actuation_c : float
        A dot is up at or above this temperature (the cavity's boiling point).
    margin_k : float
        A lowered dot must stay below ``actuation_c − margin_k``.
    p_max_w : float
        Heater power when on, W.
    f_pwm_hz : float
        PWM frequency, Hz.
    """

    ambient_c: float
    t_max_c: float
    target_c: float
    tol_k: float
    actuation_c: float
    margin_k: float
    p_max_w: float
    f_pwm_hz: float

    def __post_init__(self) -> None:
        for name, value in self.__dict__.items():
            if not (isinstance(value, int | float) and math.isfinite(value)):
                raise DataFormatError(f"array drive: {name} = {value!r} must be a finite number")
        if self.tol_k <= 0 or self.margin_k < 0 or self.p_max_w <= 0 or self.f_pwm_hz <= 0:
            raise DataFormatError("array drive: tol, power and PWM frequency must be positive, "
                                  "the margin not negative")
        if not self.ambient_c < self.actuation_c - self.margin_k:
            raise DataFormatError(f"array drive: the actuation temperature "
                                  f"{self.actuation_c:g} °C (less the margin) must be above the "
                                  f"ambient {self.ambient_c:g} °C")
        if not self.actuation_c <= self.target_c - self.tol_k:
            raise DataFormatError(f"array drive: the band {self.target_c:g} ± {self.tol_k:g} °C "
                                  f"must lie at or above the actuation temperature "
                                  f"{self.actuation_c:g} °C (a raised dot must be up)")
        if not self.target_c < self.t_max_c:
            raise DataFormatError(f"array drive: target {self.target_c:g} °C must be below "
                                  f"t_max {self.t_max_c:g} °C")

    @property
    def lim_k(self) -> float:
        """Junction limit as a rise, K."""
        return self.t_max_c - self.ambient_c

    @property
    def tgt_k(self) -> float:
        """Target as a rise, K."""
        return self.target_c - self.ambient_c

    @property
    def down_k(self) -> float:
        """A lowered dot's limit as a rise, K."""
        return self.actuation_c - self.margin_k - self.ambient_c


@dataclass(frozen=True)
class Transition:
    """The drive of one pattern change.

    Attributes
    ----------
    up : tuple of bool
        Which cells are raised by it.
    steps : tuple of ArrayStep
        ``(first_period, periods, duties)`` before the hold.
    hold : tuple of float
        The duties that hold the pattern, after the steps, forever.
    margin_k : float
        How far the averaged-plus-ripple peak limit had to be tightened for the exact
        switched peaks to respect ``t_max``.
    """

    up: tuple[bool, ...]
    steps: tuple[ArrayStep, ...]
    hold: tuple[float, ...]
    margin_k: float = 0.0

    def schedule(self, period: float) -> tuple[tuple[float, tuple[float, ...]], ...]:
        """``((t_s, duties), ...)`` from the transition's start (equal neighbours merged; the
        last piece, the hold, lasts forever).

        Parameters
        ----------
        period : float
            PWM period, s.

        Returns
        -------
        tuple of (float, tuple of float)
        """
        end = self.steps[-1][0] + self.steps[-1][1] if self.steps else 0
        out: list[tuple[float, tuple[float, ...]]] = []
        for t, d in [*((f * period, s) for f, _, s in self.steps), (end * period, self.hold)]:
            if not out or out[-1][1] != d:
                out.append((t, d))
        return tuple(out)


def _feasible_hold(dyn: ArrayDynamics, up: NDArray, lim: Limits) -> NDArray:
    """The hold duties, checked: each within [0, 1], junction peaks and lowered dots safe."""
    hold = dyn.hold_duties(up, lim.tgt_k)
    names = [p.name for p in dyn.model.ports]
    if np.any(hold[up] < 0):
        k = int(np.flatnonzero(up & (hold < 0))[0])
        raise DataFormatError(f"pattern: dot {names[k]} would sit above the target "
                              f"{lim.target_c:g} °C from its neighbours' heat alone")
    if np.any(hold > 1):
        k = int(np.argmax(hold))
        raise DataFormatError(f"pattern: holding dot {names[k]} at {lim.target_c:g} °C needs "
                              f"duty {hold[k]:.3f} > 1 at {dyn.p:g} W; raise the power")
    rise = dyn.steady_rise(hold)
    peak = rise + dyn.ripple(hold)
    if np.any(peak > lim.lim_k):
        k = int(np.argmax(peak))
        raise DataFormatError(f"pattern: the hold's junction peak of {names[k]} is "
                              f"{lim.ambient_c + peak[k]:.2f} °C > t_max {lim.t_max_c:g} °C; "
                              f"raise the PWM frequency or lower the power")
    if np.any(rise[~up] > lim.down_k):
        k = int(np.flatnonzero(~up)[np.argmax(rise[~up])])
        raise DataFormatError(
            f"pattern: dot {names[k]} must stay down but its raised neighbours hold it at "
            f"{lim.ambient_c + rise[k]:.2f} °C >= {lim.actuation_c - lim.margin_k:g} °C "
            f"(actuation less the margin): this pattern cannot be shown at this target")
    return hold


def _duty_bound(dyn: ArrayDynamics, mean_end: NDArray, slope: NDArray, limit: float
                ) -> NDArray:
    """Per cell, the largest duty (on a 1/200 grid) whose mean at the step's end plus ripple
    stays at or below ``limit``, the mean being ``mean_end + slope · d`` (own duty only)."""
    grid, ripple = dyn.ripple_table()
    ok = mean_end[None, :] + slope[None, :] * grid[:, None] + ripple <= limit
    best = np.where(ok.any(axis=0), grid[np.argmax(np.where(ok, grid[:, None], -1), axis=0)],
                    0.0)
    return best


def _greedy(dyn: ArrayDynamics, z0: NDArray, up: NDArray, hold: NDArray, lim: Limits,
            peak_k: float, horizon: float) -> list[ArrayStep]:
    from scipy.optimize import linprog

    modes = dyn.modes
    lam, w = modes.lam, modes.w
    period, n = dyn.period, dyn.n
    look = np.concatenate([[0.0], np.geomspace(period / 10, 10 * modes.tau.max(), LOOK_POINTS)])
    decay = np.exp(-np.outer(look, lam))                                  # (Q, K)
    z_hold = modes.steady(dyn.p * hold)
    rise_hold = dyn.ports(z_hold)
    idx_up = np.flatnonzero(up)
    z, k, steps = np.asarray(z0, dtype=float), 0, []
    tol_switch = 0.5 * lim.tol_k
    while k * period < horizon and idx_up.size:
        m = max(1, int(GROWTH * k))
        h = m * period
        e_h = np.exp(-lam * h)
        z_free = z * e_h
        z_in = (-np.expm1(-lam * h) / lam)[:, None] * (w.T * dyn.p)         # (K, N)
        a_free = (decay * z_free) @ w.T                                     # (Q, N)
        b = np.einsum("qk,ik,kj->qij", decay, w, z_in[:, idx_up])          # (Q, N, U)
        a_hold = (decay * (z_free - z_hold)) @ w.T + rise_hold
        now = dyn.ports(z)
        cooling = ~up & (now > lim.down_k)
        rows, rhs = [b[:, idx_up, :].reshape(-1, idx_up.size)], [
            (lim.tgt_k - a_free[:, idx_up]).ravel()]
        held = np.flatnonzero(~up & ~cooling)
        if held.size:
            rows.append(b[:, held, :].reshape(-1, idx_up.size))
            rhs.append((lim.down_k - a_hold[:, held]).ravel())
        self_slope = np.array([b[0, i, list(idx_up).index(i)] if up[i] else 0.0
                               for i in range(n)])
        coupled = a_free[0]
        bound = np.zeros(n)
        d = np.zeros(n)
        for _ in range(3):  # the peak bound with the others' duties of the last solution
            others = (b[0] @ d[idx_up]) - self_slope * d
            bound = _duty_bound(dyn, coupled + others, self_slope, peak_k)
            res = linprog(-np.ones(idx_up.size), A_ub=np.concatenate(rows),
                          b_ub=np.concatenate(rhs), bounds=list(zip(np.zeros(idx_up.size),
                                                                    bound[idx_up], strict=True)),
                          method="highs")
            new = np.zeros(n)
            if res.status == 0:
                new[idx_up] = np.clip(res.x, 0.0, 1.0)
            if np.allclose(new, d, atol=1e-6):
                d = new
                break
            d = new
        d = np.round(d, 6)
        z = dyn.advance(z, h, d)
        steps.append((k, m, tuple(float(x) for x in d)))
        k += m
        # switch to the hold once it keeps every raised dot in the band, every lowered one
        # below its limit, forever
        dz = (decay * (z - z_hold)) @ w.T + rise_hold                       # (Q, N)
        in_band = np.all(np.abs(dz[:, idx_up] - lim.tgt_k) <= tol_switch)
        below = np.all(dz[:, ~up & ~cooling] <= lim.down_k) if np.any(~up & ~cooling) else True
        if in_band and below:
            break
    return steps


def exact_peaks(dyn: ArrayDynamics, z0: NDArray, steps: list[ArrayStep] | tuple[ArrayStep, ...],
                hold: NDArray, hold_periods: int, dense: int = 2000) -> tuple[NDArray, NDArray]:
    """Every cell's exact switched junction rise at the end of its on-phases, sampled.

    Parameters
    ----------
    dyn : ArrayDynamics
        The network.
    z0 : NDArray
        Modal state at the start.
    steps : sequence of ArrayStep
        The profile; the hold follows.
    hold : NDArray
        Duties after the profile.
    hold_periods : int
        Periods of the hold to include.
    dense : int
        Periods of a piece taken one by one before the sampling turns logarithmic.

    Returns
    -------
    t_s, peak_k : NDArray
        Period start times, s, and ``(len(t_s), N)`` peaks, K.
    """
    z = np.asarray(z0, dtype=float)
    end = steps[-1][0] + steps[-1][1] if steps else 0
    ts, peaks = [], []
    for first, count, d in [*steps, (end, hold_periods, tuple(hold))]:
        sm = SwitchedMap(dyn, np.asarray(d))
        if count <= 2 * dense:
            j = np.arange(count)
        else:
            j = np.unique(np.concatenate([np.arange(dense),
                                          np.geomspace(dense, count - 1, dense).astype(int)]))
        peaks.append(sm.peaks(sm.start(z, j)))
        ts.append((first + j) * dyn.period)
        z = sm.start(z, count)
    return np.concatenate(ts), np.concatenate(peaks)


def plan_transition(dyn: ArrayDynamics, z0: NDArray, up: list[bool] | NDArray, lim: Limits
                    ) -> Transition:
    """The fastest safe drive from modal state ``z0`` to the pattern ``up``.

    Parameters
    ----------
    dyn : ArrayDynamics
        The array under PWM.
    z0 : NDArray
        Modal state at the change (zeros: cold).
    up : sequence of bool
        Which cells are raised by the new pattern.
    lim : Limits
        The limits.

    Returns
    -------
    Transition

    Examples
    --------
    >>> from spicethermal.bench.array_devices import ArrayGeometry
    >>> dyn = ArrayDynamics(ArrayGeometry(rows=1, cols=2).model(), 1.5, 1000.0)
    >>> lim = Limits(25.0, 95.0, 70.0, 1.0, 64.7, 1.0, 1.5, 1000.0)
    >>> tr = plan_transition(dyn, np.zeros(dyn.modes.lam.size), [True, False], lim)
    >>> tr.steps[0][2], round(tr.hold[0], 3)      # boost the raised dot, hold it
    ((1.0, 0.0), 0.267)
    """
    up = np.asarray(up, dtype=bool)
    if up.shape != (dyn.n,):
        raise DataFormatError(f"pattern: {up.size} dots for an array of {dyn.n} cells")
    hold = _feasible_hold(dyn, up, lim)
    horizon = 15 * float(dyn.modes.tau.max())
    margin = 0.0
    for _ in range(6):
        steps = _greedy(dyn, z0, up, hold, lim, lim.lim_k - margin, horizon)
        _, pk = exact_peaks(dyn, z0, steps, hold, int(horizon / dyn.period) + 1)
        excess = float(pk.max()) - (lim.lim_k - SAFETY_K)
        if excess <= 0:
            break
        margin += excess + SAFETY_K
    else:  # pragma: no cover - converges in 1-3 rounds
        raise SimulationError("array drive: the junction-peak margin iteration did not converge")
    return Transition(tuple(bool(x) for x in up), tuple(steps), tuple(float(x) for x in hold),
                      margin)
