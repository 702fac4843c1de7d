"""Safe fast drive: the PWM schedule that actuates fastest without overheating the heater.

The paper's opening problem: a thermal actuator responds slowly, more power makes it faster,
but the heater must survive. Here the heater is switched at ``f_pwm`` with amplitude ``P_max``;
the duty cycle is the control. The drive must bring an *actuation node* (the junction, or a
physical Cauer node such as the cavity: ``node=k`` is node k of the model converted to Cauer)
to a target temperature and keep it there, while the junction's **peak** temperature — the
state at the end of every on-phase, PWM ripple included — never exceeds ``t_max``.

Definitions
-----------
* The node temperature is the period average (what a slow actuator responds to); the junction
  limit applies to the peak.
* *Hold duty*: the duty whose steady state puts the node at the target. Its periodic steady
  state must keep the junction peak below ``t_max``, else the target is not safely reachable.
* *Time to target*: from switch-on until the node enters the band ``target ± tol`` **and stays
  in it** (a boost that crosses the target and droops back has not actuated).

Method
------
The schedule is a duty profile on a grid of whole PWM periods (fine at first, growing in
proportion to the elapsed time), ending in the hold duty. It is built greedily, bang-bang
with state constraints: in each step the largest duty such that (1) the junction peak at the
step's end stays at or below the limit and (2) the node, even if power were cut after this
step, never rises above the target (its free response, a look-ahead, prevents overshoot of a
node deep in the ladder). So the drive boosts at duty 1 until the junction peak reaches
``t_max``, rides that constraint, then rides the target (duty falling towards the hold duty
while the slow stages fill), and switches to the hold duty as soon as doing so keeps the node
within the band forever. A simpler two-phase drive (boost duty for a boost time, then the
hold duty) is optimized by grid search for comparison; the faster of the two is returned.

Accuracy
--------
For a linear model the junction constraint is **exact**: the greedy tracks the switched
state period by period in closed form (modal coordinates; at constant duty the period map is
affine) and checks the junction at the end of sampled on-phases of every step; the whole
schedule is then checked on every on-phase (:func:`_switched_peaks`), and any excess (from
merged steps or periods between samples) tightens the limit for a new pass. The node, whose
temperature is the period average, follows the averaged-power dynamics (exact for the mean).
With device effects (temperature coefficient, phase change) the drive is decided on the
averaged power, one step at a time on the network frozen at the current state and advanced
by the stiff nonlinear integration, with the closed-form periodic ripple of
:mod:`spicethermal.engines.pwm` (resistances scaled to the current junction temperature) for the
peak: an approximation for ``f_pwm`` fast against the slow stages. The switching excess over
it is taken from the linear surrogate at the junction limit, and the limit is tightened until
the averaged simulation plus ripple and that margin respects ``t_max``. Both are verified in
ngspice on the switched drive (tests/test_drive.py, bench/bench_drive.py).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..core.errors import DataFormatError, SimulationError
from ..core.ladder import Foster
from ..engines.pwm import _stage_peaks, check_drive, steady_state
from ..model import Network, Schedule, ThermalModel

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

DEFAULT_F_PWM_HZ = 1000.0
DEFAULT_TOL_K = 0.5
DEFAULT_DUTY_STEP = 0.005
_SAFETY_K = 2e-3  # the exact peak is brought this far under t_max by the margin iteration
_NONLINEAR_SAFETY_K = 0.05  # and the approximate one of a nonlinear model this far


# ------------------------------------------------------------------------------ results
@dataclass(frozen=True)
class TwoPhase:
    """The best ``boost_duty`` for ``boost_s``, then the hold duty (grid search)."""

    boost_s: float
    boost_duty: float
    time_to_target_s: float
    peak_junction_c: float

    def as_json(self) -> dict[str, float]:
        return {"boost_s": self.boost_s, "boost_duty": self.boost_duty,
                "time_to_target_s": self.time_to_target_s,
                "peak_junction_c": self.peak_junction_c}


@dataclass(frozen=True)
class Release:
    """Time for the node to fall from the steady hold to ``release_c`` at ``keep_warm_duty``."""

    release_c: float
    keep_warm_duty: float
    time_s: float

    def as_json(self) -> dict[str, float]:
        return {"release_c": self.release_c, "keep_warm_duty": self.keep_warm_duty,
                "time_s": self.time_s}


@dataclass(frozen=True, eq=False)
class DriveTrace:
    """Predicted temperatures (°C) on a time grid, for the drive and for the constant duty.

    ``junction_peak_c`` is the period-averaged junction plus the periodic ripple at the
    current duty; ``exact_t_s``/``exact_peak_c`` (linear models) are the exact switched
    junction temperatures at the ends of on-phases.
    """

    t_s: NDArray
    duty: NDArray
    node_c: NDArray
    junction_mean_c: NDArray
    junction_peak_c: NDArray
    constant_node_c: NDArray
    constant_junction_peak_c: NDArray
    exact_t_s: NDArray
    exact_peak_c: NDArray


@dataclass(frozen=True, eq=False)
class DriveResult:
    """The safe fast drive found by :func:`optimize_drive`.

    ``schedule`` is ``((t_s, duty), ...)``: each duty applies from its time until the next
    one; the last (the hold duty) applies forever. Times are whole PWM periods, each period
    starting with its on-phase. ``ripple_margin_k`` is how far the averaged-plus-ripple limit
    had to be tightened for the exact switched peak to respect ``t_max`` (a measure of the
    averaging approximation; 0 when it was conservative).
    """

    model: ThermalModel
    node: int
    t_max_c: float
    target_c: float
    ambient_c: float
    p_max_w: float
    f_pwm_hz: float
    tol_k: float
    hold_duty: float
    hold_peak_junction_c: float
    schedule: tuple[tuple[float, float], ...]
    method: str
    time_to_target_s: float
    constant_duty_time_to_target_s: float
    peak_junction_c: float
    peak_method: str
    two_phase: TwoPhase | None
    release: Release | None
    trace: DriveTrace
    ripple_margin_k: float = 0.0

    @property
    def speedup(self) -> float:
        """Constant-duty time to target over the drive's."""
        if self.time_to_target_s <= 0:
            return math.inf
        return self.constant_duty_time_to_target_s / self.time_to_target_s

    @property
    def period_s(self) -> float:
        return 1.0 / self.f_pwm_hz

    def duty_at(self, t_s: float) -> float:
        """Duty applied at time ``t_s``."""
        times = [t for t, _ in self.schedule]
        k = int(np.searchsorted(times, t_s, side="right")) - 1
        return self.schedule[max(k, 0)][1]

    def power_schedule(self) -> Schedule:
        """The period-averaged power ``P_max · duty`` as a :class:`Schedule`."""
        return Schedule(tuple(t for t, _ in self.schedule),
                        tuple(self.p_max_w * d for _, d in self.schedule))

    def as_json(self) -> dict:
        """The ``spicethermal drive --json`` document."""
        return {
            "time_to_target_s": self.time_to_target_s,
            "constant_duty_time_to_target_s": self.constant_duty_time_to_target_s,
            "speedup": self.speedup,
            "peak_junction_c": self.peak_junction_c,
            "peak_method": self.peak_method,
            "method": self.method,
            "node": self.node,
            "target_c": self.target_c,
            "t_max_c": self.t_max_c,
            "ambient_c": self.ambient_c,
            "p_max_w": self.p_max_w,
            "f_pwm_hz": self.f_pwm_hz,
            "tol_k": self.tol_k,
            "hold_duty": self.hold_duty,
            "hold_peak_junction_c": self.hold_peak_junction_c,
            "schedule": [{"t_s": t, "duty": d} for t, d in self.schedule],
            "ripple_margin_k": self.ripple_margin_k,
            "two_phase": self.two_phase.as_json() if self.two_phase else None,
            "release": self.release.as_json() if self.release else None,
        }

    def table(self) -> str:
        """The schedule as a text table (start, end, periods, duty, average power)."""
        lines = [f"{'from (s)':>12} {'to (s)':>12} {'periods':>8} {'duty':>7} {'P avg (W)':>10}"]
        for k, (t, d) in enumerate(self.schedule):
            if k + 1 < len(self.schedule):
                t1 = self.schedule[k + 1][0]
                n = f"{round((t1 - t) * self.f_pwm_hz):d}"
                end = f"{t1:12.6g}"
            else:
                n, end = "hold", f"{'∞':>12}"
            lines.append(f"{t:12.6g} {end} {n:>8} {d:7.4f} {d * self.p_max_w:10.4g}")
        return "\n".join(lines)

    def __str__(self) -> str:
        where = "junction" if self.node == 0 else f"Cauer node {self.node}"
        out = [
            f"drive of the {where} to {self.target_c:g} °C (±{self.tol_k:g} K), junction peak "
            f"≤ {self.t_max_c:g} °C, P_max {self.p_max_w:.4g} W at {self.f_pwm_hz:g} Hz, "
            f"ambient {self.ambient_c:g} °C",
            f"  {self.method} drive: time to target {self.time_to_target_s:.4g} s, "
            f"peak junction {self.peak_junction_c:.3f} °C ({self.peak_method})",
            f"  constant hold duty {self.hold_duty:.4f}: time to target "
            f"{self.constant_duty_time_to_target_s:.4g} s (speed-up ×{self.speedup:.3g}), "
            f"hold junction peak {self.hold_peak_junction_c:.2f} °C",
        ]
        if self.two_phase:
            tp = self.two_phase
            out.append(f"  two-phase drive: duty {tp.boost_duty:.4f} for {tp.boost_s:.4g} s, then "
                       f"hold: time to target {tp.time_to_target_s:.4g} s")
        if self.release:
            r = self.release
            out.append(f"  release below {r.release_c:g} °C at duty {r.keep_warm_duty:g}: "
                       f"{r.time_s:.4g} s from the steady hold")
        return "\n".join(out)

    # -- SPICE ---------------------------------------------------------------------------
    def schedule_from(self, start_s: float) -> tuple[tuple[float, float], ...]:
        """The schedule as seen from the period start ``start_s`` (times shifted by it).

        Parameters
        ----------
        start_s : float
            A period start (s); 0 gives :attr:`schedule` itself.

        Returns
        -------
        tuple of (float, float)
            ``(t_s, duty)`` pieces from ``t_s = 0``.

        Examples
        --------
        >>> r = optimize_drive(ThermalModel(Foster.from_tau([30.0, 70.0], [0.01, 1.0])),
        ...                    70.0, 55.0, p_max_w=1.0)
        >>> r.schedule_from(0.0) == r.schedule
        True
        >>> r.schedule_from(r.schedule[-1][0] + 1.0) == ((0.0, r.hold_duty),)
        True
        """
        half = 0.5 * self.period_s
        ends = [t for t, _ in self.schedule[1:]] + [math.inf]
        return tuple((max(t - start_s, 0.0), d)
                     for (t, d), end in zip(self.schedule, ends, strict=True)
                     if end > start_s + half)

    def switched_state(self, t_s: float) -> NDArray:
        """Exact node rises (K) of the switched drive at the period start ``t_s`` (linear model).

        The state of the model's network (:func:`spicethermal.spice.lib.internal_nodes` order),
        carried period by period through the closed-form period map of each duty.

        Parameters
        ----------
        t_s : float
            A period start, s.

        Returns
        -------
        NDArray
            Node rises over the ambient, junction first.

        Examples
        --------
        >>> r = optimize_drive(ThermalModel(Foster.from_tau([30.0, 70.0], [0.01, 1.0])),
        ...                    70.0, 55.0, p_max_w=1.0)
        >>> bool(r.switched_state(0.0)[0] == 0.0)
        True
        """
        if not self.model.is_linear:
            raise DataFormatError("switched_state: exact only for a model without device effects")
        dyn = _Dynamics(self.model, self.ambient_c, self.p_max_w, self.f_pwm_hz)
        _, v, _ = dyn.modes(np.zeros(dyn.n))
        n_end = round(t_s / self.period_s)
        firsts = [round(t / self.period_s) for t, _ in self.schedule] + [n_end]
        z = np.zeros(dyn.n)
        for (_, d), first, nxt in zip(self.schedule, firsts, firsts[1:], strict=False):
            if first >= n_end:  # (the hold, last, runs until t_s)
                break
            z = _PeriodMap(dyn, d).start(z, min(nxt, n_end) - first)
        return v @ z

    def spice_sources(self, pin: str = "TJ", ref: str = "0", prefix: str = "IDRV",
                      start_s: float = 0.0) -> list[str]:
        """Current sources that inject the switched power of the schedule into ``pin``.

        One ``PULSE`` per constant-duty interval with its number of pulses (ngspice ≥ 39 and
        LTspice read the 8th PULSE parameter as the pulse count), and an endless ``PULSE`` for
        the hold. Edges last 1e-4 period and the width is shortened by one edge, so the
        energy of every period is exactly ``P_max · duty / f_pwm``. ``start_s`` (a period
        start) gives the sources of the drive from that time on (:meth:`schedule_from`).
        """
        from ..spice.lib import Pulse, fmt

        period = self.period_s
        edge = Pulse.of(self.f_pwm_hz, 0.5).edge_s
        p = fmt(self.p_max_w)
        lines = []
        schedule = self.schedule_from(start_s)
        for k, (t, d) in enumerate(schedule):
            last = k + 1 == len(schedule)
            if d <= 0:
                continue
            name = f"{prefix}{k + 1}"
            if d >= 1:  # fully on: one trapezoid of the interval's length (the hold: DC)
                if last:
                    lines.append(f"{name} {ref} {pin} PWL({fmt(t)} 0 {fmt(t + edge)} {p})")
                    continue
                length = schedule[k + 1][0] - t
                lines.append(f"{name} {ref} {pin} PULSE(0 {p} {fmt(t)} {fmt(edge)} {fmt(edge)} "
                             f"{fmt(length - edge)} {fmt(length + 2 * edge)} 1)")
                continue
            width = max(d * period - edge, 0.0)
            head = (f"{name} {ref} {pin} PULSE(0 {p} {fmt(t)} {fmt(edge)} {fmt(edge)} "
                    f"{fmt(width)} {fmt(period)}")
            if last:
                lines.append(head + ")")
            else:
                n = round((schedule[k + 1][0] - t) / period)
                lines.append(f"{head} {n:d})")
        return lines

    def spice_bench(self, name: str = "HEATER", tstop_s: float | None = None,
                    tmax_s: float | None = None, reltol: float = 1e-4,
                    start_s: float = 0.0) -> str:
        """A self-contained ngspice deck: the model's subcircuit, the drive's sources, ``.tran``.

        ``TREF`` sits at the ambient temperature, so ``V(TJ)`` is the junction in °C and
        ``V(X1.Nk)`` Cauer node k; with device effects ``TREF`` is grounded and the ambient
        passed as ``TOFFSET`` (:func:`spicethermal.spice.lib.reference_drive`), so add
        :attr:`bench_offset_c` to the voltages. ``tstop_s`` defaults to
        :meth:`verification_window_s`,
        ``tmax_s`` (the maximum step) to 1/100 period (1/20 leaves errors of ~0.01 K).
        ``start_s`` > 0 (a period start, linear models) simulates the drive from that time to
        ``tstop_s`` only: the deck's time 0 is ``start_s``, its nodes start (``.ic``) in the
        exact switched state there (:meth:`switched_state`).
        """
        from .. import __version__
        from ..spice.lib import (
            environment,
            initial_conditions,
            reference_drive,
            render_lib,
            sanitize_comment,
        )

        tstop = self.verification_window_s() if tstop_s is None else float(tstop_s)
        tmax = self.period_s / 100 if tmax_s is None else float(tmax_s)
        tref = self.ambient_c - self.bench_offset_c
        ic = initial_conditions(self.model, self.switched_state(start_s), tref) \
            if start_s > 0 else []
        return environment().get_template("bench/drive.cir.j2").render(
            version=__version__, lib=render_lib(self.model, "ngspice", name=name),
            name=name, tref_c=tref,
            toffset_c=reference_drive(self.model, self.ambient_c)[1],
            sources=self.spice_sources(start_s=start_s), ic=ic, start_s=float(start_s),
            description=sanitize_comment(
                f"node {self.node} to {self.target_c:g} degC, Tj peak <= {self.t_max_c:g} "
                f"degC, {self.f_pwm_hz:g} Hz, P_max {self.p_max_w:g} W"),
            tstop_s=tstop - start_s, tstep_s=tmax, tmax_s=tmax, reltol=reltol)

    @property
    def bench_offset_c(self) -> float:
        """What to add to the voltages of :meth:`spice_bench` to read °C."""
        from ..spice.lib import reference_drive

        return self.ambient_c - reference_drive(self.model, self.ambient_c)[0]

    def verification_window_s(self, max_periods: int = 4000) -> float:
        """Span worth simulating switched: past the exact peak and the time to target."""
        t_peak = float(self.trace.exact_t_s[np.argmax(self.trace.exact_peak_c)]) \
            if self.trace.exact_t_s.size else self.time_to_target_s
        span = max(2.0 * t_peak, 1.2 * self.time_to_target_s, 20 * self.period_s)
        return min(span, max_periods * self.period_s)


# ------------------------------------------------------------------------------ dynamics
class _Dynamics:
    """Period-averaged dynamics ``Cm dx/dt = -G x + e0 P_max d`` of the model's network.

    ``modes(x)`` gives ``(λ, V, Vᵀ Cm)`` of the network (frozen at state ``x`` when the model
    is nonlinear): ``x = V z``, ``dz/dt = -λ z + V[0] P``.
    """

    def __init__(self, model: ThermalModel, ambient_c: float, p_max_w: float,
                 f_pwm_hz: float) -> None:
        self.model = model
        self.net = Network.of(model.ladder)
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
        if self.linear:
            return self._fixed
        cm, g = self.model._matrices(x, self.tref, self.net)
        return self._eig(cm, g)

    def scale(self, junction_k: float) -> float:
        """Resistance factor of the temperature coefficient at a junction rise (1 if none):
        the mean over the layers of each layer's factor with the layer at the junction
        temperature (exact for the junction form, an upper bound on the change otherwise)."""
        tj = self.tref + junction_k
        return float(np.mean([np.prod([e.resistance_scale(k, tj, tj)
                                       for e in self.model.device_effects])
                              for k in range(self.model.ladder.order)]))

    def ripple(self, duty: NDArray | float, junction_k: float = 0.0) -> NDArray:
        """Periodic-steady-state junction peak minus mean (K) at ``duty``."""
        s = self.scale(junction_k) if not self.linear else 1.0
        d = np.asarray(duty, dtype=float)
        peaks = _stage_peaks(self.r * s, self.tau * s, self.period, d[..., None]).sum(axis=-1)
        return self.p * (peaks - d * s * self.r.sum())

    def advance(self, x: NDArray, h: float, duty: float,
                modes: tuple[NDArray, NDArray, NDArray]) -> NDArray:
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


# ------------------------------------------------------------------------------ helpers
def _settle_rows(t: NDArray, y: NDArray, target: float, tol: float) -> tuple[NDArray, NDArray]:
    """Per row of ``y``: the first time after which ``|y - target| <= tol`` for good
    (interpolated; ``inf`` if still outside at the end) and the index of the last grid point
    outside the band (-1 when none)."""
    y = np.atleast_2d(y)
    err = np.abs(y - target) - tol
    out = err > 0
    last = np.where(out.any(axis=1), y.shape[1] - 1 - np.argmax(out[:, ::-1], axis=1), -1)
    i = np.clip(last, 0, y.shape[1] - 2)
    rows = np.arange(y.shape[0])
    e0, e1 = err[rows, i], err[rows, i + 1]
    with np.errstate(invalid="ignore", divide="ignore"):
        w = np.where(e0 != e1, e0 / (e0 - e1), 1.0)
    ts = t[i] + w * (t[i + 1] - t[i])
    ts = np.where(last < 0, t[0], ts)
    ts = np.where(out[:, -1], np.inf, ts)
    return ts, last


def _settle(t: NDArray, y: NDArray, target: float, tol: float) -> tuple[float, int]:
    """:func:`_settle_rows` for one curve."""
    ts, last = _settle_rows(t, y, target, tol)
    return float(ts[0]), int(last[0])


def _bisect(f, a: float, b: float, iters: int = 60) -> float:
    """Root of ``f`` in ``[a, b]`` with ``f(a) > 0 >= f(b)``."""
    from scipy.optimize import brentq

    fa, fb = f(a), f(b)
    if not (fa > 0 >= fb):
        return b
    return float(brentq(f, a, b, xtol=1e-12, rtol=1e-10, maxiter=iters))


def _time_grid(period: float, horizon: float, marks: tuple[float, ...] = (), n: int = 1500
               ) -> NDArray:
    t = np.geomspace(period / 4, horizon, n)
    return np.unique(np.concatenate([[0.0], t, np.asarray(marks, dtype=float)]))


def _compress(steps: list[tuple[int, int, float]], duty_step: float
              ) -> list[tuple[int, int, float]]:
    """Merge consecutive steps whose duties span at most ``duty_step`` (energy kept)."""
    out: list[tuple[int, int, float]] = []
    group: list[tuple[int, int, float]] = []

    def flush() -> None:
        if group:
            n = sum(g[1] for g in group)
            d = sum(g[1] * g[2] for g in group) / n
            out.append((group[0][0], n, round(d, 6)))
            group.clear()

    lo = hi = 0.0
    for s in steps:
        if group and (max(hi, s[2]) - min(lo, s[2]) > duty_step or (s[2] >= 1) != (lo >= 1)):
            flush()
        if not group:
            lo = hi = s[2]
        lo, hi = min(lo, s[2]), max(hi, s[2])
        group.append(s)
    flush()
    return out


# ------------------------------------------------------------------------------ the drive
class _PeriodMap:
    """Exact switched response of the linear network, period by period, in modal coordinates.

    A period starts with its on-phase. At constant duty the period map is affine,
    ``z -> a z + c``, so the state at the start of period j is ``z* + (z0 - z*) a^j`` and the
    junction at the end of its on-phase follows in closed form. ``duty`` may be an array
    (leading axis of every result).
    """

    def __init__(self, dyn: _Dynamics, duty: NDArray | float) -> None:
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


def _largest_duty(dyn: _Dynamics, z_sw: NDArray, j: NDArray, lim_k: float) -> float:
    """Largest duty (to 1e-4) whose exact junction peaks over periods ``j`` stay <= lim_k."""
    if _PeriodMap(dyn, 1.0).peaks(z_sw, j).max() <= lim_k:
        return 1.0
    lo, hi = 0.0, 1.0
    for _ in range(2):
        grid = np.linspace(lo, hi, 101)
        ok = _PeriodMap(dyn, grid).peaks(z_sw, j).max(axis=1) <= lim_k
        if not ok.any():
            return lo if lo > 0 else 0.0
        k = int(np.nonzero(ok)[0].max())
        if k == grid.size - 1:
            return float(grid[k])
        lo, hi = float(grid[k]), float(grid[k + 1])
    return lo


def _greedy(dyn: _Dynamics, node: int, lim_k: float, tgt_k: float, hold_duty: float,
            x_hold: NDArray, tol_switch: float, growth: float, t_end: float, sustain: int = 5
            ) -> tuple[list[tuple[int, int, float]], float, int]:
    """Bang-bang duty profile under the junction-peak and no-overshoot constraints.

    The junction constraint is exact for a linear model (switched state, sampled periods of
    the step), and a duty is accepted only if it could be kept ``sustain`` periods (this stops
    the ride along the limit from chattering between duty 1 and a low duty); with device
    effects it is the mean plus the ripple at the step's end.
    Returns steps ``(first_period, periods, duty)`` (the hold follows the last one), the
    largest junction peak rise met, and the index of the step in which the node arrived
    within ``tol_switch`` of the target (len(steps) if never).
    """
    period = dyn.period
    dgrid = np.linspace(0.0, 1.0, 2001)
    look = np.concatenate([[0.0], np.geomspace(period / 10, 10 * dyn.tau.max(), 160)])
    ripple_hold = float(dyn.ripple(hold_duty, x_hold[0]))
    linear = dyn.linear
    z_sw = np.zeros(dyn.n)  # exact switched modal state at the start of the next period
    x = np.zeros(dyn.n)
    k = 0
    steps: list[tuple[int, int, float]] = []
    worst = 0.0
    arrival = -1
    while k * period < t_end:
        m = max(1, int(growth * k))
        h = m * period
        modes = dyn.modes(x)
        lam, v, vinv = modes
        z_free = (vinv @ x) * np.exp(-lam * h)
        z_in = dyn.p * v[0] / lam * -np.expm1(-lam * h)
        # (1) junction peak: exact over sampled periods of the step (linear), else mean +
        # ripple at the step's end
        j = np.unique(np.round(np.linspace(0, m - 1, min(m, 8))))
        if linear:  # exact; a duty must be sustainable for `sustain` periods
            span = max(m, sustain)
            d_j = _largest_duty(dyn, z_sw, np.unique(np.round(np.linspace(0, span - 1,
                                                                         min(span, 8)))), lim_k)
        else:
            aj, bj = float(v[0] @ z_free), float(v[0] @ z_in)
            ok = aj + dgrid * bj + dyn.ripple(dgrid, aj) <= lim_k
            d_j = float(dgrid[ok].max()) if ok.any() else 0.0
        # (2) no overshoot: the node's free response after this step stays <= target
        decay = v[node] * np.exp(-np.outer(look, lam))
        a_n, b_n = decay @ z_free, decay @ z_in
        pos = b_n > 1e-12 * np.abs(b_n).max()
        d_n = float(np.min((tgt_k - a_n[pos]) / b_n[pos])) if pos.any() else 1.0
        d = min(1.0, max(0.0, min(d_j, d_n)))
        x = dyn.advance(x, h, d, modes)
        if linear:
            one = _PeriodMap(dyn, d)
            worst = max(worst, float(one.peaks(z_sw, j).max()))
            z_sw = one.start(z_sw, m)
        else:
            worst = max(worst, float(x[0] + dyn.ripple(d, x[0])))
        steps.append((k, m, d))
        k += m
        if arrival < 0 and x[node] >= tgt_k - tol_switch:
            arrival = len(steps)
        # switch to the hold once it keeps the node in the band and the junction safe
        lam, v, vinv = dyn.modes(x)
        dz = (vinv @ (x - x_hold)) * np.exp(-np.outer(look, lam))
        if (np.max(np.abs(dz @ v[node])) <= tol_switch
                and np.max(dz @ v[0]) + x_hold[0] + ripple_hold <= lim_k):
            break
    return steps, worst, (arrival if arrival >= 0 else len(steps))


def _smooth(steps: list[tuple[int, int, float]], first: int, passes: int = 8
            ) -> list[tuple[int, int, float]]:
    """Damp the period-2 ringing of the greedy once the node has arrived (steps >= first).

    Riding the target, a duty that is a local extremum between two partial-duty neighbours
    is replaced, with them, by their time-weighted mean over the three steps (energy kept).
    """
    d = np.array([s[2] for s in steps])
    n = np.array([s[1] for s in steps], dtype=float)
    for _ in range(passes):
        changed = False
        for i in range(max(first, 0) + 1, len(d) - 1):
            if d[i - 1] >= 1 or d[i + 1] >= 1 or d[i] >= 1:
                continue
            if (d[i] - d[i - 1]) * (d[i + 1] - d[i]) < 0:
                w = n[i - 1:i + 2]
                mean = float(w @ d[i - 1:i + 2] / w.sum())
                d[i - 1:i + 2] = mean
                changed = True
        if not changed:
            break
    return [(k, m, float(x)) for (k, m, _), x in zip(steps, d, strict=True)]


def _switched_peaks(dyn: _Dynamics, intervals: list[tuple[int, int, float]], hold_duty: float,
                    hold_periods: int, dense: int = 3000) -> tuple[NDArray, NDArray]:
    """Exact junction rise at the end of every on-phase (linear model), sampled.

    Every period is available in closed form (:class:`_PeriodMap`); long intervals are
    sampled densely first, then logarithmically.
    """
    period = dyn.period
    z = np.zeros(dyn.n)
    ts, peaks = [], []
    end = intervals[-1][0] + intervals[-1][1] if intervals else 0
    for first, n, d in [*intervals, (end, hold_periods, hold_duty)]:
        pm = _PeriodMap(dyn, d)
        if n <= 2 * dense:
            j = np.arange(n)
        else:
            j = np.unique(np.concatenate([np.arange(dense),
                                          np.geomspace(dense, n - 1, dense).astype(int)]))
        peaks.append(pm.peaks(z, j))
        ts.append((first + j + d) * period)
        z = pm.start(z, n)
    return np.concatenate(ts), np.concatenate(peaks)


def _two_phase(dyn: _Dynamics, node: int, lim_k: float, tgt_k: float, tol: float,
               hold_duty: float, horizon: float) -> TwoPhase | None:
    """Grid search over boost time (whole periods) and boost duty, then the hold duty.

    Closed form on the linear model: a candidate is the hold-duty step plus a step of
    ``boost - hold`` duty that ends at the boost time.
    """
    period = dyn.period
    band = 0.98 * tol  # a curve that grazes the band's edge between grid points is not robust
    lam, v, _ = dyn.modes(np.zeros(dyn.n))
    gain = v[0] / lam

    def resp(row: int, t: NDArray) -> NDArray:  # rise per watt after a step at t = 0
        tt = np.maximum(t, 0.0)[..., None]
        return (v[row] * gain * -np.expm1(-lam * tt)).sum(axis=-1)

    def evaluate(tbs: NDArray, dbs: NDArray) -> tuple[NDArray, NDArray, NDArray]:
        t = _time_grid(period, horizon, tuple(tbs), 1200)
        sn, sj = resp(node, t), resp(0, t)
        best_t = np.full((tbs.size, dbs.size), math.inf)
        peak = np.full((tbs.size, dbs.size), math.inf)
        rip_b = dyn.ripple(dbs)
        rip_h = float(dyn.ripple(hold_duty))
        for i, tb in enumerate(tbs):
            dn = sn - resp(node, t - tb) * (t > tb)
            dj = sj - resp(0, t - tb) * (t > tb)
            extra = (dbs - hold_duty)[:, None] * dyn.p
            jm = hold_duty * dyn.p * sj + extra * dj
            jp = np.where(t <= tb, jm + rip_b[:, None], jm + rip_h)
            peak[i] = jp.max(axis=1)
            ok = peak[i] <= lim_k  # only the safe candidates need their settling time
            if ok.any():
                y = hold_duty * dyn.p * sn + extra[ok] * dn
                best_t[i, ok] = _settle_rows(t, y, tgt_k, band)[0]
        return best_t, peak, t

    tbs = np.unique(np.maximum(1, np.round(np.geomspace(period, horizon / 4, 160) / period)))
    dbs = np.linspace(hold_duty, 1.0, 141)
    times, peaks, _ = evaluate(tbs * period, dbs)
    if not np.isfinite(times).any():
        return None
    i, q = np.unravel_index(np.argmin(times), times.shape)
    best = (float(times[i, q]), float(tbs[i]), float(dbs[q]), float(peaks[i, q]))
    # zoom in around the best candidate: +-2 grid steps in both, three times
    tb_lo, tb_hi = tbs[max(i - 2, 0)], tbs[min(i + 2, tbs.size - 1)]
    d_step = 2 * (dbs[1] - dbs[0])
    for _ in range(3):
        tb2 = np.unique(np.maximum(1, np.round(np.linspace(tb_lo, tb_hi, 25))))
        db2 = np.unique(np.clip(np.linspace(best[2] - d_step, best[2] + d_step, 25),
                                hold_duty, 1.0))
        times2, peaks2, _ = evaluate(tb2 * period, db2)
        i2, q2 = np.unravel_index(np.argmin(times2), times2.shape)
        if times2[i2, q2] <= best[0]:
            best = (float(times2[i2, q2]), float(tb2[i2]), float(db2[q2]),
                    float(peaks2[i2, q2]))
        span = max((tb_hi - tb_lo) / 6, 2.0)
        tb_lo, tb_hi = max(1.0, best[1] - span), best[1] + span
        d_step /= 4
    return TwoPhase(best[1] * period, best[2], best[0], best[3])


def _check(name: str, value: float, low: float = -math.inf, positive: bool = False) -> float:
    v = float(value)
    if not math.isfinite(v) or (positive and v <= 0) or v < low:
        raise DataFormatError(f"{name} = {value!r}: must be finite"
                              + (" and positive" if positive else "")
                              + (f" and at least {low:g}" if low > -math.inf else ""))
    return v


def optimize_drive(model: ThermalModel, t_max_c: float, target_c: float,
                   ambient_c: float = 25.0, p_max_w: float | None = None,
                   f_pwm_hz: float = DEFAULT_F_PWM_HZ, node: int = 0, *,
                   tol_k: float = DEFAULT_TOL_K, release_c: float | None = None,
                   keep_warm_duty: float = 0.0, duty_step: float = DEFAULT_DUTY_STEP,
                   two_phase: bool = True) -> DriveResult:
    """The PWM schedule that brings ``node`` to ``target_c`` fastest with Tj peak ≤ ``t_max_c``.

    Parameters
    ----------
    model : ThermalModel
        Linear or with device effects (temperature coefficient, phase change).
    t_max_c, target_c, ambient_c : float
        Junction limit (applies to the PWM peak), target of the node (period average), and
        the reference temperature, °C.
    p_max_w : float, optional
        Heater power when on, W. Default: the largest DC power whose steady state keeps the
        junction at ``t_max_c`` (then only the ripple-free boost is limited by the target).
    f_pwm_hz : float
        PWM frequency; every schedule step is a whole number of periods.
    node : int
        0 for the junction, k for Cauer node k of the model converted to Cauer (exactly; a
        phase-change effect's ``node`` then also counts Cauer nodes, as in the Cauer export).
    tol_k : float
        Half-width of the band the node must settle in (time to target).
    release_c : float, optional
        Also report the time for the node to fall below this temperature from the steady hold,
        with power off or at ``keep_warm_duty``.
    duty_step : float
        Consecutive steps whose duties differ by at most this are merged (energy kept).
    two_phase : bool
        Also optimize the two-phase drive (boost, then hold) and keep it if it is faster.

    Returns
    -------
    DriveResult

    Examples
    --------
    >>> from spicethermal.core.ladder import Foster
    >>> m = ThermalModel(Foster.from_tau([10.0, 90.0], [1e-3, 1.0]))
    >>> r = optimize_drive(m, 90.0, 50.0, p_max_w=1.0, two_phase=False)
    >>> r.peak_junction_c <= 90.0 and r.speedup > 2
    True
    """
    if not isinstance(model, ThermalModel):
        raise DataFormatError("optimize_drive: model must be a ThermalModel")
    ambient_c = _check("ambient_c", ambient_c, -273.15)
    t_max_c = _check("t_max_c", t_max_c)
    target_c = _check("target_c", target_c)
    tol_k = _check("tol_k", tol_k, positive=True)
    duty_step = _check("duty_step", duty_step, 0.0)
    check_drive(f_pwm_hz, keep_warm_duty)
    if t_max_c <= ambient_c:
        raise DataFormatError(f"t_max_c = {t_max_c:g} °C must be above the ambient "
                              f"{ambient_c:g} °C")
    if not ambient_c + tol_k < target_c < t_max_c:
        raise DataFormatError(f"target_c = {target_c:g} °C must lie between the ambient "
                              f"{ambient_c:g} °C (+ tol {tol_k:g} K) and t_max {t_max_c:g} °C")
    if not isinstance(node, int | np.integer) or not 0 <= node < model.ladder.order:
        raise DataFormatError(f"node = {node!r}: the model has Cauer nodes 0.."
                              f"{model.ladder.order - 1} (0 = junction)")
    node = int(node)
    work = model.with_topology("cauer") if node > 0 else model
    lim_k, tgt_k = t_max_c - ambient_c, target_c - ambient_c
    if p_max_w is None:
        p_max_w = _safe_dc_power(work, ambient_c, lim_k)
    p_max_w = _check("p_max_w", p_max_w, positive=True)
    dyn = _Dynamics(work, ambient_c, p_max_w, f_pwm_hz)
    period = dyn.period

    # -- the hold ----------------------------------------------------------------------
    hold_duty = _hold_duty(dyn, node, tgt_k)
    if work.is_linear:
        hold_peak_k = steady_state(work.ladder, p_max_w, f_pwm_hz, hold_duty).peak_k
    else:
        hold_peak_k = work.pwm(p_max_w, f_pwm_hz, hold_duty, tref_c=ambient_c).peak_k
    if hold_peak_k > lim_k:
        raise DataFormatError(
            f"target {target_c:g} °C is not safely reachable: holding it needs duty "
            f"{hold_duty:.4f} at {p_max_w:g} W, whose junction peak is "
            f"{ambient_c + hold_peak_k:.2f} °C > t_max {t_max_c:g} °C (lower the target, "
            f"raise f_pwm to shrink the ripple, or lower p_max)")
    x_hold = dyn.steady(p_max_w * hold_duty)
    tau_max = float(dyn.tau.max())
    horizon = 15 * tau_max

    # -- greedy profile with the margin iteration ---------------------------------------
    # linear: tighten by the exact switched excess; nonlinear: by the switching margin of
    # the linear surrogate plus the excess of the steps over their frozen-network prediction
    switching = 0.0 if work.is_linear else _surrogate_margin(dyn, node, lim_k, tgt_k, tol_k,
                                                               duty_step, horizon)
    margin = switching
    growth = 0.01 if work.is_linear else 0.05
    for _ in range(6):
        steps, worst, arrival = _greedy(dyn, node, lim_k - margin, tgt_k, hold_duty, x_hold,
                                        0.5 * tol_k, growth, horizon)
        intervals = _compress(_smooth(steps, arrival), duty_step)
        if dyn.linear:
            peak_k, ex_t, ex_pk = _junction_peak(dyn, intervals, hold_duty, horizon)
        else:  # the averaged nonlinear simulation (mean + ripple) between the steps too
            sched = _schedule(intervals, hold_duty, period)
            grid = _time_grid(period, horizon, tuple(t for t, _ in sched), 2000)
            worst = max(worst, float(np.max(_predict(dyn, node, sched, grid)[2])))
            peak_k, ex_t, ex_pk = worst + switching, np.empty(0), np.empty(0)
        safety = _SAFETY_K if dyn.linear else _NONLINEAR_SAFETY_K
        excess = peak_k - (lim_k - safety)
        if excess <= 0:
            break
        margin += excess + _SAFETY_K
    else:  # pragma: no cover - the margin iteration converges in 1-3 rounds
        raise SimulationError("drive: the junction-peak margin iteration did not converge")
    schedule = _schedule(intervals, hold_duty, period)

    # -- predictions on a time grid ------------------------------------------------------
    marks = tuple(t for t, _ in schedule)
    t_grid = _time_grid(period, horizon, marks, 2000)
    drive = _predict(dyn, node, schedule, t_grid)
    const = _predict(dyn, node, ((0.0, hold_duty),), t_grid)
    t_drive = _settle_refined(dyn, node, schedule, t_grid, drive[0], tgt_k, tol_k)
    t_const = _settle_refined(dyn, node, ((0.0, hold_duty),), t_grid, const[0], tgt_k, tol_k)
    if not dyn.linear:  # averaged nonlinear simulation + ripple, plus the switching margin
        peak_k = max(peak_k, float(np.max(drive[2])) + switching)

    method = "profile"
    tp = _two_phase(dyn, node, lim_k - margin, tgt_k, tol_k, hold_duty, horizon) \
        if two_phase and dyn.linear else None
    if tp is not None and work.is_linear:
        tp_sched = _schedule([(0, round(tp.boost_s / period), tp.boost_duty)], hold_duty, period)
        tp_peak, _, _ = _junction_peak(dyn, [(0, round(tp.boost_s / period), tp.boost_duty)],
                                       hold_duty, horizon)
        tp = TwoPhase(tp.boost_s, tp.boost_duty,
                      _settle_refined(dyn, node, tp_sched, t_grid,
                                      _predict(dyn, node, tp_sched, t_grid)[0], tgt_k, tol_k),
                      ambient_c + tp_peak)
    if tp is not None and tp.time_to_target_s < t_drive and tp.peak_junction_c <= t_max_c:
        method = "two-phase"
        n_b = round(tp.boost_s / period)
        intervals = [(0, n_b, tp.boost_duty)]
        schedule = _schedule(intervals, hold_duty, period)
        peak_k, ex_t, ex_pk = _junction_peak(dyn, intervals, hold_duty, horizon)
        drive = _predict(dyn, node, schedule, t_grid)
        t_drive = tp.time_to_target_s

    release = _release(dyn, node, x_hold, release_c, keep_warm_duty, ambient_c, target_c,
                       horizon) if release_c is not None else None
    duty = np.array([schedule[max(0, int(np.searchsorted([s[0] for s in schedule], t,
                                                           side="right")) - 1)][1]
                     for t in t_grid])
    trace = DriveTrace(
        t_s=t_grid, duty=duty, node_c=ambient_c + drive[0], junction_mean_c=ambient_c + drive[1],
        junction_peak_c=ambient_c + drive[2], constant_node_c=ambient_c + const[0],
        constant_junction_peak_c=ambient_c + const[2], exact_t_s=ex_t,
        exact_peak_c=ambient_c + ex_pk)
    return DriveResult(
        model=work, node=node, t_max_c=t_max_c, target_c=target_c, ambient_c=ambient_c,
        p_max_w=float(p_max_w), f_pwm_hz=float(f_pwm_hz), tol_k=tol_k,
        hold_duty=hold_duty, hold_peak_junction_c=ambient_c + hold_peak_k, schedule=schedule,
        method=method, time_to_target_s=t_drive, constant_duty_time_to_target_s=t_const,
        peak_junction_c=ambient_c + peak_k,
        peak_method="exact switched PWM" if dyn.linear else "average + periodic ripple",
        two_phase=tp, release=release, trace=trace, ripple_margin_k=margin)


def _surrogate_margin(dyn: _Dynamics, node: int, lim_k: float, tgt_k: float, tol_k: float,
                      duty_step: float, horizon: float) -> float:
    """Switching margin of a nonlinear model, from its linear surrogate.

    How far the averaged + ripple limit must be tightened for the exact switched peak to
    respect it comes from the fast stages over a few periods; it is taken from the linear
    ladder with its resistances scaled to the junction limit (temperature coefficient).
    """
    lad = dyn.model.ladder
    s = dyn.scale(lim_k)
    scaled = type(lad)(np.asarray(lad.r) * s, lad.c)
    sur = _Dynamics(ThermalModel(scaled), dyn.tref, dyn.p, 1 / dyn.period)
    try:
        hold = _hold_duty(sur, node, tgt_k)
    except DataFormatError:
        return 0.0
    x_hold = sur.steady(sur.p * hold)
    margin = 0.0
    for _ in range(6):
        steps, _, arrival = _greedy(sur, node, lim_k - margin, tgt_k, hold, x_hold,
                                    0.5 * tol_k, 0.01, horizon)
        peak, _, _ = _junction_peak(sur, _compress(_smooth(steps, arrival), duty_step), hold,
                                    horizon)
        excess = peak - (lim_k - _SAFETY_K)
        if excess <= 0:
            break
        margin += excess + _SAFETY_K
    return margin


def _safe_dc_power(model: ThermalModel, ambient_c: float, lim_k: float) -> float:
    """Largest constant power whose steady junction rise is ``lim_k``."""
    if model.is_linear:
        return lim_k / model.rth
    from scipy.optimize import brentq

    hi = lim_k / model.rth
    while model.steady_nodes(hi, ambient_c)[0] < lim_k:
        hi *= 2
    return float(brentq(lambda p: model.steady_nodes(p, ambient_c)[0] - lim_k, 0.0, hi,
                        xtol=1e-12))


def _hold_duty(dyn: _Dynamics, node: int, tgt_k: float) -> float:
    full = dyn.steady(dyn.p)[node]
    if full < tgt_k:
        raise DataFormatError(
            f"target not reachable: even at duty 1 ({dyn.p:g} W) the node settles at "
            f"{dyn.tref + full:.2f} °C < {dyn.tref + tgt_k:g} °C; raise p_max")
    if dyn.linear:
        return float(tgt_k / full)
    from scipy.optimize import brentq

    return float(brentq(lambda d: dyn.steady(dyn.p * d)[node] - tgt_k, 0.0, 1.0, xtol=1e-12))


def _schedule(intervals: list[tuple[int, int, float]], hold_duty: float, period: float
              ) -> tuple[tuple[float, float], ...]:
    out = [(first * period, float(d)) for first, n, d in intervals if n > 0]
    end = intervals[-1][0] + intervals[-1][1] if intervals else 0
    merged: list[tuple[float, float]] = []
    for t, d in [*out, (end * period, float(hold_duty))]:
        if merged and merged[-1][1] == d:
            continue
        merged.append((t, d))
    return tuple(merged)


def _junction_peak(dyn: _Dynamics, intervals: list[tuple[int, int, float]], hold_duty: float,
                   horizon: float) -> tuple[float, NDArray, NDArray]:
    """Max junction peak rise of a schedule: exact switched (linear) or averaged + ripple."""
    if dyn.linear:
        t, pk = _switched_peaks(dyn, intervals, hold_duty, int(horizon / dyn.period) + 1)
        return float(pk.max()), t, pk
    sched = _schedule(intervals, hold_duty, dyn.period)
    t = _time_grid(dyn.period, horizon, tuple(s[0] for s in sched), 1200)
    _, _, jp = _predict(dyn, 0, sched, t)
    return float(jp.max()), np.empty(0), np.empty(0)


def _predict(dyn: _Dynamics, node: int, schedule: tuple[tuple[float, float], ...],
             t: NDArray) -> tuple[NDArray, NDArray, NDArray]:
    """Node rise, junction mean rise and junction peak (mean + ripple) on ``t``."""
    sched = Schedule(tuple(s[0] for s in schedule), tuple(dyn.p * s[1] for s in schedule))
    tr = dyn.model.simulate(t, sched, dyn.tref)
    times = np.array([s[0] for s in schedule])
    duties = np.array([s[1] for s in schedule])
    # the ripple of a new duty builds up over its first period: until then the previous one's
    lag = t - dyn.period
    d = duties[np.clip(np.searchsorted(times, lag, side="left") - 1, 0, None)]
    if dyn.linear:
        rip = dyn.ripple(d)
    else:
        rip = np.array([float(dyn.ripple(di, j)) for di, j in zip(d, tr.tj_k, strict=True)])
    return tr.theta_k[:, node], tr.tj_k, tr.tj_k + rip


def _settle_refined(dyn: _Dynamics, node: int, schedule: tuple[tuple[float, float], ...],
                    t: NDArray, y: NDArray, tgt_k: float, tol: float) -> float:
    ts, i = _settle(t, y, tgt_k, tol)
    if not dyn.linear or i < 0 or not math.isfinite(ts):
        return ts
    sched = Schedule(tuple(s[0] for s in schedule), tuple(dyn.p * s[1] for s in schedule))

    def f(tt: float) -> float:
        val = dyn.model.simulate([tt], sched, dyn.tref).theta_k[0, node]
        return abs(val - tgt_k) - tol

    return _bisect(f, float(t[i]), float(t[i + 1]))


def _release(dyn: _Dynamics, node: int, x_hold: NDArray, release_c: float,
             keep_warm_duty: float, ambient_c: float, target_c: float,
             horizon: float) -> Release:
    release_c = _check("release_c", release_c)
    if not release_c < target_c:
        raise DataFormatError(f"release_c = {release_c:g} °C must be below the target "
                              f"{target_c:g} °C")
    rel_k = release_c - ambient_c
    floor = dyn.steady(dyn.p * keep_warm_duty)[node]
    if floor >= rel_k:
        raise DataFormatError(
            f"release below {release_c:g} °C is not reachable at keep-warm duty "
            f"{keep_warm_duty:g}: the node settles at {ambient_c + floor:.2f} °C")
    sched = Schedule((0.0,), (dyn.p * keep_warm_duty,))
    t = _time_grid(dyn.period, horizon, (), 1500)
    y = dyn.model.simulate(t, sched, ambient_c, x_hold).theta_k[:, node]
    below = np.nonzero(y <= rel_k)[0]
    if below.size == 0:  # pragma: no cover - the floor check makes this unreachable
        raise SimulationError("release: the node did not fall below the release temperature")
    i = int(below[0])
    if i == 0:
        return Release(release_c, float(keep_warm_duty), 0.0)
    if dyn.linear:
        def f(tt: float) -> float:
            return dyn.model.simulate([tt], sched, ambient_c, x_hold).theta_k[0, node] - rel_k

        ts = _bisect(f, float(t[i - 1]), float(t[i]))
    else:
        w = (y[i - 1] - rel_k) / (y[i - 1] - y[i])
        ts = float(t[i - 1] + w * (t[i] - t[i - 1]))
    return Release(release_c, float(keep_warm_duty), ts)
