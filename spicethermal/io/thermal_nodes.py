"""Where the heat goes in and where it is held, in a flattened vendor subcircuit.

:class:`Circuit` reads a :class:`~spicethermal.io.spice_netlist.Netlist` as a thermal
engineer would: every resistor and capacitor becomes a branch (an LTspice ``Rpar``,
``Rser`` or ``Cpar`` option becomes the branch it stands for; a value that is not a linear R
or C keeps its reason); the sources are sorted into **heat sources** (a current, ``G``,
``F`` or ``B … I=`` source from a thermal reference into a node), **Thevenin heat
sources** (a voltage that follows the power, behind a resistor), **ambient sources** (a
constant or ``{TEMP}`` voltage: the node is held) and electrical ones; the pins are sorted
by name into junction, case and ambient. Every other element is electrical and left alone.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field, replace

from .spice_expr import NotConstant, evaluate
from .spice_netlist import GROUND, Element, Netlist, linear_value, split_words

JUNCTION = re.compile(r"t_?j\w*|j\d*|junction\w*|t?_?die\w*", re.I)
CASE = re.compile(r"t_?c\w*|case\w*|t_?mb\w*|t_?sp\d*|t_?sol(der)?\w*|t_?foot\w*|t_?lead\w*|"
                  r"t_?tab\w*|t_?hs\w*|t_?sink\w*|tref|t_?board\w*|t_?pcb\w*|t_?base\w*",
                  re.I)
AMBIENT = re.compile(r"t_?a\d*|t_?amb\w*|amb(ient|iant)?\w*|t_?air\w*", re.I)
#: Element kinds that are electrical devices (every node of theirs is electrical).
DEVICES = set("dqjzmlswtoyupna")


@dataclass(frozen=True)
class Branch:
    """A two-terminal R or C of the thermal graph: its element's name, ``r`` or ``c``, nodes,
    value (Ω or F; None when not linear, with ``why``) and the element it comes from."""

    name: str
    kind: str
    a: str
    b: str
    value: float | None
    element: Element
    why: str = ""

    def other(self, n: str) -> str:
        """The node at the other end from ``n``."""
        return self.b if n == self.a else self.a


@dataclass
class Circuit:
    """The thermal reading of a netlist (see the module docstring)."""

    net: Netlist
    branches: list[Branch] = field(default_factory=list)
    heat: dict[str, list[str]] = field(default_factory=dict)  # node -> heat sources into it
    thevenin: dict[str, str] = field(default_factory=dict)     # driven node -> its source
    ambient: dict[str, str] = field(default_factory=dict)      # held node -> its source
    electrical: set[str] = field(default_factory=set)
    ignored: dict[str, list[str]] = field(default_factory=dict)  # element -> options ignored
    kinds: dict[str, str] = field(default_factory=dict)        # element -> role
    notes: dict[str, str] = field(default_factory=dict)        # element -> what was assumed
    elements: list[Element] = field(default_factory=list)      # the netlist's, shorts merged
    alias: dict[str, str] = field(default_factory=dict)        # node -> node it is shorted to

    @classmethod
    def of(cls, net: Netlist) -> Circuit:
        """Sort the netlist's elements (see the module docstring).

        >>> import tempfile, pathlib
        >>> from spicethermal.io.spice_read import read_library
        >>> from spicethermal.io.spice_netlist import flatten
        >>> p = pathlib.Path(tempfile.mkdtemp()) / "v.lib"
        >>> _ = p.write_text(".SUBCKT D d s Tj Tc\\nM1 d g s s NM\\nG1 0 Tj VALUE={V(d,s)}\\n"
        ...                  "VA Ta 0 25\\nR1 Tj Tc 2 TC=0,0\\n.ENDS\\n")
        >>> lib = read_library(p)
        >>> c = Circuit.of(flatten(lib, lib.get("D")))
        >>> c.heat, c.ambient, c.kinds["M1"], c.ignored, c.pin_role("tc")
        ({'tj': ['G1']}, {'ta': 'VA'}, 'electrical', {'R1': ['TC=0,0']}, 'case')
        """
        c = cls(net)
        c.alias = _shorts(net)
        c.elements = [replace(el, nodes=tuple(c.alias.get(n, n) for n in el.nodes))
                      for el in net.elements]
        sources = []
        for el in c.elements:
            if el.kind == "v" and el.nodes[0] == el.nodes[1]:
                c.kinds[el.name] = "short (0 V)"
                continue
            if el.kind in "rc":
                c._add_rc(el)
            elif el.kind in "vehgfib":
                sources.append(el)
            elif el.kind in DEVICES:
                c.electrical.update(el.nodes)
                c.kinds[el.name] = "electrical"
            else:
                c.kinds[el.name] = "electrical" if el.kind != "x" else "unread subcircuit"
        c._sources(sources)
        return c

    # -- pins ----------------------------------------------------------------------------
    def pin_role(self, node: str) -> str | None:
        """``junction``, ``case``, ``ambient`` or ``pin`` for a pin, None for another node."""
        if node not in self.net.pins:
            return None
        for role, pattern in (("junction", JUNCTION), ("case", CASE), ("ambient", AMBIENT)):
            if pattern.fullmatch(node):
                return role
        return "pin"

    def spelled(self, node: str) -> str:
        """A node as the library spells it (its first spelling in the subcircuit)."""
        return self.net.spelling.get(node, node)

    def thermal_ground(self, node: str) -> bool:
        """Ground, an ambient pin or a node an ambient source holds: where heat capacities
        connect."""
        return node == GROUND or self.pin_role(node) == "ambient" or node in self.ambient

    def thermal_held(self, node: str) -> bool:
        """Ground, a thermal pin (case or ambient) or a node an ambient source holds."""
        return node == GROUND or self.pin_role(node) in ("case", "ambient") \
            or node in self.ambient

    # -- elements ------------------------------------------------------------------------
    def _add_rc(self, el: Element) -> None:
        a, b = el.nodes
        if a == b:
            self.kinds[el.name] = "shorted"
            return
        try:
            lin = linear_value(el)
        except (NotConstant, ValueError) as exc:
            self.branches.append(Branch(el.name, el.kind, a, b, None, el, str(exc)))
            return
        if lin.value < 0 or (el.kind == "r" and lin.value == 0) or lin.value != lin.value:
            why = f"{el.name} = {lin.value!r}: must be {'> 0' if el.kind == 'r' else '>= 0'}"
            self.branches.append(Branch(el.name, el.kind, a, b, None, el, why))
            return
        if lin.ignored:
            self.ignored[el.name] = list(lin.ignored)
        if lin.note:
            self.notes[el.name] = lin.note
        if el.kind == "c" and lin.rser:
            mid = f"{el.name.lower()}#rser"
            self.branches += [Branch(f"{el.name}(Rser)", "r", a, mid, lin.rser, el),
                              Branch(el.name, "c", mid, b, lin.value, el)]
        elif lin.value > 0 or el.kind == "r":
            self.branches.append(Branch(el.name, el.kind, a, b, lin.value, el))
        if lin.rpar:
            self.branches.append(Branch(f"{el.name}(Rpar)", "r", a, b, lin.rpar, el))
        if lin.cpar:
            self.branches.append(Branch(f"{el.name}(Cpar)", "c", a, b, lin.cpar, el))

    def _sources(self, sources: list[Element]) -> None:
        todo = list(sources)
        changed = True
        while changed:  # ambient sources may hold nodes other sources hang from
            changed = False
            for el in list(todo):
                if self._voltage(el) and self._classify_voltage(el):
                    todo.remove(el)
                    changed = True
        for el in todo:
            a, b = el.nodes
            current = not self._voltage(el)
            held = [n for n in (a, b) if self.thermal_held(n) or n in self.thevenin]
            free = [n for n in (a, b) if n not in held]
            if current and len(held) == 1 and len(free) == 1:
                self.heat.setdefault(free[0], []).append(el.name)
                self.kinds[el.name] = "heat source"
            else:
                self.electrical.update(el.nodes)
                self.kinds[el.name] = "electrical"

    def _voltage(self, el: Element) -> bool:
        if el.kind in "veh":
            return True
        return el.kind == "b" and bool(re.match(r"\s*v\s*=", el.tail, re.I))

    def _classify_voltage(self, el: Element) -> bool:
        """An ambient (constant) or Thevenin (power-following) source from a held node; False
        when it is neither (yet)."""
        a, b = el.nodes
        held = [n for n in (a, b) if self.thermal_held(n) or n in self.net.pins]
        free = [n for n in (a, b) if n not in held]
        if len(held) != 1 or len(free) != 1 or free[0] in self.electrical:
            return False
        if self._constant(el) and self.thermal_held(held[0]):
            self.ambient[free[0]] = el.name
            self.kinds[el.name] = "ambient source"
            return True
        if self.thermal_held(held[0]) and self._resistive_only(free[0], el):
            self.thevenin[free[0]] = el.name
            self.kinds[el.name] = "heat source"
            return True
        return False

    def _resistive_only(self, node: str, source: Element) -> bool:
        others = [e for e in self.elements if node in e.nodes and e is not source]
        return bool(others) and all(e.kind == "r" for e in others)

    def _constant(self, el: Element) -> bool:
        words = split_words(el.tail)
        if el.kind == "b":
            words = [words[0].split("=", 1)[1]] if words and "=" in words[0] else []
        elif words and words[0].lower() == "dc":
            words = words[1:]
        elif words and re.match(r"value\s*=", words[0], re.I):
            words = [words[0].split("=", 1)[1]] if "=" in words[0] else words[1:2]
        if not words or (el.kind in "eh" and len(words) > 1 and "=" not in words[0]):
            return el.kind == "v" and not words  # "V1 a 0" is 0 V
        try:
            evaluate(words[0], el.scope, el.scope.functions())
        except NotConstant as exc:  # the simulator temperature is a constant
            return "TEMP" in str(exc) and "V(" not in words[0].upper()
        except (ValueError, KeyError):
            return False
        return True


def _shorts(net: Netlist) -> dict[str, str]:
    """Nodes joined by a 0 V source (an ammeter), each to the node it is merged into (a pin
    or ground when one side is one)."""
    alias: dict[str, str] = {}

    def find(n: str) -> str:
        while n in alias:
            n = alias[n]
        return n

    def fixed(n: str) -> bool:
        return n == GROUND or n in net.pins

    for el in net.elements:
        if el.kind != "v" or not _zero(el):
            continue
        a, b = (find(n) for n in el.nodes)
        if a == b or (fixed(a) and fixed(b)):
            continue
        if fixed(b):
            a, b = b, a
        alias[b] = a
    return {n: find(n) for n in alias}


def _zero(el: Element) -> bool:
    words = [w for w in split_words(el.tail) if w.lower() != "dc"]
    if not words:
        return True
    if len(words) > 1 and words[1].lower() != "ac":
        return False
    try:
        return evaluate(words[0], el.scope, el.scope.functions()) == 0
    except (ValueError, KeyError):
        return False
