"""One interface to the simulators: the closed form, ``ngspice -b`` and ngspice in process.

Every engine answers the same two questions about a :class:`~spicethermal.model.ThermalModel`:

* ``simulate(model, schedule, t_s, tref_c)``: the junction rise (K over the reference) at
  times ``t_s`` under a piecewise-constant power :class:`~spicethermal.model.Schedule`, from
  the reference temperature (a step, an impulse of finite width, any P(t) held piece by piece);
* ``pwm_steady(model, power_w, freq_hz, duty, window_s, tref_c)``: the PWM periodic steady
  state, a :class:`~spicethermal.engines.pwm.PwmState`.

:class:`Analytic` is the exact solution of a linear ladder (modal, no time step); it refuses
a model with device effects. :class:`Spice` runs the exported subcircuit in ngspice through a
:class:`~spicethermal.spice.ngspice.Simulator` backend: ``ngspice`` (the ``ngspice -b`` binary) or
``pyspice`` (libngspice in process); it takes any model. :func:`engine` picks one by name,
``auto`` choosing the closed form for a linear model and ngspice with device effects.

>>> from spicethermal.core.ladder import Foster
>>> from spicethermal.model import Schedule, ThermalModel
>>> m = ThermalModel(Foster.from_tau([2.0], [1.0]))
>>> eng = engine("auto", m)
>>> eng.name, round(float(eng.simulate(m, Schedule.step(1.0), [1.0])[0]), 6)  # 2 (1 - 1/e)
('analytic', 1.264241)
"""

from __future__ import annotations

import tempfile
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Protocol

import numpy as np

from ..core.errors import DataFormatError, SimulationError
from ..spice.lib import reference_drive, render_bench, render_lib
from ..spice.ngspice import simulator
from .pwmsim import ENGINES, SpicePwm, resolve_engine

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import ArrayLike, NDArray

    from ..model import Schedule, ThermalModel
    from ..spice.ngspice import Simulator
    from .pwm import PwmState

#: Engine names every simulating command accepts (``--engine``).
NAMES = ("auto", *ENGINES)


class Engine(Protocol):
    """What every engine offers (module docstring)."""

    name: str

    def simulate(self, model: ThermalModel, schedule: Schedule, t_s: ArrayLike,
                 tref_c: float = 25.0) -> NDArray:
        """Junction rise (K) at ``t_s`` under ``schedule``, from the reference temperature."""

    def pwm_steady(self, model: ThermalModel, power_w: float, freq_hz: float, duty: float,
                   window_s: float = 0.0, tref_c: float = 25.0) -> PwmState:
        """PWM periodic steady state (rises over the reference)."""


class Analytic:
    """The exact solution of a linear model: modal response and closed-form PWM state.

    Examples
    --------
    >>> from spicethermal.core.ladder import Foster
    >>> from spicethermal.model import ThermalModel
    >>> m = ThermalModel(Foster.from_tau([10.0], [1e-3]))
    >>> round(Analytic().pwm_steady(m, 0.1, 1e3, 0.5).mean_k, 12)
    0.5
    """

    name = "analytic"

    @staticmethod
    def check(model: ThermalModel) -> None:
        """Refuse a model with device effects (one line naming them)."""
        if model.device_effects:
            raise DataFormatError(
                f"--engine analytic: the model has device effects "
                f"({', '.join(e.name for e in model.device_effects)}) and the analytic engine "
                f"is for linear models; use --engine ngspice (or auto)")

    def simulate(self, model: ThermalModel, schedule: Schedule, t_s: ArrayLike,
                 tref_c: float = 25.0) -> NDArray:
        self.check(model)
        return model.simulate(t_s, schedule, tref_c).tj_k

    def pwm_steady(self, model: ThermalModel, power_w: float, freq_hz: float, duty: float,
                   window_s: float = 0.0, tref_c: float = 25.0) -> PwmState:
        self.check(model)
        return model.pwm(power_w, freq_hz, duty, window_s, tref_c)


class Spice:
    """The exported subcircuit in ngspice, through the backend ``simulator``.

    Parameters
    ----------
    simulator : Simulator
        :class:`~spicethermal.spice.ngspice.NgspiceBatch` or
        :class:`~spicethermal.spice.ngspice.NgspiceShared`.
    dialect : str
        The ``.lib`` dialect exported and run.

    Examples
    --------
    >>> from spicethermal.spice.ngspice import NgspiceBatch
    >>> Spice(NgspiceBatch()).name
    'ngspice'
    """

    def __init__(self, simulator: Simulator, dialect: str = "ngspice") -> None:
        self.simulator = simulator
        self.dialect = dialect
        self.name = simulator.name

    def transient(self, model: ThermalModel, corners: Sequence[tuple[float, float]],
                  t_s: ArrayLike, tref_c: float = 25.0, description: str = "") -> NDArray:
        """Junction rise (K) at ``t_s`` under the piecewise-linear power ``corners``
        (``(t_s, power_w)``, held after the last), from the reference temperature.

        Parameters
        ----------
        model : ThermalModel
            Any model (device effects as behavioural elements).
        corners : sequence of (float, float)
            The PWL power source.
        t_s : array_like
            Output times, ascending; the run ends at the last.
        tref_c : float
            Reference temperature, degC.
        description : str
            A line for the deck's header.

        Returns
        -------
        NDArray
            The junction rise over the reference at ``t_s``.
        """
        t = np.asarray(t_s, dtype=float).ravel()
        end = float(t[-1])
        pts = [(float(a), float(p)) for a, p in corners if a <= end]
        if pts[-1][0] < end:
            pts.append((end, pts[-1][1]))
        bench_tref, toffset = reference_drive(model, tref_c)
        with tempfile.TemporaryDirectory(prefix="spicethermal-engine-") as tmp:
            lib = Path(tmp) / "dut.lib"
            lib.write_text(render_lib(model, self.dialect, name="DUT", filename="dut.lib"),
                           encoding="utf-8")
            # ngspice breaks at every PWL corner; its error control does the rest
            text = render_bench(lib, "DUT", power_w=max(p for _, p in pts), tstop_s=end,
                                tmax_s=end / 200.0, tref_c=bench_tref, toffset_c=toffset,
                                pwl=pts, title="spicethermal transient",
                                description=description or f"{len(pts)} PWL corners to {end:g} s")
            waves = self.simulator.run(text, ["V(TJ)"], self.dialect)
        tt = np.asarray(waves.t_s, dtype=float)
        rise = np.asarray(waves["V(TJ)"], dtype=float) - bench_tref
        keep = np.concatenate([[True], np.diff(tt) > 0])  # ngspice may repeat a time point
        tt, rise = tt[keep], rise[keep]
        if tt.size < 2 or tt[-1] < end * (1 - 1e-9) or not np.all(np.isfinite(rise)):
            raise SimulationError(f"{self.name} returned an incomplete waveform (ended at "
                                  f"{tt[-1] if tt.size else float('nan'):g} s of {end:g} s)")
        return np.interp(t, tt, rise)

    def simulate(self, model: ThermalModel, schedule: Schedule, t_s: ArrayLike,
                 tref_c: float = 25.0) -> NDArray:
        t = np.asarray(t_s, dtype=float).ravel()
        return self.transient(model, pwl_corners(schedule, float(t[-1])), t, tref_c)

    def pwm_steady(self, model: ThermalModel, power_w: float, freq_hz: float, duty: float,
                   window_s: float = 0.0, tref_c: float = 25.0) -> PwmState:
        return SpicePwm(model, self.name, self.dialect, tref_c=tref_c).state(
            power_w, freq_hz, duty, window_s)


def pwl_corners(schedule: Schedule, t_end_s: float, edge: float = 1e-7
                ) -> list[tuple[float, float]]:
    """A piecewise-constant schedule as PWL corners: each switch a ramp of ``edge`` (relative
    to ``t_end_s``) centred on its instant, so every piece keeps its energy; the power rises
    from 0 at t = 0.

    Parameters
    ----------
    schedule : Schedule
        The power pieces.
    t_end_s : float
        End of the run, s.
    edge : float
        Ramp duration as a fraction of ``t_end_s``.

    Returns
    -------
    list of (float, float)
        ``(t_s, power_w)`` corners, strictly increasing in time.

    Examples
    --------
    >>> from spicethermal.model import Schedule
    >>> pwl_corners(Schedule((0.0, 1.0), (2.0, 0.0)), 2.0, edge=0.01)
    [(0.0, 0.0), (0.02, 2.0), (0.99, 2.0), (1.01, 0.0)]
    """
    half = 0.5 * edge * t_end_s
    pts: list[tuple[float, float]] = [(0.0, 0.0)]
    power = 0.0
    for t, p in zip(schedule.t_s, schedule.power_w, strict=True):
        if t >= t_end_s or p == power:
            continue
        start = max(t - half, pts[-1][0]) if t > 0 else 0.0
        if start > pts[-1][0]:
            pts.append((start, power))
        pts.append((t + half if t > 0 else 2 * half, float(p)))
        power = float(p)
    return pts


def engine(name: str, model: ThermalModel | None = None, dialect: str = "ngspice") -> Engine:
    """The engine called ``name``: ``auto``, ``analytic``, ``ngspice`` or ``pyspice``.

    Parameters
    ----------
    name : str
        ``auto`` picks ``analytic`` for a linear ``model`` and ``ngspice`` with device effects.
    model : ThermalModel, optional
        The model to simulate: needed by ``auto``; ``analytic`` refuses one with device
        effects (a one-line :class:`~spicethermal.core.errors.DataFormatError`).
    dialect : str
        The ``.lib`` dialect of the SPICE engines.

    Returns
    -------
    Engine
        :class:`Analytic` or :class:`Spice`.

    Examples
    --------
    >>> engine("pyspice").name
    'pyspice'
    """
    if name not in NAMES:
        raise DataFormatError(f"--engine {name!r}: expected one of {', '.join(NAMES)}")
    if model is not None:
        name = resolve_engine(name, model)
    elif name == "auto":
        raise DataFormatError("--engine auto needs the model to choose")
    if name == "analytic":
        if model is not None:
            Analytic.check(model)
        return Analytic()
    return Spice(simulator(name), dialect)
