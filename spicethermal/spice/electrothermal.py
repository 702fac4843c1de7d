"""The heater as an electrothermal part: one subcircuit ``NAME A K TJ TREF`` in which the diode's
current follows its fitted Vf(I, T) at the junction temperature, its dissipation I·V heats the
thermal ladder (and the ladder's device effects), and the junction temperature is a pin.

The ladder and its device effects are written by the thermal ``.lib`` writer's own context
(:func:`spicethermal.spice.lib.lib_context`: each effect plugin renders itself); the diode is
written from :class:`~spicethermal.core.diode.DiodeLaw`'s SPICE rendering: a series resistor,
the junction current as a behavioural source whose value sits on helper nodes (``DT`` the
junction temperature in kelvin, ``DX`` the exponent, ``DI`` the current), and the heat
``V(DI)·V(A,K)`` into the junction. Every expression uses ``EXP``, ``LOG``, ``MIN``, ``MAX``
only (no ``limit()``, a random function in ngspice), so one rendering serves ngspice, PSPICE and
LTspice (tested under ngspice's ``ps`` and ``lt`` modes).

>>> from spicethermal.core.diode import DiodeLaw
>>> from spicethermal.core.ladder import Foster
>>> from spicethermal.model import ThermalModel
>>> m = ThermalModel(Foster.from_tau([100.0], [1.0]), electrical=DiodeLaw(n=1.8, is_a=2e-9))
>>> ".SUBCKT HEATER A K TJ TREF PARAMS: TOFFSET=25" in render_electrothermal(m, name="HEATER")
True
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING

from ..core.errors import DataFormatError
from ..io.files import atomic_write_text
from .lib import DIALECTS, lib_context
from .ngspice import sanitize_comment
from .pins import Pins
from .templates import environment

if TYPE_CHECKING:  # pragma: no cover
    from ..model import ThermalModel

#: A resistor across the junction (Ω): keeps its node defined where the exponential's slope
#: vanishes (reverse bias, a Newton iterate far off); 0.6 nA at 0.6 V.
LEAK_OHM = 1e9
#: The default pins of an electrothermal part.
PINS = Pins("TJ", "TREF", None, ("anode", "cathode", "junction", "reference"), "A", "K")


def missing_law(model: ThermalModel, source: str = "the model") -> str:
    """The one line that says why ``model`` has no electrothermal part, or ``""``.

    >>> from spicethermal.core.ladder import Foster
    >>> from spicethermal.model import ThermalModel
    >>> missing_law(ThermalModel(Foster.from_tau([1.0], [1.0])), "m.json")[:55]
    'm.json has no diode law Vf(I, T) (the electrical key of'
    """
    if model.electrical is not None:
        return ""
    return (f"{source} has no diode law Vf(I, T) (the electrical key of spicethermal-model/4): "
            "fit a bundle with forward-voltage points (spicethermal-bundle/3, measured by 'bench "
            "calibrate' with firmware 1.2) to get one; the thermal model works as before without "
            "--electrothermal or --circuit")


def render_electrothermal(model: ThermalModel, dialect: str = "ngspice",
                          topology: str | None = None, name: str | None = None,
                          filename: str = "model.lib", *, pins: Pins | None = None,
                          temperature: str = "rise") -> str:
    """The electrothermal subcircuit of ``model`` (which needs its ``electrical`` law) as text.

    Parameters
    ----------
    model : ThermalModel
        A model with a diode law (``model.electrical``).
    dialect, topology, name, filename, temperature
        As for :func:`spicethermal.spice.lib.render_lib`.
    pins : Pins, optional
        Pin names and order (default ``A K TJ TREF``; thermal pins alone get ``A K`` in front).

    Returns
    -------
    str
        The ``.lib`` text.
    """
    problem = missing_law(model)
    if problem:
        raise DataFormatError(problem)
    law = model.electrical
    assert law is not None
    pins = pins or PINS
    if not pins.electrical:
        pins = Pins(pins.junction, pins.reference, pins.ambient,
                    ("anode", "cathode", *pins.order), "A", "K")
    ctx = lib_context(model, dialect, topology, name, filename, pins=pins,
                      temperature=temperature)
    offset = ctx["offset"]
    kelvin = law.spice_kelvin(f"V({pins.junction}){offset}")
    junction = "DJ" if law.rs_ohm > 0 else pins.anode
    facts = []
    rms = law.fit.get("rms_v")
    if isinstance(rms, Mapping):
        facts.append("Fit residual: " + "; ".join(
            f"{1e3 * float(v):.3g} mV rms over the {k} points" for k, v in rms.items()))
    if law.valid_i_a is not None and law.valid_t_c is not None:
        facts.append(f"Valid for I from {law.valid_i_a[0]:.3g} A to {law.valid_i_a[1]:.3g} A "
                     f"and Tj from {law.valid_t_c[0]:.4g} degC to {law.valid_t_c[1]:.4g} degC "
                     "(the data's; outside them the law extrapolates)")
    if law.sense_current_a is not None:
        facts.append(f"TSP calibrated at a sense current of {law.sense_current_a:.4g} A")
    ctx.update(
        electrothermal=True, rs=law.rs_ohm, junction=junction, knee_a=law.knee_current_a,
        law_line=sanitize_comment(law.describe()), model_card=law.model_card(),
        law_facts=[sanitize_comment(x) for x in facts], kelvin=kelvin,
        exponent=law.spice_exponent(f"V({junction},{pins.cathode})", "V(DT)"),
        current=law.spice_current("V(DX)", "V(DT)"), leak_ohm=LEAK_OHM,
        usage_nodes=[{"anode": "A", "cathode": "0"}.get(r, n)
                     for r, n in zip(pins.order, ctx["usage_nodes"], strict=True)])
    return environment().get_template("lib/electrothermal.lib.j2").render(**ctx)


def export_electrothermal(model: ThermalModel, path: str | os.PathLike,
                          dialect: str = "ngspice", topology: str | None = None,
                          name: str | None = None, *, pins: Pins | None = None,
                          temperature: str = "rise") -> Path:
    """Write the electrothermal subcircuit atomically and return its path
    (:func:`render_electrothermal`).

    Parameters
    ----------
    model : ThermalModel
        A model with a diode law.
    path : str or os.PathLike
        The ``.lib`` file to write.
    dialect, topology, name, pins, temperature
        As for :func:`render_electrothermal`.

    Returns
    -------
    Path
        The path written.
    """
    if dialect not in DIALECTS:
        raise DataFormatError(f"dialect {dialect!r}: expected one of {', '.join(DIALECTS)}")
    path = Path(path)
    text = render_electrothermal(model, dialect, topology, name, path.name, pins=pins,
                                 temperature=temperature)
    return atomic_write_text(path, text)


__all__ = ["PINS", "export_electrothermal", "missing_law", "render_electrothermal"]
