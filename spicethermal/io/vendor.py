"""Vendors' thermal models as they ship them: the thermal network cut out of any SPICE
subcircuit, and datasheet Foster tables.

:func:`import_subckt` reads a subcircuit the way a thermal engineer would: it flattens it
(:mod:`spicethermal.io.spice_netlist`), sorts the heat sources, references and electrical
elements (:mod:`spicethermal.io.thermal_nodes`), and cuts out the passive R/C network from the
junction to the reference (:mod:`spicethermal.io.thermal_extract`), exactly, no refit. What it
took, what it left and why is one line in the model's ``provenance`` (``extraction``), with the
lists under ``elements``. Choices a designer must make are explicit: ``params`` (PSpice
``PARAMS:``, e.g. Infineon's ``Zthtype=1``), ``network`` (one of several networks, listed by
:func:`networks`), ``to`` (a reference farther than the case).
"""

from __future__ import annotations

import os
import re
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from ..core.errors import DataFormatError
from ..model import ThermalModel
from .datasheet import read_foster_table
from .spice_netlist import flatten, node
from .spice_read import Library, read_library
from .thermal_extract import Found, extract, reference_label
from .thermal_nodes import Circuit

#: How many element names a one-line summary spells before it counts.
NAMES_SHOWN = 8
_SHAPES = {"cauer": "Cauer ladder as written", "foster": "Foster chain as written",
           "network": "R/C network, converted exactly to its Foster form"}


class SeveralNetworks(DataFormatError):
    """A subcircuit holds several thermal networks and none was chosen; ``found`` lists them."""

    def __init__(self, message: str, circuit: Circuit, found: list[Found]) -> None:
        super().__init__(message)
        self.circuit = circuit
        self.found = found


@dataclass(frozen=True)
class Extraction:
    """A subcircuit's networks: the circuit read and every network found (junction first)."""

    circuit: Circuit
    found: list[Found]


def networks(lib: Library, name: str | None = None, params: Mapping[str, str] | None = None,
             to: str | None = None) -> Extraction:
    """Every thermal network of subcircuit ``name``: from each junction pin, else from each
    node a heat source feeds (a readout pin, a network no pin reaches while others are, an R/C
    without pins or thermal names are left, and said so in the networks' notes).

    Parameters
    ----------
    lib, name, params, to
        As in :func:`import_subckt`.

    Returns
    -------
    Extraction

    Raises
    ------
    DataFormatError
        No thermal network (the reason of the most likely junction), or bad input.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "v.lib"
    >>> _ = p.write_text(".SUBCKT TWO P TJA TJF\\nG1 0 TJA VALUE={V(P)}\\nR1 TJA 0 30\\n"
    ...                  "C1 TJA 0 1\\nG2 0 TJF VALUE={V(P)}\\nR2 TJF 0 2\\nC2 TJF 0 1\\n.ENDS\\n")
    >>> ex = networks(read_library(p))
    >>> [(f.junction, f.reference, f.rth) for f in ex.found]
    [('tja', '0', 30.0), ('tjf', '0', 2.0)]
    """
    sub = lib.get(name)
    c = Circuit.of(flatten(lib, sub, params))
    target = node(to) if to is not None else None
    pins = [p for p in c.net.pins if c.pin_role(p) == "junction"]
    candidates = pins + [n for n in c.heat if n not in pins]
    fallback = not candidates and bool(c.net.pins)
    if fallback:
        candidates = [c.net.pins[0]]  # a bare R/C subcircuit: its first pin
    found: list[Found] = []
    errors: list[DataFormatError] = []
    for j in candidates:
        if j not in pins and any(j in f.nodes for f in found):
            continue
        try:
            f = extract(c, j, target)
        except DataFormatError as exc:
            if j in pins:
                errors.append(exc)
            elif fallback and "no thermal network" not in str(exc):
                errors.append(exc)
            continue
        if j not in pins and not fallback and f.nodes & c.electrical:
            continue  # an electrical current source, not a heat source
        found.append(f)
    found, dropped = _thermal(c, found)
    if not found:
        if errors:
            raise errors[0]
        why = f"; {'; '.join(dropped)}" if dropped else ""
        raise DataFormatError(f"{sub.line.file}, .SUBCKT {sub.name} (line {sub.line.number}): no "
                              "thermal network: no pin named like Tj, and no current source (G, "
                              "F, I, B) from a thermal reference feeds an R/C network that stores "
                              f"heat{why}")
    for f in found:
        f.notes += dropped
        other = sorted({b.element.name for g in found if g is not f for b in g.branches},
                       key=_order(c))
        if other:
            f.left["in the other networks (--network)"] = other
    return Extraction(c, found)


#: Names by which an R/C network without pins shows it is thermal.
THERMAL_NAME = re.compile(r"(^|[._])([rcz]_?th|rth|cth|zth|therm|heat|temp|foster|cauer|t_?j)",
                          re.I)


def _thermal(c: Circuit, found: list[Found]) -> tuple[list[Found], list[str]]:
    """The networks that are thermal networks, and a note for each one left: a readout (its
    source computes the node from other networks' temperatures), a network no pin reaches when
    others are, a network without pins or thermal names (an electrical R/C)."""
    notes: list[str] = []
    keep = []
    for f in found:
        others = set().union(*(g.nodes | {g.reference} for g in found if g is not f))
        sources = [e for e in c.elements if e.name in f.heat]
        reads = [{c.alias.get(n, n) for n in e.reads()} for e in sources]
        if sources and others and all(r & (others - f.nodes - f.held) for r in reads):
            notes.append(f"{c.spelled(f.junction)} is left: a readout ({', '.join(f.heat)} "
                         "computes it from another network's temperatures), not a network")
        else:
            keep.append(f)
    pinned = [f for f in keep if ({f.junction, f.reference} | f.nodes) & set(c.net.pins)]
    for f in keep:
        if f in pinned:
            continue
        named = any(THERMAL_NAME.search(b.element.name) for b in f.branches) or \
            THERMAL_NAME.search(f.junction)
        if pinned or not named:
            why = "no pin reaches it" if pinned else "no pin and no thermal name: electrical"
            notes.append(f"the R/C network from {c.spelled(f.junction)} to "
                         f"{c.spelled(f.reference)} is left: {why}")
    return (pinned or [f for f in keep if any(THERMAL_NAME.search(b.element.name)
                                                for b in f.branches)
                       or THERMAL_NAME.search(f.junction)]), notes


def describe(c: Circuit, f: Found) -> str:
    """One line for a network: from/to nodes, shape, Rth.

    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "v.lib"
    >>> _ = p.write_text(".SUBCKT D Tj Tc\\nR1 Tj Tc 2\\nC1 Tj 0 1m\\n.ENDS\\n")
    >>> ex = networks(read_library(p))
    >>> describe(ex.circuit, ex.found[0])
    'from Tj to Tc: Cauer ladder as written, 1 stage, Rth = 2 K/W'
    """
    stages = f.ladder.order
    return (f"from {c.spelled(f.junction)} to {c.spelled(f.reference)}: {_SHAPES[f.shape]}, "
            f"{stages} stage{'s' if stages > 1 else ''}, Rth = {f.rth:.6g} K/W")


def _names(names: list[str]) -> str:
    shown = ", ".join(names[:NAMES_SHOWN])
    return shown + (f" and {len(names) - NAMES_SHOWN} more" if len(names) > NAMES_SHOWN else "")


def summary(c: Circuit, f: Found) -> str:
    """What was taken, left and why, in one line.

    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "v.lib"
    >>> _ = p.write_text(".SUBCKT D d s Tj Tc\\nM1 d g s s NM\\nG1 0 Tj VALUE={V(d,s)}\\n"
    ...                  "R1 Tj Tc 2\\nC1 Tj 0 1m\\nR9 Tc 0 10k\\n.ENDS\\n")
    >>> ex = networks(read_library(p))
    >>> summary(ex.circuit, ex.found[0])
    'took 2 (R1, C1); heat source G1; left 1 joining held nodes (R9), 1 electrical (M1)'
    """
    taken = sorted({b.element.name for b in f.branches}, key=_order(c))
    parts = [f"took {len(taken)} ({_names(taken)})"]
    if f.case:
        parts.append(f"case capacitance {_names(f.case)}")
    if f.heat:
        parts.append(f"heat source{'s' if len(f.heat) > 1 else ''} {_names(f.heat)}")
    left = [f"{len(v)} {k} ({_names(v)})" for k, v in f.left.items()]
    used = set(taken) | set(f.heat) | set(f.case) | {n for v in f.left.values() for n in v}
    between = sorted({b.element.name for b in c.branches if b.element.name not in used
                      and b.name not in used and {b.a, b.b} <= (f.held | {f.reference})
                      and {b.a, b.b} & {f.reference}}, key=_order(c))
    if between:
        left.append(f"{len(between)} joining held nodes ({_names(between)})")
    used |= set(between)
    electrical = [e.name for e in c.net.elements if e.name not in used
                  and c.kinds.get(e.name) != "ambient source"]
    if electrical:
        left.append(f"{len(electrical)} electrical ({_names(electrical)})")
    options: dict[str, int] = {}
    for name in taken:
        for word in c.ignored.get(name, []):
            options[word] = options.get(word, 0) + 1
    if options:
        parts.append("options that change nothing: " + ", ".join(
            f"{k}{f' ×{n}' if n > 1 else ''}" for k, n in options.items()))
    out = "; ".join(parts)
    return out + ("; left " + ", ".join(left) if left else "") + \
        ("; " + "; ".join(f.notes) if f.notes else "")


def _order(c: Circuit):
    index = {e.name: i for i, e in enumerate(c.net.elements)}
    return lambda name: index.get(name, len(index))


def _choose(ex: Extraction, network: str | int | None, at: str) -> Found:
    found = ex.found
    if network is None:
        if len(found) == 1:
            return found[0]
        raise SeveralNetworks(f"{at}: {len(found)} thermal networks (listed above); choose one "
                              "with --network N", ex.circuit, found)
    text = str(network).strip()
    if text.isdigit() and 1 <= int(text) <= len(found):
        return found[int(text) - 1]
    for f in found:
        if f.junction == node(text):
            return f
    raise DataFormatError(f"{at}: --network {text}: expected 1 to {len(found)} or a junction "
                          f"node ({', '.join(ex.circuit.spelled(f.junction) for f in found)})")


def import_subckt(lib: Library, name: str | None = None, reference: str | None = None, *,
                  params: Mapping[str, str] | None = None, network: str | int | None = None,
                  to: str | None = None) -> ThermalModel:
    """The thermal network of subcircuit ``name`` as a model, exactly as the vendor wrote it.

    Parameters
    ----------
    lib : Library
        From :func:`read_library`.
    name : str, optional
        Subcircuit name (any case); may be omitted when the library holds one.
    reference : str, optional
        ``case`` or ``ambient``; default from the reference node (an ambient pin such as
        ``Ta``, ``Tamb``, an ambient source or ground: ambient; else case).
    params : mapping of str to str, optional
        Parameter values replacing the library's (``{"Zthtype": "1"}``).
    network : int or str, optional
        Which network (1-based, or its junction node) when the subcircuit holds several.
    to : str, optional
        Import to this node instead of the case pin (a network that continues past it).

    Returns
    -------
    ThermalModel
        A Cauer ladder or Foster chain as the vendor wrote it, any other network in its exact
        Foster form (with a pure resistance: the exact Cauer equivalent).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "v.lib"
    >>> _ = p.write_text(".SUBCKT D_TH Tj Tcase\\nR1 Tj 1 10m\\nR2 1 Tcase 20m\\n"
    ...                  "C1 Tj 0 1m\\nC2 1 0 5m\\nC3 Tcase 0 0.1\\n.ENDS\\n")
    >>> m = import_subckt(read_library(p))
    >>> m.ladder.topology, m.ladder.r, m.ladder.c, m.case_c_j_per_k, m.reference
    ('cauer', (0.01, 0.02), (0.001, 0.005), 0.1, 'case')
    """
    ex = networks(lib, name, params, to)
    c = ex.circuit
    sub = c.net.sub
    f = _choose(ex, network, f"{sub.line.file}, .SUBCKT {sub.name} (line {sub.line.number})")
    prov: dict = {"source": Path(lib.source).name, "device": sub.name, "subckt": sub.name,
                  "import": f"vendor network, exact (no refit): {_SHAPES[f.shape]}",
                  "pins": f"junction {c.spelled(f.junction)}, reference "
                          f"{c.spelled(f.reference)}",
                  "extraction": summary(c, f),
                  "elements": {"taken": sorted({b.element.name for b in f.branches},
                                               key=_order(c)),
                               "case_capacitance": f.case, "heat_sources": f.heat,
                               "left": f.left}}
    if len(ex.found) > 1:
        prov["network"] = f"{ex.found.index(f) + 1} of {len(ex.found)}: {describe(c, f)}"
    if params:
        prov["params"] = dict(params)
    ref = reference or reference_label(c, f.reference)
    return ThermalModel(f.ladder, reference=ref, provenance=prov, case_c_j_per_k=f.case_c)


def import_table(path: str | os.PathLike, reference: str = "case") -> ThermalModel:
    """A datasheet Foster table (CSV: ``r_k_per_w`` and ``tau_s`` or ``c_j_per_k``) as a model."""
    foster = read_foster_table(path)
    return ThermalModel(foster, reference=reference,
                        provenance={"source": Path(path).name, "device": Path(path).stem,
                                    "import": "datasheet Foster table, exact (no refit)"})


def import_model(path: str | os.PathLike, subckt: str | None = None,
                 reference: str | None = None, **choices) -> ThermalModel:
    """A vendor's thermal model from a SPICE library or a datasheet Foster table (``.csv``).

    Parameters
    ----------
    path : str or os.PathLike
        A SPICE library (``.lib``, ``.txt``, ``.mod``, ...) or a Foster table CSV.
    subckt : str, optional
        The subcircuit to import when the library holds several.
    reference : str, optional
        ``"case"`` or ``"ambient"``: what the network is measured to.
    **choices
        ``params``, ``network``, ``to``: as in :func:`import_subckt`.

    Returns
    -------
    ThermalModel
        The vendor's network, exactly (no refit).
    """
    if Path(path).suffix.lower() == ".csv":
        if subckt is not None or any(v is not None for v in choices.values()):
            raise DataFormatError(f"{path}: --subckt, --param, --network and --to apply to SPICE "
                                  "libraries, not CSV tables")
        return import_table(path, reference or "case")
    return import_subckt(read_library(path), subckt, reference, **choices)


__all__ = ["Extraction", "SeveralNetworks", "describe", "import_model", "import_subckt",
           "import_table", "networks", "read_library", "summary"]
