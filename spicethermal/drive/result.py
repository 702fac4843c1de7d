"""What :func:`~spicethermal.drive.optimize.optimize_drive` returns: the drive, its predicted
temperatures, and what SPICE needs to reproduce it.

:class:`DriveResult` holds the schedule and the figures of merit (time to target against the
constant duty, junction peak), prints a summary and the schedule as a table, serialises to the
``spicethermal drive --json`` document (:meth:`DriveResult.to_dict`), draws itself
(:meth:`DriveResult.plot`, through :mod:`spicethermal.viz.pwm`) and writes the current sources
and the self-contained ngspice deck of the switched drive. :class:`DriveTrace` is the predicted
trajectory on a time grid.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from .. import __version__
from ..core.errors import DataFormatError
from ..io.jsondoc import JsonDocument
from ..model import Schedule, ThermalModel
from ..spice.lib import (
    Pulse,
    environment,
    fmt,
    initial_conditions,
    reference_drive,
    render_lib,
    sanitize_comment,
)
from .dynamics import Dynamics, PeriodMap
from .release import Release
from .twophase import TwoPhase

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.axes import Axes
    from numpy.typing import NDArray


@dataclass(frozen=True, eq=False)
class DriveTrace:
    """Predicted temperatures (°C) on a time grid, for the drive and for the constant duty.

    Attributes
    ----------
    t_s : NDArray
        The time grid, s (logarithmic, with the schedule's switching times).
    duty : NDArray
        The duty in force.
    node_c, junction_mean_c : NDArray
        The node and the junction under the drive, period averages.
    junction_peak_c : NDArray
        The period-averaged junction plus the periodic ripple at the current duty.
    constant_node_c, constant_junction_peak_c : NDArray
        The node and the junction peak under the constant hold duty.
    exact_t_s, exact_peak_c : NDArray
        The exact switched junction temperatures at the ends of on-phases (linear models;
        empty otherwise).
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
class DriveResult(JsonDocument):
    """The safe fast drive found by :func:`~spicethermal.drive.optimize.optimize_drive`.

    It serialises to the ``spicethermal drive --json`` document (:meth:`to_dict`,
    :meth:`to_json`); that document holds neither the model nor the trace, so there is no
    ``from_dict``: rerun the optimisation from the model instead.

    Attributes
    ----------
    model : ThermalModel
        The model the drive was computed on (converted to Cauer for a node > 0).
    node : int
        The actuation node: 0 the junction, k Cauer node k.
    t_max_c, target_c, ambient_c : float
        Junction limit (on the PWM peak), node target (period average), ambient, °C.
    p_max_w, f_pwm_hz : float
        Heater power when on (W) and PWM frequency (Hz).
    tol_k : float
        Half-width of the band the node must settle in, K.
    hold_duty, hold_peak_junction_c : float
        The duty that holds the target and the junction peak of its periodic steady state, °C.
    schedule : tuple of (float, float)
        ``((t_s, duty), ...)``: each duty applies from its time until the next one; the last
        (the hold duty) applies forever. Times are whole PWM periods, each period starting
        with its on-phase.
    method : str
        ``"profile"`` (the greedy profile) or ``"two-phase"``.
    time_to_target_s, constant_duty_time_to_target_s : float
        Until the node settles in the band, under the drive and at the constant hold duty, s.
    peak_junction_c : float
        The largest junction peak of the drive, °C.
    peak_method : str
        ``"exact switched PWM"`` (linear model) or ``"average + periodic ripple"``.
    two_phase : TwoPhase or None
        The best two-phase drive (linear models), for comparison.
    release : Release or None
        The release from the steady hold, when asked for.
    trace : DriveTrace
        Predicted temperatures on a time grid.
    ripple_margin_k : float
        How far the averaged-plus-ripple limit had to be tightened for the exact switched
        peak to respect ``t_max`` (a measure of the averaging approximation; 0 when it was
        conservative).
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

    def to_dict(self) -> dict[str, Any]:
        """The ``spicethermal drive --json`` document (without the model and the trace).

        Returns
        -------
        dict
            The figures of merit, the parameters, ``schedule`` as ``[{"t_s", "duty"}, ...]``,
            and ``two_phase`` and ``release`` (:meth:`TwoPhase.to_dict`,
            :meth:`Release.to_dict`; None when absent).
        """
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
            "two_phase": self.two_phase.to_dict() if self.two_phase else None,
            "release": self.release.to_dict() if self.release else None,
        }

    #: Deprecated spelling of :meth:`to_dict` (kept for existing callers).
    as_json = to_dict

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
        out += [f"  {part}" for part in (self.two_phase, self.release) if part]
        return "\n".join(out)

    def plot(self, ax: Axes | None = None) -> Axes:
        """The predicted temperatures (:func:`spicethermal.viz.pwm.plot_drive`).

        Parameters
        ----------
        ax : matplotlib Axes, optional
            Where to draw (default: a new figure).

        Returns
        -------
        Axes
        """
        from ..viz.pwm import plot_drive

        return plot_drive(self, ax)

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
        >>> from spicethermal.core.ladder import Foster
        >>> from spicethermal.drive.optimize import optimize_drive
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
        >>> import spicethermal as st
        >>> ladder = st.Foster.from_tau([30.0, 70.0], [0.01, 1.0])
        >>> r = st.optimize_drive(st.ThermalModel(ladder), 70.0, 55.0, p_max_w=1.0)
        >>> bool(r.switched_state(0.0)[0] == 0.0)
        True
        """
        if not self.model.is_linear:
            raise DataFormatError("switched_state: exact only for a model without device effects")
        dyn = Dynamics(self.model, self.ambient_c, self.p_max_w, self.f_pwm_hz)
        _, v, _ = dyn.modes(np.zeros(dyn.n))
        n_end = round(t_s / self.period_s)
        firsts = [round(t / self.period_s) for t, _ in self.schedule] + [n_end]
        z = np.zeros(dyn.n)
        for (_, d), first, nxt in zip(self.schedule, firsts, firsts[1:], strict=False):
            if first >= n_end:  # (the hold, last, runs until t_s)
                break
            z = PeriodMap(dyn, d).start(z, min(nxt, n_end) - first)
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
        return self.ambient_c - reference_drive(self.model, self.ambient_c)[0]

    def verification_window_s(self, max_periods: int = 4000) -> float:
        """Span worth simulating switched: past the exact peak and the time to target."""
        t_peak = float(self.trace.exact_t_s[np.argmax(self.trace.exact_peak_c)]) \
            if self.trace.exact_t_s.size else self.time_to_target_s
        span = max(2.0 * t_peak, 1.2 * self.time_to_target_s, 20 * self.period_s)
        return min(span, max_periods * self.period_s)
