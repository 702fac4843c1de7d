"""A safe fast drive applied through the bench circuit (``spicethermal drive --verify
--circuit``): the schedule's PWM as the microcontroller's ``S_C``, switching the heating current
through the electrothermal heater (:mod:`spicethermal.engines.circuit`), in ngspice.

The drive is computed for a heating power ``P_max``; a current source gives power that follows
the diode's voltage, which falls as the junction heats. The heating current is set where that
power is largest, at the ambient (the cold junction of the drive's start): it adds ``P_max`` to
the sense current's dissipation there, and less once the junction is warm, so the circuit runs
at or below the power the drive assumed. The run starts cold (the DC operating point: the sense
current alone) and covers the drive's verification window at 1/100 period; the junction peak it
reaches, the sense current's heating included, is checked against ``t_max``.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..core.errors import DataFormatError
from ..engines.circuit import PART, render_circuit
from ..spice.electrothermal import missing_law, render_electrothermal
from ..spice.ngspice import simulator

if TYPE_CHECKING:  # pragma: no cover
    from .result import DriveResult


def heating_current(result: DriveResult) -> float:
    """The heating current of the drive through the circuit: ``P_max`` added to the sense
    current's dissipation with the junction at the ambient (see the module's text), A.

    Parameters
    ----------
    result : DriveResult
        A drive of a model with a diode law.

    Returns
    -------
    float
        The current, A.
    """
    law = result.model.electrical
    if law is None:
        raise DataFormatError(missing_law(result.model))
    return law.heating_current(result.p_max_w, result.ambient_c)


def circuit_deck(result: DriveResult, dialect: str = "ngspice", tstop_s: float | None = None,
                 tmax_s: float | None = None, lib_path: str | Path | None = None) -> str:
    """The bench circuit's deck of the drive: the schedule's sources into ``S_C``.

    Parameters
    ----------
    result : DriveResult
        A drive of a model with a diode law (and a sense current).
    dialect : str
        ``ngspice``, ``pspice`` or ``ltspice``.
    tstop_s, tmax_s : float, optional
        The run's end (default the verification window) and largest step (1/100 period).
    lib_path : str or Path, optional
        The electrothermal ``.lib`` to include; by default it is written into the deck.

    Returns
    -------
    str
        The deck.
    """
    law = result.model.electrical
    if law is None:
        raise DataFormatError(missing_law(result.model))
    if law.sense_current_a is None:
        raise DataFormatError("the diode law names no sense current (fit it with the "
                              "calibration)")
    model = result.model.with_topology("cauer") if result.model.device_effects else result.model
    lib = render_electrothermal(model, dialect, name=PART, filename="heater.lib",
                                temperature="rise")
    return render_circuit(
        lib_path or "heater.lib", ambient_c=result.ambient_c, i_sense_a=law.sense_current_a,
        i_heat_a=float(f"{heating_current(result):.9g}"),
        tstop_s=result.verification_window_s() if tstop_s is None else tstop_s,
        tmax_s=result.period_s / 100 if tmax_s is None else tmax_s, dialect=dialect,
        gate_lines=result.spice_sources(pin="SC", prefix="IDRV"), gate_ohm=1 / result.p_max_w,
        lib_text="" if lib_path is not None else lib,
        title="spicethermal safe fast drive through the bench circuit",
        description=f"node {result.node} to {result.target_c:g} degC, Tj peak <= "
                    f"{result.t_max_c:g} degC, {result.f_pwm_hz:g} Hz, P_max "
                    f"{result.p_max_w:g} W")


def verify_circuit(result: DriveResult, engine: str = "ngspice",
                   dialect: str = "ngspice") -> dict[str, float | str]:
    """Run the drive through the bench circuit from cold and report its junction peak.

    Parameters
    ----------
    result : DriveResult
        A drive of a model with a diode law.
    engine : str
        ``ngspice`` or ``pyspice``.
    dialect : str
        The ``.lib`` dialect.

    Returns
    -------
    dict
        ``engine``, ``dialect``, ``window_s``, ``heating_current_a``,
        ``circuit_peak_junction_c`` (the sense current's heating included),
        ``circuit_peak_at_s``, ``t_max_c`` and ``margin_k`` (``t_max`` less the peak).
    """
    wave = simulator(engine).run(circuit_deck(result, dialect), ["V(TJ)"], dialect)
    tj = result.ambient_c + np.asarray(wave["V(TJ)"], dtype=float)
    k = int(np.argmax(tj))
    return {"engine": engine, "dialect": dialect, "window_s": float(wave.t_s[-1]),
            "heating_current_a": heating_current(result),
            "circuit_peak_junction_c": float(tj[k]), "circuit_peak_at_s": float(wave.t_s[k]),
            "t_max_c": result.t_max_c, "margin_k": result.t_max_c - float(tj[k])}
