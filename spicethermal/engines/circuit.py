"""The paper's bench circuit (Fig. 3) around the electrothermal heater, in ngspice: PWM readings
as the bench takes them, through the diode itself.

The deck (``templates/bench/fig3.cir.j2``, golden copy in ``netlists/``): the heater ``X1`` and
the reference diode ``X2`` beside it at the ambient, both the electrothermal part
(:mod:`spicethermal.spice.electrothermal`); the sense current ``I_cal`` through each (block B);
the microcontroller's PWM ``S_C`` closing switch S, which adds the heating current ``I_S`` of
block A; the TSP ``V(A) − V(AR)`` (the INA112). The heating current is what the firmware's
power loop settles to: the current whose dissipation, at the junction temperature of an
on-phase reading (its middle, in the periodic steady state), adds the set power to the sense
current's (:meth:`~spicethermal.core.diode.DiodeLaw.heating_current`). The TSP is read as the
bench reads it: switch S opens at the end of an on-phase, the sense current alone flows through
the sample window, and at its end the TSP goes through the calibration
(:meth:`~spicethermal.core.diode.DiodeLaw.bench_temperature`, with the reference diode at the
ambient); with no window (a bench with an ideal track-and-hold) the junction at the cut is
read. Peak, mean and valley are the junction's rises less the sense current's steady heating,
on the thermal model's footing.

Runs start in the periodic steady state (node temperatures of the heater from the thermal
model, the sense current's steady heating added) and are accepted only when periodic, as
:class:`~spicethermal.engines.pwmsim.SpicePwm` runs are (:func:`periodic_state`).
"""

from __future__ import annotations

import tempfile
from collections.abc import Sequence
from dataclasses import dataclass, replace
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from .. import __version__
from ..core.errors import DataFormatError
from ..core.network import Schedule
from ..spice.electrothermal import missing_law, render_electrothermal
from ..spice.lib import DIALECTS, initial_conditions
from ..spice.ngspice import sanitize_comment, simulator
from ..spice.templates import environment
from .pwm import PwmState, check_drive
from .pwmsim import EDGE_TAU, SpicePwm, periodic_state, pwm_waveform, resolve_engine

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

    from ..core.diode import DiodeLaw
    from ..model import ThermalModel

#: The subcircuit name in the decks.
PART = "HEATER"
#: Vectors a run returns: the heater's voltage, its junction current, the junction, the TSP.
VECTORS = ("V(A)", "V(X1.DI)", "V(TJ)", "V(TSP)")


def render_circuit(lib_path: str | Path, *, ambient_c: float, i_sense_a: float,
                   i_heat_a: float, tstop_s: float, tmax_s: float, dialect: str = "ngspice",
                   gate: Sequence[tuple[float, float]] = (), gate_lines: Sequence[str] = (),
                   gate_ohm: float = 1.0, ic: Sequence[tuple[str, float]] = (),
                   reltol: float = 1e-4, trtol: float = 0.5,
                   title: str = "spicethermal bench circuit", description: str = "",
                   lib_text: str = "") -> str:
    """The Fig. 3 deck around the electrothermal part ``HEATER`` in ``lib_path``.

    Parameters
    ----------
    lib_path : str or Path
        The electrothermal ``.lib`` (rise temperatures, pins ``A K TJ TREF``).
    ambient_c, i_sense_a, i_heat_a : float
        The ambient (°C), the sense current and the heating current (A).
    tstop_s, tmax_s : float
        The transient's end and largest step, s.
    dialect : str
        The dialect the deck's own behavioural elements are written in (the ``.lib``'s).
    gate : sequence of (float, float)
        The PWM ``S_C`` as PWL corners (0 open, 1 closed), or else
    gate_lines, gate_ohm : sequence of str, float
        current sources into node ``SC`` loaded by ``gate_ohm`` (a drive's sources, whose
        amplitude times ``gate_ohm`` is 1).
    ic : sequence of (str, float)
        ``.ic`` node voltages.
    reltol, trtol : float
        ngspice's tolerances.
    title, description : str
        The deck's first lines.
    lib_text : str
        The ``.lib`` itself, written into the deck instead of included (a deck on its own).

    Returns
    -------
    str
        The deck.
    """
    if dialect not in DIALECTS:
        raise DataFormatError(f"dialect {dialect!r}: expected one of {', '.join(DIALECTS)}")
    return environment().get_template("bench/fig3.cir.j2").render(
        title=sanitize_comment(title), description=sanitize_comment(description),
        version=__version__, lib_path=str(lib_path), name=PART, ambient_c=ambient_c,
        i_sense_a=i_sense_a, i_heat_a=i_heat_a, gate=list(gate), gate_lines=list(gate_lines),
        gate_ohm=gate_ohm, ic=list(ic), dialect=dialect, reltol=reltol, trtol=trtol,
        lib_text=lib_text,
        tstep_s=tmax_s, tstop_s=tstop_s, tmax_s=tmax_s)


@dataclass(frozen=True, eq=False)
class CircuitRun:
    """One run of the bench circuit: the state as the bench reads it, and its waveforms.

    Attributes
    ----------
    state : PwmState
        Peak, mean and valley of the junction (rises less the sense current's heating) and the
        reading through the TSP, K over the ambient.
    t_s, vf_v, i_a, tj_c : NDArray
        The heater's voltage, its junction current and the junction temperature (°C) against
        time from the periodic start.
    i_heat_a : float
        The heating current the power loop settled to, A.
    drift_k : float
        How far the last period strayed from the first.
    dialect : str
        The dialect run.
    ambient_c : float
        The ambient, °C.
    """

    state: PwmState
    t_s: NDArray
    vf_v: NDArray
    i_a: NDArray
    tj_c: NDArray
    i_heat_a: float
    drift_k: float
    dialect: str
    ambient_c: float


@dataclass(frozen=True)
class CircuitPwm(SpicePwm):
    """PWM readings of ``model``'s electrothermal part in the bench circuit, in ngspice.

    The parameters are :class:`~spicethermal.engines.pwmsim.SpicePwm`'s (``tref_c`` is the
    ambient); ``model`` needs a diode law (``model.electrical``) that names its sense current.
    :meth:`state` and :meth:`grid` are :class:`SpicePwm`'s, over :meth:`run`.

    Attributes
    ----------
    model : ThermalModel
        The model, with its diode law.
    engine : str
        ``ngspice`` (``ngspice -b``) or ``pyspice`` (libngspice in process).
    dialect : str
        The ``.lib`` dialect exported and run.
    topology : str or None
        The ladder's topology in the part (default the model's; Cauer with device effects).
    tref_c : float
        The ambient, °C.
    periods : int
        Whole periods simulated from the periodic start (the first checked against the last).
    tol_k, rel_tol : float
        The periodicity tolerance: K, and relative to the ripple.
    points_per_period : int
        The largest time step, as a fraction of the period.

    Examples
    --------
    >>> from spicethermal.core.diode import DiodeLaw
    >>> from spicethermal.core.ladder import Foster
    >>> from spicethermal.model import ThermalModel
    >>> law = DiodeLaw(n=1.75, is_a=2.5e-9, rs_ohm=0.57, sense_current_a=1e-3)
    >>> sim = CircuitPwm(ThermalModel(Foster.from_tau([100.0], [1e-3]), electrical=law))
    >>> round(sim.heating_current(0.094, 1e3, 0.5), 4)
    0.1104
    """

    def __post_init__(self) -> None:
        problem = missing_law(self.model)
        if problem:
            raise DataFormatError(problem)
        if self.law.sense_current_a is None:
            raise DataFormatError("the diode law names no sense current: the bench circuit "
                                  "reads the TSP through it (fit it with the calibration)")
        super().__post_init__()

    @property
    def law(self) -> DiodeLaw:
        """The diode law."""
        assert self.model.electrical is not None
        return self.model.electrical

    @cached_property
    def lib_text(self) -> str:
        """The electrothermal subcircuit (``.SUBCKT HEATER A K TJ TREF``, rise temperatures)."""
        return render_electrothermal(self._model, self.dialect, name=PART,
                                     filename="heater.lib", temperature="rise")

    @cached_property
    def sense_power_w(self) -> float:
        """The sense current's dissipation at the ambient, W."""
        v = float(self.law.bench_voltage(self.tref_c, self.model.rth))
        return float(self.law.sense_current_a) * v

    def _start(self, power_w: float, freq_hz: float, duty: float) -> NDArray:
        """Node rises at an on-phase start: the PWM's periodic state plus the sense current's
        steady heating."""
        theta = self._model.pwm_initial_state(power_w, freq_hz, duty, self.tref_c,
                                              tol_k=self.tol_k / 10)
        return theta + self._model.steady_nodes(self.sense_power_w, self.tref_c)

    def heating_current(self, power_w: float, freq_hz: float, duty: float) -> float:
        """The heating current the power loop settles to (see the module's text), A."""
        theta = self._start(power_w, freq_hz, duty)
        half = 0.5 * duty / freq_hz
        mid = self._model.simulate([half], Schedule.step(power_w + self.sense_power_w),
                                   self.tref_c, theta)
        return self.law.heating_current(power_w, self.tref_c + float(mid.tj_k[0]))

    def netlist(self, lib_path: str | Path, power_w: float,  # type: ignore[override]
                freq_hz: float, duty: float, window_s: float = 0.0) -> tuple[str, float, float]:
        """The deck for one operating point, its reading time and its heating current."""
        tau_min = float(self._model.ladder.time_constants()[0])
        gate, t_read = pwm_waveform(1.0, freq_hz, duty, self.periods, window_s,
                                    EDGE_TAU * tau_min)
        # rounded far below what matters (1 ppm, 1 nK): the same deck on every machine
        i_heat = float(f"{self.heating_current(power_w, freq_hz, duty):.9g}")
        ic = [(n, round(v, 9)) for n, v in
              initial_conditions(self._model, self._start(power_w, freq_hz, duty))]
        text = render_circuit(
            lib_path, ambient_c=self.tref_c, i_sense_a=float(self.law.sense_current_a),
            i_heat_a=i_heat, tstop_s=t_read, tmax_s=1.0 / freq_hz / self.points_per_period,
            dialect=self.dialect, gate=gate, ic=ic,
            title="spicethermal bench circuit: PWM periodic steady state",
            description=f"{freq_hz:g} Hz, duty {duty:g}, {power_w:g} W, window {window_s:g} s")
        return text, t_read, i_heat

    def run(self, power_w: float, freq_hz: float, duty: float,  # type: ignore[override]
            window_s: float = 0.0) -> CircuitRun:
        """Simulate one operating point; :class:`SimulationError` if it is not periodic."""
        check_drive(freq_hz, duty, power_w, window_s)
        if duty == 0 or power_w == 0:
            raise DataFormatError("the bench circuit needs a heating power and a duty > 0")
        with tempfile.TemporaryDirectory(prefix="spicethermal-circuit-") as tmp:
            lib = Path(tmp) / "heater.lib"
            lib.write_text(self.lib_text, encoding="utf-8")
            text, t_read, i_heat = self.netlist(lib, power_w, freq_hz, duty, window_s)
            waves = simulator(self.engine).run(text, list(VECTORS), self.dialect)
        sense_k = float(self._model.steady_nodes(self.sense_power_w, self.tref_c)[0])
        t = np.asarray(waves.t_s, dtype=float)
        keep = np.concatenate([[True], np.diff(t) > 0])  # ngspice may repeat a time point
        t, vf, i_d, tj, tsp = (np.asarray(x, dtype=float)[keep] for x in (
            t, waves["V(A)"], waves["V(X1.DI)"], waves["V(TJ)"], waves["V(TSP)"]))
        state, t, rise, drift = periodic_state(
            t, tj - sense_k, t_read, self.periods, power_w, freq_hz, duty, window_s,
            self.tol_k, self.rel_tol)
        if window_s > 0:  # the TSP at the window's end, through the calibration
            v_tsp = float(np.interp(t_read, t, tsp))
            v_ref = float(self.law.bench_voltage(self.tref_c, self.model.rth))
            reading = float(self.law.bench_temperature(v_tsp + v_ref, self.model.rth)) - \
                self.tref_c
            state = replace(state, reading_k=reading)
        return CircuitRun(state, t, vf, i_d, self.tref_c + rise + sense_k, i_heat, drift,
                          self.dialect, self.tref_c)


def pwm_points(model: ThermalModel, power_w: float, freq_hz: Sequence[float],
               duty: Sequence[float], window_s: float = 0.0, *, engine: str = "analytic",
               tref_c: float = 25.0, dialect: str = "ngspice",
               circuit: bool = False) -> list[PwmState]:
    """The periodic steady state at every ``(freq_hz[i], duty[i])``: by the named engine
    (:func:`~spicethermal.engines.pwmsim.pwm_state`'s), or through the bench circuit
    (``circuit``: ngspice or pyspice, the reading as the bench takes it).

    Parameters
    ----------
    model : ThermalModel
        The model (with a diode law for ``circuit``).
    power_w : float
        Heating power during an on-phase, W.
    freq_hz, duty : sequence of float
        The operating points, equally many.
    window_s : float
        The sample window, s.
    engine : str
        ``analytic``, ``ngspice``, ``pyspice`` or ``auto``.
    tref_c : float
        Reference (ambient) temperature, °C.
    dialect : str
        The ``.lib`` dialect of a SPICE engine.
    circuit : bool
        Through the bench circuit around the electrothermal part.

    Returns
    -------
    list of PwmState
        One per point, in order.

    Examples
    --------
    >>> from spicethermal.core.ladder import Foster
    >>> from spicethermal.model import ThermalModel
    >>> m = ThermalModel(Foster.from_tau([10.0], [1e-3]))
    >>> [round(s.mean_k, 9) for s in pwm_points(m, 0.1, [1e3, 1e3], [0.5, 0.2])]
    [0.5, 0.2]
    """
    if circuit:
        if engine not in ("ngspice", "pyspice"):
            raise DataFormatError("--circuit runs the bench circuit in ngspice: use --engine "
                                  "ngspice or pyspice")
        return CircuitPwm(model, engine, dialect, tref_c=tref_c).grid(power_w, freq_hz, duty,
                                                                      window_s)
    engine = resolve_engine(engine, model)
    if engine == "analytic":
        return [model.pwm(power_w, f, d, window_s, tref_c)
                for f, d in zip(freq_hz, duty, strict=True)]
    return SpicePwm(model, engine, dialect, tref_c=tref_c).grid(power_w, freq_hz, duty,
                                                                window_s)
