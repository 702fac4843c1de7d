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
schedule is then checked on every on-phase (:func:`.dynamics.switched_peaks`), and any
excess (from merged steps or periods between samples) tightens the limit for a new pass. The
node, whose temperature is the period average, follows the averaged-power dynamics (exact for
the mean).
With device effects (temperature coefficient, phase change) the drive is decided on the
averaged power, one step at a time on the network frozen at the current state and advanced
by the stiff nonlinear integration, with the closed-form periodic ripple of
:mod:`spicethermal.engines.pwm` (resistances scaled to the current junction temperature) for the
peak: an approximation for ``f_pwm`` fast against the slow stages. The switching excess over
it is taken from the linear surrogate at the junction limit, and the limit is tightened until
the averaged simulation plus ripple and that margin respects ``t_max``. Both are verified in
ngspice on the switched drive (tests/test_drive.py, bench/bench_drive.py).

Where the parts live
--------------------
This module holds the search (:func:`optimize_drive`: the hold, the margin iteration, the
choice between the two drives); :mod:`.dynamics` the averaged and the exact switched network,
:mod:`.profile` the greedy profile, :mod:`.twophase` the two-phase drive, :mod:`.release` the
release, :mod:`.trajectory` the predictions and times to target of a schedule, :mod:`.result`
what is returned (:class:`DriveResult`), and :mod:`.check` the ngspice check.
"""

from __future__ import annotations

import math

import numpy as np

from ..core.errors import DataFormatError, SimulationError
from ..engines.pwm import check_drive, steady_state
from ..model import ThermalModel
from .dynamics import Dynamics
from .profile import compress, greedy, smooth
from .release import find_release
from .result import DriveResult, DriveTrace
from .trajectory import junction_peak, predict, schedule_of, settle_time, time_grid
from .twophase import TwoPhase, search_two_phase

__all__ = ["DEFAULT_DUTY_STEP", "DEFAULT_F_PWM_HZ", "DEFAULT_TOL_K", "DriveResult",
           "optimize_drive"]

DEFAULT_F_PWM_HZ = 1000.0
DEFAULT_TOL_K = 0.5
DEFAULT_DUTY_STEP = 0.005
_SAFETY_K = 2e-3  # the exact peak is brought this far under t_max by the margin iteration
_NONLINEAR_SAFETY_K = 0.05  # and the approximate one of a nonlinear model this far


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
    if release_c is not None:
        release_c = _check("release_c", release_c)
        if not release_c < target_c:
            raise DataFormatError(f"release_c = {release_c:g} °C must be below the target "
                                  f"{target_c:g} °C")
    if not isinstance(node, int | np.integer) or not 0 <= node < model.ladder.order:
        raise DataFormatError(f"node = {node!r}: the model has Cauer nodes 0.."
                              f"{model.ladder.order - 1} (0 = junction)")
    node = int(node)
    work = model.with_topology("cauer") if node > 0 else model
    lim_k, tgt_k = t_max_c - ambient_c, target_c - ambient_c
    if p_max_w is None:
        p_max_w = _safe_dc_power(work, ambient_c, lim_k)
    p_max_w = _check("p_max_w", p_max_w, positive=True)
    dyn = Dynamics(work, ambient_c, p_max_w, f_pwm_hz)
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
        steps, worst, arrival = greedy(dyn, node, lim_k - margin, tgt_k, hold_duty, x_hold,
                                       0.5 * tol_k, growth, horizon)
        intervals = compress(smooth(steps, arrival), duty_step)
        if dyn.linear:
            peak_k, ex_t, ex_pk = junction_peak(dyn, intervals, hold_duty, horizon)
        else:  # the averaged nonlinear simulation (mean + ripple) between the steps too
            sched = schedule_of(intervals, hold_duty, period)
            grid = time_grid(period, horizon, tuple(t for t, _ in sched), 2000)
            worst = max(worst, float(np.max(predict(dyn, node, sched, grid)[2])))
            peak_k, ex_t, ex_pk = worst + switching, np.empty(0), np.empty(0)
        safety = _SAFETY_K if dyn.linear else _NONLINEAR_SAFETY_K
        excess = peak_k - (lim_k - safety)
        if excess <= 0:
            break
        margin += excess + _SAFETY_K
    else:  # pragma: no cover - the margin iteration converges in 1-3 rounds
        raise SimulationError("drive: the junction-peak margin iteration did not converge")
    schedule = schedule_of(intervals, hold_duty, period)

    # -- predictions on a time grid ------------------------------------------------------
    marks = tuple(t for t, _ in schedule)
    t_grid = time_grid(period, horizon, marks, 2000)
    drive = predict(dyn, node, schedule, t_grid)
    const = predict(dyn, node, ((0.0, hold_duty),), t_grid)
    t_drive = settle_time(dyn, node, schedule, t_grid, drive[0], tgt_k, tol_k)
    t_const = settle_time(dyn, node, ((0.0, hold_duty),), t_grid, const[0], tgt_k, tol_k)
    if not dyn.linear:  # averaged nonlinear simulation + ripple, plus the switching margin
        peak_k = max(peak_k, float(np.max(drive[2])) + switching)

    method = "profile"
    tp = search_two_phase(dyn, node, lim_k - margin, tgt_k, tol_k, hold_duty, horizon) \
        if two_phase and dyn.linear else None
    if tp is not None and work.is_linear:
        boost = [(0, round(tp.boost_s / period), tp.boost_duty)]
        tp_sched = schedule_of(boost, hold_duty, period)
        tp_peak, _, _ = junction_peak(dyn, boost, hold_duty, horizon)
        tp = TwoPhase(tp.boost_s, tp.boost_duty,
                      settle_time(dyn, node, tp_sched, t_grid,
                                  predict(dyn, node, tp_sched, t_grid)[0], tgt_k, tol_k),
                      ambient_c + tp_peak)
    if tp is not None and tp.time_to_target_s < t_drive and tp.peak_junction_c <= t_max_c:
        method = "two-phase"
        n_b = round(tp.boost_s / period)
        intervals = [(0, n_b, tp.boost_duty)]
        schedule = schedule_of(intervals, hold_duty, period)
        peak_k, ex_t, ex_pk = junction_peak(dyn, intervals, hold_duty, horizon)
        drive = predict(dyn, node, schedule, t_grid)
        t_drive = tp.time_to_target_s

    release = find_release(dyn, node, x_hold, release_c, keep_warm_duty, horizon) \
        if release_c is not None else None
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


def _surrogate_margin(dyn: Dynamics, node: int, lim_k: float, tgt_k: float, tol_k: float,
                      duty_step: float, horizon: float) -> float:
    """Switching margin of a nonlinear model, from its linear surrogate.

    How far the averaged + ripple limit must be tightened for the exact switched peak to
    respect it comes from the fast stages over a few periods; it is taken from the linear
    ladder with its resistances scaled to the junction limit (temperature coefficient).
    """
    lad = dyn.model.ladder
    s = dyn.scale(lim_k)
    scaled = type(lad)(np.asarray(lad.r) * s, lad.c)
    sur = Dynamics(ThermalModel(scaled), dyn.tref, dyn.p, 1 / dyn.period)
    try:
        hold = _hold_duty(sur, node, tgt_k)
    except DataFormatError:
        return 0.0
    x_hold = sur.steady(sur.p * hold)
    margin = 0.0
    for _ in range(6):
        steps, _, arrival = greedy(sur, node, lim_k - margin, tgt_k, hold, x_hold,
                                   0.5 * tol_k, 0.01, horizon)
        peak, _, _ = junction_peak(sur, compress(smooth(steps, arrival), duty_step), hold,
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


def _hold_duty(dyn: Dynamics, node: int, tgt_k: float) -> float:
    full = dyn.steady(dyn.p)[node]
    if full < tgt_k:
        raise DataFormatError(
            f"target not reachable: even at duty 1 ({dyn.p:g} W) the node settles at "
            f"{dyn.tref + full:.2f} °C < {dyn.tref + tgt_k:g} °C; raise p_max")
    if dyn.linear:
        return float(tgt_k / full)
    from scipy.optimize import brentq

    return float(brentq(lambda d: dyn.steady(dyn.p * d)[node] - tgt_k, 0.0, 1.0, xtol=1e-12))
