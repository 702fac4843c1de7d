"""The thermal network inside a vendor's subcircuit: found, cut, and stated.

From each junction (a pin named like ``Tj``, else a node a heat source feeds) the network is
the R/C subgraph reached without crossing a **held** node: ground, the pins (a vendor's
``Tcase`` is where the user holds or couples the case), nodes an ambient source holds. The
**reference** is the held node the heat leaves through (``--to NODE`` names another: the pins
up to it are then free), preferring a case pin, then an ambient pin, another pin, an ambient
source, ground. Stated rules (each named in the result):

* a resistor into a node that stores no heat and leads nowhere else carries no heat: dropped
  (a power-injection resistor between a heat source and the ``Tj`` pin, a stray bond wire);
* a branch reached only through a resistor of at least :data:`GUARD` × Rth (a sensor tap, an
  LTspice ``Rpar=1G`` leak to ground) changes Zth by less than 1/:data:`GUARD`: dropped;
* the resistor behind a Thevenin heat source (``E = R·P`` behind ``R``) belongs to the source:
  dropped when its leak is below :data:`THEVENIN_LEAK` of Rth, kept as a path otherwise;
* elements beyond the reference are left (``--to`` takes them);
* a capacitor from the reference to the thermal ground is the case capacitance.

The network is then a Cauer ladder, a Foster chain (kept as the vendor wrote them), or any
other R/C network, converted exactly to its Foster form
(:func:`spicethermal.core.rc_network.nodal_foster`).
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field

import numpy as np

from ..core.errors import DataFormatError
from ..core.ladder import Cauer, Foster
from ..core.network import Network
from ..core.rc_network import as_ladder, nodal_foster
from .spice_netlist import GROUND
from .thermal_nodes import AMBIENT, Branch, Circuit

#: A branch behind a resistor of at least GUARD × Rth is negligible (Zth changes < 1/GUARD).
GUARD = 1e6
#: A Thevenin source's resistor is dropped when the leak it adds is below this fraction of Rth.
THEVENIN_LEAK = 1e-2
_PRIORITY = {"case": 0, "ambient": 1, "pin": 2, "junction": 3}


@dataclass
class Found:
    """One thermal network: junction, reference, the branches taken, the ladder, and why each
    other element was left."""

    junction: str
    reference: str
    branches: list[Branch]
    ladder: Foster | Cauer
    case_c: float
    shape: str
    left: dict[str, list[str]] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)
    heat: list[str] = field(default_factory=list)
    nodes: set[str] = field(default_factory=set)
    held: set[str] = field(default_factory=set)
    case: list[str] = field(default_factory=list)

    @property
    def rth(self) -> float:
        return self.ladder.rth


def _component(c: Circuit, start: str, held: set[str]) -> tuple[set[str], list[Branch]]:
    """Free nodes reached from ``start`` through R and C branches, and every branch touching
    them."""
    seen, todo = {start}, deque([start])
    by_node: dict[str, list[Branch]] = {}
    for b in c.branches:
        by_node.setdefault(b.a, []).append(b)
        by_node.setdefault(b.b, []).append(b)
    while todo:
        n = todo.popleft()
        for b in by_node.get(n, []):
            m = b.other(n)
            if m not in seen and m not in held:
                seen.add(m)
                todo.append(m)
    return seen, [b for b in c.branches if b.a in seen or b.b in seen]


def held_nodes(c: Circuit, junction: str, to: str | None) -> set[str]:
    """The nodes held for the network from ``junction``: ground, the pins but the junction
    pins (another die's junction is inside the network), the nodes ambient or Thevenin sources
    drive; with ``to``, that node, the other pins but the ambient ones becoming free.

    >>> from spicethermal.io.spice_read import read_library
    >>> from spicethermal.io.spice_netlist import flatten
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "v.lib"
    >>> _ = p.write_text(".SUBCKT D d Tj Tc Ta\\nR1 Tj Tc 1\\nC1 Tj Ta 1m\\n.ENDS\\n")
    >>> lib = read_library(p)
    >>> c = Circuit.of(flatten(lib, lib.get("D")))
    >>> sorted(held_nodes(c, "tj", None)), sorted(held_nodes(c, "tj", "ta"))
    (['0', 'd', 'ta', 'tc'], ['0', 'ta'])
    """
    held = {GROUND, *c.net.pins, *c.ambient, *c.thevenin}
    held -= {p for p in c.net.pins if c.pin_role(p) == "junction"}  # other dies: inside
    if to is not None:
        held -= {p for p in c.net.pins if c.pin_role(p) in ("case", "junction", "pin")}
        held.add(to)
    held.discard(junction)
    return held


def _reference(c: Circuit, j: str, reached: set[str], held: set[str],
               branches: list[Branch], to: str | None) -> str:
    """``to``, else the reached held node of the best role; among equals, the one most of the
    steady-state heat leaves through."""
    if to is not None:
        return to
    flows = _steady(j, held, branches)[1]

    def rank(n: str) -> tuple[int, float, str]:
        role = c.pin_role(n)
        level = _PRIORITY[role] if role is not None else (4 if n in c.ambient else 5)
        return level, -flows.get(n, 0.0), n
    return min(reached, key=rank)


def _steady(j: str, held: set[str], branches: list[Branch]) -> tuple[float, dict[str, float]]:
    """Steady state per watt into ``j``: its rise (K, the DC Rth) and the heat (W) leaving
    through each held node."""
    free = [j] + sorted({n for b in branches for n in (b.a, b.b) if n not in held} - {j})
    idx = {n: i for i, n in enumerate(free)}
    rs = tuple(tuple(sorted((idx.get(b.a, len(free)), idx.get(b.b, len(free))))) + (b.value,)
               for b in branches if b.kind == "r" and (b.a in idx or b.b in idx))
    e = np.zeros(len(free))
    e[0] = 1.0
    try:
        x = np.linalg.solve(Network(len(free), rs, ()).conductance(), e)
    except np.linalg.LinAlgError:
        return float("inf"), {}
    out: dict[str, float] = {}
    for b in branches:
        if b.kind == "r" and (b.a in held) != (b.b in held):
            inner, outer = (b.a, b.b) if b.b in held else (b.b, b.a)
            out[outer] = out.get(outer, 0.0) + float(x[idx[inner]]) / b.value
    return float(x[0]), out


def extract(c: Circuit, junction: str, to: str | None = None) -> Found:
    """The network from ``junction`` (see the module docstring).

    Parameters
    ----------
    c : Circuit
        The subcircuit's thermal reading.
    junction : str
        Where the heat enters (a node, lower case).
    to : str, optional
        The reference node, instead of the one the rules choose.

    Returns
    -------
    Found

    Raises
    ------
    DataFormatError
        No network there, or an element of it that is not a linear R or C (named with its
        file and line).

    Examples
    --------
    >>> from spicethermal.io.spice_read import read_library
    >>> from spicethermal.io.spice_netlist import flatten
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "v.lib"
    >>> _ = p.write_text(".SUBCKT D Tj Tc\\nR1 Tj n 1\\nC1 Tj 0 1m\\nR2 n Tc 2\\nC2 n 0 3m\\n"
    ...                  "Rx n x 5\\n.ENDS\\n")
    >>> lib = read_library(p)
    >>> f = extract(Circuit.of(flatten(lib, lib.get("D"))), "tj")
    >>> f.reference, f.shape, f.ladder.r, f.left
    ('tc', 'cauer', (1.0, 2.0), {'dead end without heat storage (carries no heat)': ['Rx']})
    """
    sub = c.net.sub
    at = f"{sub.line.file}, .SUBCKT {sub.name} (line {sub.line.number})"
    j = junction
    driver = next((e.name for e in c.elements if e.kind in "veh" and j in e.nodes
                   and c.kinds.get(e.name) != "short (0 V)"), None)
    if driver is not None:
        raise DataFormatError(f"{at}: {c.spelled(j)} is driven by {driver} (a voltage source: its "
                              "temperature is imposed, not computed): no thermal network")
    held = held_nodes(c, j, to)
    nodes, branches = _component(c, j, held)
    bad = next((b for b in branches if b.value is None), None)
    if bad is not None:
        raise DataFormatError(f"{bad.element.line.where}: {bad.element.name} is in the thermal "
                              f"network from {c.spelled(j)} but {bad.why}")
    left: dict[str, list[str]] = {}
    notes: list[str] = []
    resistors = [b for b in branches if b.kind == "r"]
    reached = {n for b in resistors for n in (b.a, b.b) if n in held}
    if to is not None and to not in reached:
        raise DataFormatError(f"{at}: no resistive path from {c.spelled(j)} to {to} (--to)")
    if not reached:
        what = "no R or C element there" if not branches else \
            "no resistor leads to a held node (a reference pin, an ambient source or ground)"
        raise DataFormatError(f"{at}: no thermal network at {c.spelled(j)}: {what}")
    ref = _reference(c, j, reached, held, branches, to)
    branches = _drop_thevenin(c, j, ref, held, branches, left, notes)
    branches = _drop_dead_ends(c, j, held, branches, left, notes)
    at_j = [b for b in branches if j in (b.a, b.b)]
    if c.pin_role(j) is None and len(at_j) == 1 and at_j[0].kind == "r":
        notes.append(f"{at_j[0].name}: a series resistor at the junction {c.spelled(j)} without "
                     f"heat storage: kept (the heat enters at {c.spelled(j)}; no Tj pin reads "
                     "past it)")
    rth = _rth(j, ref, held, branches)
    branches = _drop_guarded(c, j, held, branches, rth, left, notes)
    others = sorted({n for b in branches if b.kind == "r" for n in (b.a, b.b)
                     if n in held and n != ref})
    if others:
        notes.append(f"heat also leaves through {', '.join(c.spelled(n) for n in others)}, "
                     f"held at the reference temperature")
    case = [b for b in c.branches if b.kind == "c" and b.value and ref != GROUND
            and ref in (b.a, b.b) and c.thermal_ground(b.other(ref))]
    _past_reference(c, j, ref, held, nodes, case, left)
    notes += sorted({c.notes[b.element.name] for b in branches if b.element.name in c.notes})
    ladder, shape = _ladder(j, ref, held, branches,
                            f"{at}: the network from {c.spelled(j)} to {c.spelled(ref)}")
    heat = sorted({s for n in nodes for s in c.heat.get(n, [])})
    return Found(j, ref, branches, ladder, sum(b.value for b in case), shape, left, notes, heat,
                 nodes, held, [b.name for b in case])


def _rth(j: str, ref: str, held: set[str], branches: list[Branch]) -> float:
    """DC resistance from ``j`` to the held nodes through the resistors of ``branches``."""
    return _steady(j, held, branches)[0]


def _drop(branches: list[Branch], gone: list[Branch], left: dict[str, list[str]],
          reason: str) -> list[Branch]:
    if gone:
        left.setdefault(reason, []).extend(b.name for b in gone)
    return [b for b in branches if b not in gone]


def _drop_thevenin(c: Circuit, j: str, ref: str, held: set[str], branches: list[Branch],
                   left: dict[str, list[str]], notes: list[str]) -> list[Branch]:
    for node, source in c.thevenin.items():
        if node == ref:
            continue
        inj = [b for b in branches if b.kind == "r" and node in (b.a, b.b)]
        if not inj:
            continue
        rest = [b for b in branches if b not in inj]
        rth = _rth(j, ref, held, rest)
        leak = max(rth / b.value for b in inj)
        names = ", ".join(b.name for b in inj)
        if leak < THEVENIN_LEAK:
            branches = _drop(branches, inj, left, f"resistor of the Thevenin heat source {source}")
            notes.append(f"{names}: the resistor of the Thevenin heat source {source} (E = R·P), "
                         f"dropped (the leak it adds: {100 * leak:.2g} % of Rth)")
        else:
            notes.append(f"{names}: the resistor of the Thevenin heat source {source} leaks "
                         f"{100 * leak:.2g} % of Rth: kept as a path to {node}")
    return branches


def _drop_dead_ends(c: Circuit, j: str, held: set[str], branches: list[Branch],
                    left: dict[str, list[str]], notes: list[str]) -> list[Branch]:
    while True:
        count: dict[str, list[Branch]] = {}
        for b in branches:
            for n in (b.a, b.b):
                count.setdefault(n, []).append(b)
        dead = [(n, bs[0]) for n, bs in count.items() if n != j and n not in held
                and len(bs) == 1 and bs[0].kind == "r"]
        if not dead:
            return branches
        for n, b in dead:
            if n in c.heat and b.other(n) == j:
                notes.append(f"{b.name}: between the dissipation node {n} "
                             f"({', '.join(c.heat[n])}) and the junction {c.spelled(j)}, no heat "
                             f"storage at {n}: the heat reaches {c.spelled(j)} whole; dropped "
                             "(the junction is the Tj pin)")
        branches = _drop(branches, [b for _, b in dead], left,
                         "dead end without heat storage (carries no heat)")


def _drop_guarded(c: Circuit, j: str, held: set[str], branches: list[Branch], rth: float,
                  left: dict[str, list[str]], notes: list[str]) -> list[Branch]:
    guards = []
    for b in branches:
        if b.kind != "r" or b.value < GUARD * rth:
            continue
        if b.a in held or b.b in held:
            guards.append([b])
            continue
        rest = [x for x in branches if x is not b]
        part = _part_without(j, held, rest)
        cut = [x for x in rest if (x.a in part or x.b in part) and
               not (x.kind == "r" and (x.a in held or x.b in held))]
        stub_to_held = any(x.kind == "r" and (x.a in part or x.b in part) and
                           (x.a in held or x.b in held) for x in rest)
        if part and not stub_to_held:
            guards.append([b, *cut])
    gone = [x for g in guards for x in g]
    if gone:
        notes.append(f"{', '.join(g[0].name for g in guards)}: at least {GUARD:.0e} × Rth, "
                     f"negligible (Zth changes < {1 / GUARD:.0e}): dropped with what hangs on it")
    return _drop(branches, gone, left, f"negligible: behind a resistor ≥ {GUARD:.0e} × Rth")


def _part_without(j: str, held: set[str], branches: list[Branch]) -> set[str]:
    """Free nodes no longer reached from ``j`` through ``branches``."""
    nodes = {n for b in branches for n in (b.a, b.b) if n not in held}
    seen, todo = {j}, deque([j])
    while todo:
        n = todo.popleft()
        for b in branches:
            if n in (b.a, b.b):
                m = b.other(n)
                if m not in seen and m not in held:
                    seen.add(m)
                    todo.append(m)
    return nodes - seen


def _past_reference(c: Circuit, j: str, ref: str, held: set[str], nodes: set[str],
                    case: list[Branch], left: dict[str, list[str]]) -> None:
    if ref == GROUND:
        return
    _, beyond = _component(c, j, held - {ref})
    far = [b.name for b in beyond if b not in case and not any(n in nodes for n in (b.a, b.b))
           and not (b.a in held and b.b in held)]
    if far:
        left.setdefault(f"past the reference {c.spelled(ref)}", []).extend(far)


def _ladder(j: str, ref: str, held: set[str], branches: list[Branch],
            at: str) -> tuple[Foster | Cauer, str]:
    rs: dict[frozenset[str], float] = {}
    cs: dict[frozenset[str], float] = {}
    for b in branches:
        key = frozenset((b.a, b.b))
        if b.kind == "r":
            rs[key] = 1.0 / (1.0 / rs[key] + 1.0 / b.value) if key in rs else b.value
        elif b.value:
            cs[key] = cs.get(key, 0.0) + b.value
    if not cs:
        raise DataFormatError(f"{at} has no capacitance (a temperature held through a "
                              "resistor, not a thermal network)")
    chain = _chain(j, ref, held, rs)
    found = _chain_ladder(chain, held, rs, cs) if chain is not None else None
    return found if found is not None else (_general(j, held, rs, cs), "network")


def _chain(j: str, ref: str, held: set[str], rs: dict[frozenset[str], float]) -> list[str] | None:
    """The nodes from ``j`` to ``ref`` when the resistors form one chain, else None."""
    path, used = [j], set()
    while path[-1] != ref:
        nxt = [k for k in rs if path[-1] in k and k not in used]
        if len(nxt) != 1:
            return None
        used.add(nxt[0])
        (m,) = nxt[0] - {path[-1]}
        if m in path or (m in held and m != ref):
            return None
        path.append(m)
    return path if len(used) == len(rs) else None


def _chain_ladder(chain: list[str], held: set[str], rs: dict[frozenset[str], float],
                  cs: dict[frozenset[str], float]) -> tuple[Foster | Cauer, str] | None:
    """A chain's capacitors all across stages (Foster) or all to held nodes (Cauer); None for
    a mixture. A capacitor from the last inner node to the reference is either."""
    idx = {n: i for i, n in enumerate(chain)}
    n = len(chain) - 1
    r = [rs[frozenset((chain[i], chain[i + 1]))] for i in range(n)]
    across, ground, last = [0.0] * n, [0.0] * n, 0.0
    for key, value in cs.items():
        a, b = sorted(key, key=lambda x: idx.get(x, n + 1))
        if a not in idx:
            return None
        if b in idx and idx[b] == idx[a] + 1 and b == chain[-1]:
            last += value
        elif b in idx and idx[b] == idx[a] + 1:
            across[idx[a]] += value
        elif b in held or b == chain[-1]:
            ground[idx[a]] += value
        else:
            return None
    if any(across) and any(ground):
        return None
    if any(across):
        across[-1] += last
        live = [i for i in range(n) if across[i]]
        tau = [r[i] * across[i] for i in live]
        pure = sum(r[i] for i in range(n) if not across[i])
        if not pure:
            return Foster(r, across), "foster"
        return as_ladder(pure, [r[i] for i in live], tau), "foster"
    ground[-1] += last
    return Cauer(r, ground), "cauer"


def _general(j: str, held: set[str], rs: dict[frozenset[str], float],
             cs: dict[frozenset[str], float]) -> Foster | Cauer:
    """Any other network: its exact Foster form seen from ``j``."""
    free = [j] + sorted({n for k in (*rs, *cs) for n in k if n not in held} - {j})
    idx = {n: i for i, n in enumerate(free)}
    size = len(free)

    def pairs(d: dict[frozenset[str], float]) -> tuple[tuple[int, int, float], ...]:
        out = []
        for key, v in d.items():
            a, b = sorted((idx.get(x, size) for x in key), key=lambda i: i)
            if a < size:
                out.append((a, b, v))
        return tuple(out)

    net = Network(size, pairs(rs), pairs(cs))
    return as_ladder(*nodal_foster(net.conductance(), net.capacitance(), 0))


def reference_label(c: Circuit, ref: str) -> str:
    """``ambient`` for ground, an ambient pin or an ambient source's node; else ``case``.

    >>> from spicethermal.io.spice_read import Line, Subckt
    >>> from spicethermal.io.spice_netlist import Netlist
    >>> from spicethermal.io.spice_expr import Scope
    >>> c = Circuit(Netlist(Subckt("D", ("Tj", "Tamb"), Line("f", 1, "")), ("tj", "tamb"),
    ...                     [], Scope()))
    >>> reference_label(c, "tamb"), reference_label(c, "0"), reference_label(c, "tmb")
    ('ambient', 'ambient', 'case')
    """
    if ref == GROUND or ref in c.ambient or AMBIENT.fullmatch(ref):
        return "ambient"
    return "case"
