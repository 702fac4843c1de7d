"""SPICE: render subcircuits and test benches from templates, and run them in ngspice.

Templates live in ``templates/`` (shipped in the wheel as ``spicethermal/_templates``) and are
rendered with ``StrictUndefined``. The decks run in ngspice through
:mod:`spicethermal.spice.ngspice` (its simulators are re-exported here: :class:`Simulator`,
:class:`NgspiceBatch`,
:class:`NgspiceShared`, :func:`simulator`, :class:`Waveforms`).
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from .. import __version__
from ..core.errors import DataFormatError
from ..core.ladder import Cauer, Foster
from ..effects.spice import number
from ..io.files import atomic_write_text
from .ngspice import (  # the simulators, re-exported: decks rendered here run through them
    NgspiceBatch,  # noqa: F401
    NgspiceShared,  # noqa: F401
    Simulator,  # noqa: F401
    Waveforms,  # noqa: F401
    sanitize_comment,
    simulator,  # noqa: F401
)
from .pins import Pins, check_name, default_name  # noqa: F401  (names, re-exported here)
from .templates import environment, template_dir

if TYPE_CHECKING:  # pragma: no cover
    from ..effects import Effect
    from ..model import ThermalModel

DIALECTS = ("ngspice", "pspice", "ltspice")
TOPOLOGIES = ("foster", "cauer")
#: Temperature conventions of an exported subcircuit (see :func:`render_lib`).
TEMPERATURES = ("absolute", "rise")
#: Stages whose resistance is below this fraction of Rth are merged before export.
NEGLIGIBLE = 1e-9


# ------------------------------------------------------------------------------ templates
#: The one template environment is :func:`spicethermal.spice.templates.environment` (importable
#: from here as before); this alias serves callers that predate it.
_template_dir = template_dir


#: A number in SPICE syntax with full double precision (no engineering suffixes).
fmt = number


def simulator_ready(ladder: Foster | Cauer) -> tuple[Foster | Cauer, list[str]]:
    """The ladder without stages that make a simulator fail, and what was changed.

    A stage whose resistance is below :data:`NEGLIGIBLE` of Rth (an exact conversion can
    produce R = 1e-22 K/W with C = 1e16 J/K: "timestep too small") is merged: a Foster stage
    into the stage of nearest time constant (its R added, that τ kept), a Cauer resistor by
    joining its two nodes (their capacitances added). Zth changes by less than the merged R.

    >>> from spicethermal.core.ladder import Foster
    >>> lad, notes = simulator_ready(Foster.from_tau([1.0, 2.4e-22, 2.0], [1e-3, 2e-6, 1.0]))
    >>> lad.order, notes[0].startswith("1 stage")
    (2, True)
    """
    tiny = NEGLIGIBLE * ladder.rth
    r = list(ladder.r)
    merged = 0.0
    count = 0
    if isinstance(ladder, Foster):
        tau = list(ladder.tau)
        while len(r) > 1 and min(r) < tiny:
            i = int(np.argmin(r))
            j = min((k for k in range(len(r)) if k != i),
                    key=lambda k: abs(np.log(tau[k] / tau[i])))
            r[j] += r[i]
            merged, count = merged + r.pop(i), count + 1
            tau.pop(i)
        out: Foster | Cauer = Foster.from_tau(r, tau) if count else ladder
    else:
        c = list(ladder.c)
        for i in range(len(r) - 2, -1, -1):
            if r[i] < tiny:
                merged, count = merged + r.pop(i), count + 1
                c[i] += c.pop(i + 1)
        out = Cauer(r, c) if count else ladder
    notes = [f"{count} stage{'s' if count > 1 else ''} with R < {NEGLIGIBLE:g} Rth merged into "
             f"a neighbour (Zth changes by < {merged:.3g} K/W)"] if count else []
    return out, notes


def _provenance_lines(provenance: Mapping) -> list[str]:
    lines = []
    for key, value in provenance.items():
        if isinstance(value, Mapping | list | tuple):
            continue  # structured provenance stays in the model file
        lines.append(sanitize_comment(f"{key}: {value}"))
    return lines[:20]


def _stages(ladder: Foster | Cauer, pins: Pins) -> list[dict]:
    n = ladder.order
    node = [pins.junction, *[f"N{k}" for k in range(1, n)], pins.reference]
    out = []
    for k, (r, c) in enumerate(zip(ladder.r, ladder.c, strict=True)):
        a, b = node[k], node[k + 1]
        ca, cb = (a, b) if ladder.topology == "foster" else (a, pins.ground)
        out.append({"k": k + 1, "a": a, "b": b, "ca": ca, "cb": cb, "r": r, "c": c})
    return out


def _temperature(node: str, offset: str) -> str:
    """SPICE expression of a node's temperature in °C (a rise plus ``TOFFSET`` in rise mode)."""
    return f"V({node}){offset}"


def _resistance_expression(effects: Sequence[Effect], layer: int, stage: Mapping, pins: Pins,
                           offset: str) -> str | None:
    """``R·f1·f2…`` for the stage's behavioural resistance, ``None`` when no effect touches it.

    The layer's temperature is the mean of its two end nodes (the reference pin counts as a
    node: its voltage is the reference temperature).
    """
    t_layer = (f"(({_temperature(stage['a'], offset)})"
               f"+({_temperature(stage['b'], offset)}))/2")
    t_junction = _temperature(pins.junction, offset)
    factors = [f for e in effects
               if (f := e.spice_resistance_scale(layer, t_layer, t_junction)) is not None]
    return "*".join([fmt(stage["r"]), *factors]) if factors else None


def _stored_heats(effects: Sequence[Effect], nodes: Sequence[str], offset: str,
                  capacities: Sequence[float] = ()) -> list[dict]:
    """Per node, the SPICE expression of the heat stored beyond the linear capacity (the
    node's linear capacity to the thermal ground from ``capacities``: a Cauer ladder's)."""
    out = []
    for index, node in enumerate(nodes):
        c_node = float(capacities[index]) if index < len(capacities) else 0.0
        terms = [q for e in effects
                 if (q := e.spice_stored_heat(index, _temperature(node, offset), c_node))
                 is not None]
        if terms:
            out.append({"node": node, "expr": "+".join(terms)})
    return out


def internal_nodes(model: ThermalModel) -> list[str]:
    """Names of the ladder nodes inside the subcircuit, junction first (``TJ``, ``N1``, ...)."""
    return ["TJ", *[f"N{k}" for k in range(1, model.ladder.order)]]


def initial_conditions(model: ThermalModel, theta_k: Sequence[float], tref_c: float = 0.0,
                       instance: str = "X1") -> list[tuple[str, float]]:
    """``.ic`` entries that put the subcircuit's nodes at rises ``theta_k`` over ``tref_c``.

    ``theta_k`` are node rises in the order of :func:`internal_nodes` (the nodal state of
    :class:`~spicethermal.model.ThermalModel`); the junction is the pin ``TJ`` itself.

    >>> from spicethermal.core.ladder import Foster
    >>> from spicethermal.model import ThermalModel
    >>> initial_conditions(ThermalModel(Foster.from_tau([1, 1], [1, 2])), [2.0, 1.0], 25.0)
    [('TJ', 27.0), ('X1.N1', 26.0)]
    """
    nodes = internal_nodes(model)
    if len(theta_k) != len(nodes):
        raise DataFormatError(f"initial state has {len(theta_k)} values, the ladder "
                              f"{len(nodes)} nodes")
    names = ["TJ", *[f"{instance}.{n}" for n in nodes[1:]]]
    return [(n, float(tref_c + v)) for n, v in zip(names, theta_k, strict=True)]


def reference_drive(model: ThermalModel, tref_c: float) -> tuple[float, float | None]:
    """How a test bench puts a ``temperature="rise"`` subcircuit at reference ``tref_c``.

    Returns ``(volts on TREF, TOFFSET or None)``. A linear model takes the temperature on
    ``TREF`` itself. A model with device effects gets ``TREF`` grounded and the temperature as
    its ``TOFFSET`` parameter: ngspice's truncation-error control stalls ("timestep too small")
    at tight tolerances when every node sits at a large DC offset, so node voltages are kept
    as rises and only the behavioural expressions add the offset.

    >>> from spicethermal.core.ladder import Foster
    >>> from spicethermal.model import ThermalModel
    >>> reference_drive(ThermalModel(Foster.from_tau([1], [1])), 25.0)
    (25.0, None)
    """
    return (0.0, float(tref_c)) if model.device_effects else (float(tref_c), None)


_REFERENCE_LABEL = {"case": "junction-to-case", "ambient": "junction-to-ambient"}


def _facts(model: ThermalModel) -> list[str]:
    """Header lines: where the data came from, how well the ladder fits, and over what time."""
    prov = model.provenance
    lines = []
    fit = prov.get("fit")
    if isinstance(fit, Mapping) and isinstance(fit.get("rms_k_per_w"), int | float):
        rms = float(fit["rms_k_per_w"])
        lines.append(f"Fit error: rms {rms:.3g} K/W ({100 * rms / model.rth:.3g} % of Rth) "
                     f"over {fit.get('n_points', '?')} points")
    span = prov.get("valid_t_s")
    if isinstance(span, list | tuple) and len(span) == 2:
        lines.append(f"Valid from {float(span[0]):.3g} s to {float(span[1]):.3g} s (the data's "
                     "time range; outside it the ladder extrapolates)")
    return [sanitize_comment(x) for x in lines]


def render_lib(model: ThermalModel, dialect: str = "ngspice", topology: str | None = None,
               name: str | None = None, filename: str = "model.lib", *,
               pins: Pins | None = None, temperature: str = "rise") -> str:
    """The subcircuit of ``model`` as text.

    Parameters
    ----------
    model : ThermalModel
        The model to write.
    dialect : str
        ``ngspice``, ``pspice`` or ``ltspice``.
    topology : str, optional
        ``foster`` or ``cauer`` (default the model's own, or ``cauer`` when a device effect
        needs physical node temperatures, such as a local temperature coefficient, which
        refuses ``foster``; converted exactly). A Cauer
        ladder's capacitors connect to node 0, the thermal ground (or the ambient pin): it
        stays right when its reference pin is coupled to a heatsink model. A Foster ladder is
        valid only with an ideal reference.
    name : str, optional
        Subcircuit name (default :func:`default_name`).
    filename : str
        File name quoted in the usage lines of the header.
    pins : Pins, optional
        Pin names and order (default ``TJ TREF``).
    temperature : str
        ``absolute``: node voltages are temperatures in degC; the user drives the reference
        (or ambient) pin; device effects read them as they are. ``rise``: node voltages are
        rises over node 0, which stands for the ambient; device effects add the subcircuit
        parameter ``TOFFSET`` (the ambient in degC, default 25). A linear ladder's elements are
        the same in both; only the header and the effects' expressions differ.

    Returns
    -------
    str
        The ``.lib`` text.

    Examples
    --------
    >>> from spicethermal.core.ladder import Foster
    >>> from spicethermal.model import ThermalModel
    >>> text = render_lib(ThermalModel(Foster.from_tau([1.0], [1e-3])), name="DUT")
    >>> ".SUBCKT DUT TJ TREF" in text
    True
    """
    if pins is not None and pins.electrical:
        raise DataFormatError("--pins: anode and cathode pins belong to an electrothermal part "
                              "(export --electrothermal)")
    ctx = lib_context(model, dialect, topology, name, filename, pins=pins,
                      temperature=temperature)
    return environment().get_template(f"lib/{dialect}.lib.j2").render(**ctx)


def lib_context(model: ThermalModel, dialect: str = "ngspice", topology: str | None = None,
                name: str | None = None, filename: str = "model.lib", *,
                pins: Pins | None = None, temperature: str = "rise") -> dict:
    """What the ``.lib`` templates render: the checked names, the ladder's stages with the
    device effects' SPICE renderings (each effect plugin renders its own), the header's facts.

    The arguments are those of :func:`render_lib`; the electrothermal part
    (:mod:`spicethermal.spice.electrothermal`) renders the same ladder inside its subcircuit.

    Returns
    -------
    dict
        The template context (``stages``, ``heats``, ``pins``, ``offset``, header lines ...).

    Examples
    --------
    >>> from spicethermal.core.ladder import Foster
    >>> from spicethermal.model import ThermalModel
    >>> ctx = lib_context(ThermalModel(Foster.from_tau([1.0], [1e-3])), name="DUT")
    >>> ctx["name"], [s["r"] for s in ctx["stages"]]
    ('DUT', [1.0])
    """
    if dialect not in DIALECTS:
        raise DataFormatError(f"dialect {dialect!r}: expected one of {', '.join(DIALECTS)}")
    if topology is not None and topology not in TOPOLOGIES:
        raise DataFormatError(f"topology {topology!r}: expected one of {', '.join(TOPOLOGIES)}")
    if temperature not in TEMPERATURES:
        raise DataFormatError(f"temperature {temperature!r}: expected one of "
                              f"{', '.join(TEMPERATURES)}")
    pins = pins or Pins()
    name = check_name(default_name(model, filename) if name is None else name)
    model = model.with_topology(written_topology(model, topology))
    if pins.ambient and model.ladder.topology == "foster":
        raise DataFormatError("--pins: an ambient pin (thermal ground) needs --topology cauer; "
                              "a Foster ladder has no node for it")
    ladder, notes = simulator_ready(model.ladder)
    offset = "+TOFFSET" if temperature == "rise" else ""
    stages = _stages(ladder, pins)
    for layer, stage in enumerate(stages):
        stage["rexpr"] = _resistance_expression(model.device_effects, layer, stage, pins, offset)
    heats = _stored_heats(model.device_effects, [pins.junction, *internal_nodes(model)[1:]],
                          offset, ladder.c if ladder.topology == "cauer" else ())
    ctx = {
        "name": name, "dialect": dialect, "topology": ladder.topology,
        "order": ladder.order, "version": __version__, "rth": model.rth,
        "reference": model.reference, "reference_label": _REFERENCE_LABEL[model.reference],
        "filename": sanitize_comment(filename, 80), "pins": pins, "temperature": temperature,
        "offset": offset,
        "usage_nodes": [{"junction": "TJ", "reference": "TREF", "anode": "A", "cathode": "0",
                         "ambient": "TAMB" if temperature == "absolute" else "0"}[role]
                        for role in pins.order],
        "taus": [f"{t:.4g}" for t in ladder.time_constants()],
        "provenance": _provenance_lines(model.provenance), "facts": _facts(model),
        "notes": notes, "case_c": model.case_c_j_per_k if ladder.topology == "cauer" else 0.0,
        "effects": [e for e in model.device_effects],
        "stages": stages, "heats": heats, "electrothermal": False,
    }
    return ctx


def written_topology(model: ThermalModel, topology: str | None = None) -> str:
    """The topology a ``.lib`` of ``model`` is written in: ``topology``, else the model's own,
    or ``cauer`` when a device effect needs physical node temperatures (where ``foster`` is
    refused).

    >>> from spicethermal.core.ladder import Foster
    >>> from spicethermal.effects import Effect
    >>> from spicethermal.model import ThermalModel
    >>> band = Effect.create("phase-change", t_c=40.0, latent_j=0.1, node=1)
    >>> written_topology(ThermalModel(Foster.from_tau([1.0, 2.0], [1e-3, 1.0]), (band,)))
    'cauer'
    """
    local = [e for e in model.device_effects if e.physical_nodes]
    if local and topology == "foster":
        raise DataFormatError(f"--topology foster: effect {local[0].name} (form "
                              f"{local[0].form}) needs physical node temperatures; use "
                              "--topology cauer")
    return topology or ("cauer" if local else model.ladder.topology)


def export(model: ThermalModel, path: str | os.PathLike, dialect: str = "ngspice",
           topology: str | None = None, name: str | None = None, *, pins: Pins | None = None,
           temperature: str = "rise") -> Path:
    """Write the subcircuit file atomically and return its path (see :func:`render_lib`).

    Parameters
    ----------
    model : ThermalModel
        The model to write.
    path : str or os.PathLike
        The ``.lib`` file to write.
    dialect, topology, name, pins, temperature
        As for :func:`render_lib`.

    Returns
    -------
    Path
        The path written.
    """
    path = Path(path)
    text = render_lib(model, dialect, topology, name, path.name, pins=pins,
                      temperature=temperature)
    return atomic_write_text(path, text)


@dataclass(frozen=True)
class Pulse:
    """A PWM current source: period, width at full power, edge time (all seconds)."""

    period_s: float
    width_s: float
    edge_s: float

    @classmethod
    def of(cls, freq_hz: float, duty: float) -> Pulse:
        """Edges of 1e-4 period; width chosen so the energy per period is exactly ``duty``."""
        period = 1.0 / freq_hz
        edge = period * 1e-4
        return cls(period, max(duty * period - edge, 0.0), edge)


def render_bench(lib_path: str | os.PathLike, name: str, *, power_w: float, tstop_s: float,
                 tmax_s: float, tref_c: float = 0.0, pulse: Pulse | None = None,
                 ic: Sequence[tuple[str, float]] = (), rise_s: float | None = None,
                 pwl: Sequence[tuple[float, float]] = (), toffset_c: float | None = None,
                 reltol: float = 1e-4, trtol: float = 0.5,
                 title: str = "spicethermal test bench",
                 description: str = "") -> str:
    """A transient test bench for the subcircuit in ``lib_path``: power step or PWM train.

    ``ic`` sets node temperatures at t = 0 (e.g. the periodic steady state), as
    ``(node, volts)`` with nodes such as ``X1.N1`` (see :func:`initial_conditions`). A step
    ramps up linearly over ``rise_s`` (default ``1e-5 · tmax_s``: ngspice cannot start on a much
    sharper edge at a large maximum step, least of all with behavioural elements); compare it
    with the exact ramp response. ``pwl`` (``(t_s, power_w)`` corners, used
    instead of ``pulse`` and the step) drives any piecewise-linear power waveform, e.g. a few
    PWM periods followed by a power-off sample window. The default tolerances (``reltol=1e-4``,
    ``trtol=0.5``) keep ladder responses within 3e-4 of Rth over 8 decades of time and let
    ngspice start behavioural (device-effect) models; tighter trtol can stall them.
    ``toffset_c`` passes ``PARAMS: TOFFSET=`` to a subcircuit with device effects (see
    :func:`reference_drive`).
    """
    rise_s = max(1e-9, 1e-5 * tmax_s) if rise_s is None else rise_s

    check_name(name)
    return environment().get_template("bench/transient.cir.j2").render(
        title=sanitize_comment(title), description=sanitize_comment(description),
        version=__version__, lib_path=str(lib_path), name=name, tref_c=tref_c,
        power_w=power_w, pulse=pulse, rise_s=rise_s, ic=list(ic), pwl=list(pwl),
        toffset_c=toffset_c, tstop_s=tstop_s,
        tstep_s=tmax_s, tmax_s=tmax_s, reltol=reltol, trtol=trtol)
