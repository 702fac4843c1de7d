"""PWM periodic steady state in ngspice, started where it ends: a few periods instead of thousands.

A cold-start transient needs about five of the slowest time constants (the actuator's is tens of
seconds) at a step of a fraction of the PWM period: millions of steps per operating point.
Here each run starts *in* the periodic steady state instead. The initial node temperatures come
from :meth:`ThermalModel.pwm_initial_state <spicethermal.model.ThermalModel.pwm_initial_state>`
(closed form for a linear model, shooting for one with device effects) and are set with ``.ic``
on the subcircuit's nodes (``TJ``, ``X1.N1``, ...: the nodal rises θ of the model's network are
exactly those node voltages relative to ``TREF``, also for a Foster ladder, whose inner nodes
hold sums of stage rises). ngspice then simulates ``periods`` periods, and the run is accepted
only if the last period repeats the first within ``tol_k`` plus ``rel_tol`` of the ripple
(else :class:`SimulationError`): that check is what makes the shortcut safe, since a wrong start
would drift, and judging it against the ripple keeps the integrator's relative error at low
frequencies (ripple of several kelvin) from passing for drift.

What a measurement reads (DESIGN.md, ``pwm.csv``): after the periodic part the power source
(a PWL) gives one more on-phase and then stays off for the sample window; the junction rise at
the window's end is the reading. Peak, valley and mean come from the last whole period. Edges
are linear ramps of 1e-4 of the period centred on the ideal switching instants, so the energy per
period and the timing of the rectangular train the closed form assumes are kept; at low
frequencies they are shortened to 1e-3 of the fastest time constant, else the fastest stage
follows the ramp and the state at a switching instant is no longer the closed form's (70 mK at
1 Hz on the actuator). The time step is bounded by the period only, not by the sample window
(the window's end is a PWL corner, so ngspice steps onto it): a 1 Hz point takes 0.1 s, not 2 s.

Independent operating points run in parallel (:meth:`SpicePwm.grid`, :func:`run_parallel`: a
process pool sized to the cores, each job shooting its start and running ``ngspice -b``).

>>> from spicethermal.core.ladder import Foster
>>> from spicethermal.model import ThermalModel
>>> m = ThermalModel(Foster.from_tau([10.0, 20.0], [1e-3, 1.0]))
>>> s = SpicePwm(m).state(0.1, 1e3, 0.5, window_s=1e-4)       # doctest: +SKIP
>>> abs(s.reading_k - m.pwm(0.1, 1e3, 0.5, 1e-4).reading_k) < 1e-3   # doctest: +SKIP
True
"""

from __future__ import annotations

import multiprocessing
import os
import tempfile
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor, ThreadPoolExecutor
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..core.errors import DataFormatError, SimulationError
from ..core.progress import bar
from ..spice.lib import (
    DIALECTS,
    TOPOLOGIES,
    initial_conditions,
    reference_drive,
    render_bench,
    render_lib,
)
from ..spice.ngspice import simulator
from .pwm import PwmState, check_drive

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

    from ..model import ThermalModel

#: PWM engines of ``spicethermal pwm`` / ``compare``: the closed form (shooting when the model
#: is nonlinear) and the two ngspice backends of :mod:`spicethermal.spice.lib`.
ENGINES = ("analytic", "ngspice", "pyspice")
#: Device effects whose exported behavioural elements ngspice runs reliably from ``.ic``; ``auto``
#: uses ngspice only for models limited to these (the phase-change element, a Gaussian
#: capacitance written with DDT, stops ngspice with "timestep too small" on the actuator ladder,
#: from a cold start as well as from the periodic steady state).
SUBCKT = "DUT"
EDGE = 1e-4  # edge time as a fraction of the period (as spice.Pulse.of)
EDGE_TAU = 1e-3  # longest edge as a fraction of the fastest time constant


@dataclass(frozen=True)
class PwmRun:
    """One ngspice PWM run: the steady state it gives and the waveform behind it.

    ``t_s`` and ``tj_k`` (junction rise over the reference) cover ``periods`` periods from the
    periodic steady state, then one more on-phase and the power-off sample window.
    ``drift_k`` is how far the last period strayed from the first (at period starts and
    on-phase ends, and in peak, valley and mean).
    """

    state: PwmState
    t_s: NDArray
    tj_k: NDArray
    periods: int
    drift_k: float
    engine: str
    dialect: str


def pwm_waveform(power_w: float, freq_hz: float, duty: float, periods: int,
                 window_s: float = 0.0, max_edge_s: float = float("inf")
                 ) -> tuple[list[tuple[float, float]], float]:
    """PWL corners of ``periods`` periods, one more on-phase, then ``window_s`` with power off.

    Ideal switching instants are ``k T`` (on) and ``(k + D) T`` (off); each edge is a linear ramp
    of ``1e-4 T`` (at most ``max_edge_s``) centred on its instant (shorter for a very small duty
    or off-time), so each period carries exactly ``P D T`` of energy. Returns the corners and the
    reading time ``(periods + D) T + window_s``, which is a corner too.

    >>> pts, t_read = pwm_waveform(1.0, 1.0, 0.5, 1)
    >>> pts[:3], t_read
    ([(0.0, 0.5), (5e-05, 1.0), (0.49995, 1.0)], 1.5)
    """
    check_drive(freq_hz, duty, power_w, window_s)
    if periods < 1:
        raise DataFormatError(f"periods = {periods}: must be at least 1")
    period = 1.0 / freq_hz
    t_read = (periods + duty) * period + window_s
    if duty == 0 or power_w == 0:
        return [(0.0, 0.0), (t_read, 0.0)], t_read
    on, off = duty * period, (1 - duty) * period
    edge = min(EDGE * period, max_edge_s)
    edge = min(edge, on / 2, off / 2) if off > 0 else edge  # corners strictly increasing
    half = edge / 2
    intervals = [(0.0, t_read - window_s)] if off == 0 else \
        [(k * period, k * period + on) for k in range(periods + 1)]
    # the run starts half-way up the first ramp (or at full power when it never switches off)
    pts: list[tuple[float, float]] = [(0.0, power_w / 2), (half, power_w)] if off else \
        [(0.0, power_w)]
    for k, (a, b) in enumerate(intervals):
        if k:
            pts += [(a - half, 0.0), (a + half, power_w)]
        pts += [(b - half, power_w), (b + half, 0.0)]
    if window_s < half:  # the reading falls on the last falling ramp: make it a corner
        pts.insert(-1, (t_read, power_w * (0.5 - window_s / edge)))
        pts = [p for p in pts if p[0] <= t_read]
    else:
        pts.append((t_read, 0.0))
    return pts, t_read


@dataclass(frozen=True)
class SpicePwm:
    """PWM periodic steady state of ``model`` in ngspice, from the periodic steady state.

    Parameters
    ----------
    model : ThermalModel
        Linear or with device effects (exported as behavioural elements).
    engine : ``"ngspice"`` (the ``ngspice -b`` binary) or ``"pyspice"`` (libngspice in
        process); see :func:`spicethermal.spice.ngspice.simulator`.
    dialect : the ``.lib`` dialect exported and run (PSPICE/LTspice under ngspice's
        compatibility modes).
    topology : ``"foster"`` or ``"cauer"`` (default: the model's own).
    tref_c : reference temperature driven on ``TREF``, °C (matters for device effects).
    periods : whole periods simulated (at least 2: the first is compared with the last).
    tol_k : largest accepted difference between the last period and the first, K, plus
        ``rel_tol`` times the ripple (peak - valley).

    Examples
    --------
    >>> from spicethermal.core.ladder import Foster
    >>> from spicethermal.model import ThermalModel
    >>> sp = SpicePwm(ThermalModel(Foster.from_tau([10.0], [1e-3])), periods=2)
    >>> sp.periods, sp.engine
    (2, 'ngspice')
    """

    model: ThermalModel
    engine: str = "ngspice"
    dialect: str = "ngspice"
    topology: str | None = None
    tref_c: float = 25.0
    periods: int = 3
    tol_k: float = 1e-3
    points_per_period: int = 50
    rel_tol: float = 1e-3

    def __post_init__(self) -> None:
        if self.engine not in ("ngspice", "pyspice"):
            raise DataFormatError(f"engine {self.engine!r}: expected ngspice or pyspice")
        if self.dialect not in DIALECTS:
            raise DataFormatError(f"dialect {self.dialect!r}: expected one of "
                                  f"{', '.join(DIALECTS)}")
        if self.topology is not None and self.topology not in TOPOLOGIES:
            raise DataFormatError(f"topology {self.topology!r}: expected one of "
                                  f"{', '.join(TOPOLOGIES)}")
        if int(self.periods) != self.periods or self.periods < 2:
            raise DataFormatError(f"periods = {self.periods!r}: must be an integer >= 2")
        if not (np.isfinite(self.tol_k) and self.tol_k > 0):
            raise DataFormatError(f"tol_k = {self.tol_k!r}: must be positive")
        if not np.isfinite(self.tref_c):
            raise DataFormatError(f"tref_c = {self.tref_c!r}: must be finite")

    # -- the exported model ----------------------------------------------------------------
    @cached_property
    def _model(self) -> ThermalModel:
        """The model in the topology that is exported (the .ic nodes are this ladder's): the
        model's own, or its Cauer form when it has device effects (their physics, and the
        model's simulation that starts the runs, are on the Cauer form's layers)."""
        own = "cauer" if self.model.device_effects else self.model.ladder.topology
        return self.model.with_topology(self.topology or own)

    @cached_property
    def lib_text(self) -> str:
        """The exported subcircuit (``.SUBCKT DUT TJ TREF``) the runs include."""
        return render_lib(self._model, self.dialect, name=SUBCKT, filename="dut.lib")

    def initial_conditions(self, power_w: float, freq_hz: float,
                           duty: float) -> list[tuple[str, float]]:
        """``.ic`` node temperatures (°C) at the start of an on-phase, periodic steady state."""
        theta = self._model.pwm_initial_state(power_w, freq_hz, duty, self.tref_c,
                                              tol_k=self.tol_k / 10)  # ample for the check
        return initial_conditions(self._model, theta, reference_drive(self._model,
                                                                      self.tref_c)[0])

    def netlist(self, lib_path: str | Path, power_w: float, freq_hz: float, duty: float,
                window_s: float = 0.0) -> tuple[str, float]:
        """The test bench for one operating point and its reading time."""
        tau_min = float(self._model.ladder.time_constants()[0])
        pts, t_read = pwm_waveform(power_w, freq_hz, duty, self.periods, window_s,
                                   EDGE_TAU * tau_min)
        bench_tref, toffset = reference_drive(self._model, self.tref_c)
        tmax = 1.0 / freq_hz / self.points_per_period
        text = render_bench(lib_path, SUBCKT, power_w=power_w, tstop_s=t_read, tmax_s=tmax,
                            tref_c=bench_tref, toffset_c=toffset, pwl=pts,
                            ic=self.initial_conditions(power_w, freq_hz, duty),
                            title="spicethermal PWM periodic steady state",
                            description=f"{freq_hz:g} Hz, duty {duty:g}, {power_w:g} W, "
                                        f"window {window_s:g} s")
        return text, t_read

    # -- running ---------------------------------------------------------------------------
    def run(self, power_w: float, freq_hz: float, duty: float,
            window_s: float = 0.0) -> PwmRun:
        """Simulate one operating point; raise :class:`SimulationError` if it is not periodic."""
        check_drive(freq_hz, duty, power_w, window_s)
        with tempfile.TemporaryDirectory(prefix="spicethermal-pwm-") as tmp:
            lib = Path(tmp) / "dut.lib"
            lib.write_text(self.lib_text, encoding="utf-8")
            text, t_read = self.netlist(lib, power_w, freq_hz, duty, window_s)
            waves = simulator(self.engine).run(text, ["V(TJ)"], self.dialect)
        rise = np.asarray(waves["V(TJ)"], dtype=float) - reference_drive(self._model,
                                                                         self.tref_c)[0]
        state, t, rise, drift = periodic_state(
            waves.t_s, rise, t_read, self.periods, power_w, freq_hz, duty, window_s,
            self.tol_k, self.rel_tol)
        return PwmRun(state, t, rise, self.periods, drift, self.engine, self.dialect)

    def state(self, power_w: float, freq_hz: float, duty: float,
              window_s: float = 0.0) -> PwmState:
        """The :class:`~spicethermal.engines.pwm.PwmState` of :meth:`run` (rises over the
        reference)."""
        return self.run(power_w, freq_hz, duty, window_s).state

    def grid(self, power_w: float | Sequence[float], freq_hz: Sequence[float],
             duty: Sequence[float], window_s: float | Sequence[float] = 0.0) -> list[PwmState]:
        """:meth:`state` at every ``(freq_hz[i], duty[i])`` (``power_w``, ``window_s`` per point
        or one), the points in parallel (:func:`run_parallel`)."""
        return run_grid(self, power_w, freq_hz, duty, window_s)


def run_grid(sim: SpicePwm, power_w: float | Sequence[float], freq_hz: Sequence[float],
             duty: Sequence[float], window_s: float | Sequence[float] = 0.0) -> list[PwmState]:
    """``sim.state`` at every ``(freq_hz[i], duty[i])`` (``power_w``, ``window_s`` per point or
    one), the points in parallel (:func:`run_parallel`); ``sim`` is any simulator with
    ``state``, ``engine`` and ``model`` (:class:`SpicePwm`, the bench circuit's
    :class:`~spicethermal.engines.circuit.CircuitPwm`).

    >>> run_grid(SpicePwm.__new__(SpicePwm), 0.1, [], [])
    []
    """
    f = np.atleast_1d(np.asarray(freq_hz, dtype=float))
    d = np.atleast_1d(np.asarray(duty, dtype=float))
    if f.shape != d.shape:
        raise DataFormatError("grid: freq_hz and duty must be equally long")
    p = np.broadcast_to(np.asarray(power_w, dtype=float), f.shape)
    w = np.broadcast_to(np.asarray(window_s, dtype=float), f.shape)
    return run_parallel([(sim, *map(float, x)) for x in zip(p, f, d, w, strict=True)])


def run_parallel(jobs: Sequence[tuple[SpicePwm, float, float, float, float]], *,
                 quiet: bool = True) -> list[PwmState]:
    """:meth:`SpicePwm.state` of every ``(sim, power_w, freq_hz, duty, window_s)``, in order.

    With device effects the jobs run in a pool of forked processes sized to the cores
    (:func:`workers`): each shoots its periodic start (CPU in Python) and runs ``ngspice -b``;
    the workers inherit the jobs (models need no pickling) and send back only the states. For
    linear models (closed-form start, the work is in ngspice) and where ``fork`` is unavailable
    the pool is of threads. ``pyspice`` jobs run in turn (its shared library runs one
    simulation at a time). Unless ``quiet``, a progress bar on stderr
    (:func:`spicethermal.core.progress.bar`).

    >>> run_parallel([])
    []
    """
    n = min(workers(), len(jobs))
    desc = "ngspice PWM points"
    if n < 2 or any(job[0].engine == "pyspice" for job in jobs):
        return [_run_job(job) for job in bar(jobs, desc=desc, quiet=quiet)]
    if all(job[0].model.is_linear for job in jobs) or \
            "fork" not in multiprocessing.get_all_start_methods():
        with ThreadPoolExecutor(n) as threads:  # the work is in ngspice: no process to fork
            return list(bar(threads.map(_run_job, jobs), total=len(jobs), desc=desc,
                            quiet=quiet))
    # forked workers inherit the modules already imported: import the shooting's once, here
    import scipy.integrate  # noqa: F401
    import scipy.linalg  # noqa: F401
    import scipy.optimize  # noqa: F401

    _FORKED_JOBS[:] = jobs
    try:
        with ProcessPoolExecutor(n, mp_context=multiprocessing.get_context("fork")) as pool:
            return list(bar(pool.map(_run_forked_job, range(len(jobs))), total=len(jobs),
                            desc=desc, quiet=quiet))
    finally:
        _FORKED_JOBS.clear()


_FORKED_JOBS: list[tuple[SpicePwm, float, float, float, float]] = []


def _run_job(job: tuple[SpicePwm, float, float, float, float]) -> PwmState:
    sim, power_w, freq_hz, duty, window_s = job
    return sim.state(power_w, freq_hz, duty, window_s)


def _run_forked_job(index: int) -> PwmState:
    return _run_job(_FORKED_JOBS[index])


def workers() -> int:
    """Parallel ngspice processes: the cores this process may use.

    >>> workers() >= 1
    True
    """
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not on Linux
        return max(1, os.cpu_count() or 1)


def periodic_state(t_s: NDArray, rise: NDArray, t_read: float, periods: int, power_w: float,
                   freq_hz: float, duty: float, window_s: float, tol_k: float,
                   rel_tol: float) -> tuple[PwmState, NDArray, NDArray, float]:
    """The periodic steady state an ngspice run from the periodic start shows, checked.

    ``rise`` is the junction rise against ``t_s`` over ``periods`` periods, one more on-phase
    and the sample window (:func:`pwm_waveform`); the run is accepted only if its last period
    repeats its first within ``tol_k`` plus ``rel_tol`` of the ripple (else
    :class:`SimulationError`). Peak, valley and mean are the last period's, the reading the
    rise at ``t_read``.

    Parameters
    ----------
    t_s, rise : NDArray
        The simulated waveform (ngspice may repeat a time point).
    t_read : float
        The reading's time, s.
    periods : int
        Whole periods simulated.
    power_w, freq_hz, duty, window_s : float
        The operating point.
    tol_k, rel_tol : float
        The periodicity tolerance, K and relative to the ripple.

    Returns
    -------
    tuple
        ``(state, t, rise, drift_k)``: the state, the waveform without repeated points and how
        far the last period strayed from the first.
    """
    t = np.asarray(t_s, dtype=float)
    rise = np.asarray(rise, dtype=float)
    keep = np.concatenate([[True], np.diff(t) > 0])  # ngspice may repeat a time point
    t, rise = t[keep], rise[keep]
    if t.size < 3 or not np.all(np.isfinite(rise)) or t[-1] < t_read * (1 - 1e-9):
        raise SimulationError(f"ngspice returned an incomplete waveform at {freq_hz:g} Hz, "
                              f"duty {duty:g} (ended at {t[-1]:g} s of {t_read:g} s)")
    period = 1.0 / freq_hz
    first = _period_summary(t, rise, 0, period, duty)
    last = _period_summary(t, rise, periods - 1, period, duty)
    drift = float(np.max(np.abs(np.subtract(last, first))))
    _, peak, valley, mean, _ = last
    tol = tol_k + rel_tol * (peak - valley)
    if not drift <= tol:
        raise SimulationError(
            f"ngspice PWM run at {freq_hz:g} Hz, duty {duty:g} is not periodic: the last of "
            f"{periods} periods differs from the first by {drift:.3g} K "
            f"(tolerance {tol:.3g} K: {tol_k:g} K + {rel_tol:g} of the ripple)")
    state = PwmState(float(freq_hz), float(duty), float(power_w), float(window_s),
                     peak_k=peak, mean_k=mean, valley_k=valley,
                     reading_k=float(np.interp(t_read, t, rise)))
    return state, t, rise, drift


def _period_summary(t: NDArray, rise: NDArray, k: int, period: float,
                    duty: float) -> tuple[float, float, float, float, float]:
    """(start value, peak, valley, mean, value at the on-phase end) of period ``k``."""
    a, b = k * period, (k + 1) * period
    inside = (t > a) & (t < b)
    tt = np.concatenate([[a], t[inside], [b]])
    vv = np.concatenate([[np.interp(a, t, rise)], rise[inside], [np.interp(b, t, rise)]])
    mean = float(np.trapezoid(vv, tt) / period)
    return (float(vv[0]), float(vv.max()), float(vv.min()), mean,
            float(np.interp(a + duty * period, t, rise)))


def pwm_state(model: ThermalModel, power_w: float, freq_hz: float, duty: float,
              window_s: float = 0.0, *, engine: str = "analytic", tref_c: float = 25.0,
              dialect: str = "ngspice", topology: str | None = None) -> PwmState:
    """Periodic steady state by the named engine (``analytic``, ``ngspice``, ``pyspice``, ``auto``).

    ``analytic`` is :meth:`ThermalModel.pwm` (closed form, or shooting with device effects);
    ``auto`` picks it for a linear model and ngspice otherwise (see :func:`resolve_engine`).

    Parameters
    ----------
    model : ThermalModel
        The model to drive.
    power_w, freq_hz, duty : float
        Pulse power (W), PWM frequency (Hz) and duty cycle (0..1).
    window_s : float
        Sample window after an on-phase, s (0 reads the peak).
    engine : str
        ``analytic``, ``ngspice``, ``pyspice`` or ``auto``.
    tref_c : float
        Reference temperature, degC.
    dialect, topology : str
        The ``.lib`` written for a SPICE engine.

    Returns
    -------
    PwmState
        Peak, mean, valley and bench reading (K above the reference).

    >>> from spicethermal.core.ladder import Foster
    >>> from spicethermal.model import ThermalModel
    >>> m = ThermalModel(Foster.from_tau([10.0], [1e-3]))
    >>> round(pwm_state(m, 0.1, 1e3, 0.5).mean_k, 12)
    0.5
    """
    engine = resolve_engine(engine, model)
    if engine == "analytic":
        return model.pwm(power_w, freq_hz, duty, window_s, tref_c)
    return SpicePwm(model, engine, dialect, topology, tref_c).state(power_w, freq_hz, duty,
                                                                     window_s)


def resolve_engine(engine: str, model: ThermalModel) -> str:
    """``auto`` → ``analytic`` for a linear model, ``ngspice`` with device effects.

    >>> from spicethermal.core.ladder import Foster
    >>> from spicethermal.model import ThermalModel
    >>> resolve_engine("auto", ThermalModel(Foster.from_tau([1.0], [1.0])))
    'analytic'
    """
    if engine == "auto":
        return "ngspice" if model.device_effects else "analytic"
    if engine not in ENGINES:
        raise DataFormatError(f"engine {engine!r}: expected auto or one of {', '.join(ENGINES)}")
    return engine
