"""A subcircuit flattened into elements: every subcircuit instance (``X``) it holds expanded,
recursively, with its parameters (``PARAMS:`` defaults, the instance's values, ``.PARAM`` and
``.FUNC`` lines) in a :class:`~spicethermal.io.spice_expr.Scope` of its own.

:func:`linear_value` reads a resistor's or capacitor's value and options as a linear element:
``R=``/``C=`` forms, ``M=``, LTspice's ``Rser=``, ``Rpar=``, ``Cpar=`` (kept as the elements
they stand for), options that change nothing (``IC=``, ``TC=0,0``, ``noiseless``) named as
ignored; anything else (a non-zero ``TC``, ``Q=``, a model, a value that reads the circuit) is
a one-line reason.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

from ..core.errors import DataFormatError
from .spice_expr import Definition, Function, Scope, evaluate, unwrap
from .spice_read import Library, Line, Subckt, assignments

#: Output nodes of each element kind (first letter); controlling nodes of E/G/S are not
#: connections.
NODE_COUNT = {"r": 2, "c": 2, "l": 2, "v": 2, "i": 2, "e": 2, "g": 2, "f": 2, "h": 2, "b": 2,
              "d": 2, "q": 3, "j": 3, "z": 3, "m": 4, "s": 4, "w": 2, "t": 4, "o": 4, "k": 0}
GROUND = "0"
MAX_DEPTH = 32
_FUNC = re.compile(r"\.func\s+([a-z_][\w.$]*)\s*\(([^)]*)\)\s*=?\s*(.+)$", re.I)


def node(name: str) -> str:
    """A node's canonical name: lower case, ground ``0`` for ``0``, ``gnd`` and ``gnd!``.

    >>> node("Tcase"), node("GND")
    ('tcase', '0')
    """
    low = name.lower()
    return GROUND if low in ("0", "gnd", "gnd!") else low


@dataclass(frozen=True)
class Element:
    """One element of the flattened subcircuit: its hierarchical name (``X1.R_Rth1``), kind
    (first letter, lower case), nodes (lower case, hierarchical; ground is ``0``), the text
    after its nodes, its line and the parameter scope of its instance."""

    name: str
    kind: str
    nodes: tuple[str, ...]
    tail: str
    line: Line
    scope: Scope = field(repr=False, compare=False)
    resolve: Callable[[str], str] = field(default=node, repr=False, compare=False)

    def reads(self) -> set[str]:
        """The nodes whose voltage the element's expression reads (``V(a)``, ``V(a,b)``).

        >>> from spicethermal.io.spice_read import Line
        >>> sorted(Element("B1", "b", ("0", "tj"), "I=V(Tc)+V(t1, Tc)", Line("f", 1, ""),
        ...                Scope()).reads())
        ['t1', 'tc']
        """
        found = re.findall(r"\bv\s*\(\s*([^,()\s]+)\s*(?:,\s*([^,()\s]+)\s*)?\)", self.tail,
                           re.I)
        return {self.resolve(n) for pair in found for n in pair if n}


@dataclass
class Netlist:
    """A flattened subcircuit: its pins (lower case), elements and what could not be expanded."""

    sub: Subckt
    pins: tuple[str, ...]
    elements: list[Element]
    scope: Scope
    notes: list[str] = field(default_factory=list)
    #: node -> its first spelling in the subcircuit (pins first)
    spelling: dict[str, str] = field(default_factory=dict)


def split_words(text: str) -> list[str]:
    """Words of an element's tail, keeping ``{...}``, ``(...)`` and ``'...'`` whole and joining
    ``key = value`` and ``a , b``.

    >>> split_words("{a + b}  TC = 0 , 0  Rpar=1G")
    ['{a + b}', 'TC=0,0', 'Rpar=1G']
    """
    words: list[str] = []
    depth, quote, cur = 0, False, ""
    for ch in text:
        if ch == "'":
            quote = not quote
        elif not quote and ch in "{(":
            depth += 1
        elif not quote and ch in "})":
            depth = max(depth - 1, 0)
        if ch.isspace() and depth == 0 and not quote:
            if cur:
                words.append(cur)
            cur = ""
        else:
            cur += ch
    if cur:
        words.append(cur)
    out: list[str] = []
    for w in words:
        if out and (w.startswith(("=", ",")) or out[-1].endswith(("=", ","))):
            out[-1] += w
        else:
            out.append(w)
    return out


def _scope(lib: Library, sub: Subckt, parent: Scope, overrides: Mapping[str, Definition]) -> Scope:
    where = sub.line.where
    defs = {k: Definition(v, where) for k, v in sub.defaults.items()}
    funcs: dict[str, Function] = {}
    for line in sub.body:
        word = line.text.split()[0].lower()
        if word in (".param", ".params"):
            defs.update({k: Definition(v, line.where) for k, v in _params(line).items()})
        elif word == ".func":
            name, f = parse_func(line)
            funcs[name] = f
    defs.update(overrides)
    return Scope(defs, parent, funcs)


def _params(line: Line) -> dict[str, str]:
    """The assignments of a ``.PARAM`` line."""
    words = line.text.split(None, 1)
    return assignments(words[1]) if len(words) > 1 else {}


def parse_func(line: Line) -> tuple[str, Function]:
    """A ``.FUNC name(a, b) {body}`` line as (lower-case name, :class:`Function`).

    >>> parse_func(Line("f", 1, ".FUNC rlim(x,n) {min(x,n)}"))[1].args
    ('x', 'n')
    """
    m = _FUNC.match(line.text)
    if not m:
        raise DataFormatError(f"{line.where}: cannot read this .FUNC line")
    args = tuple(a.strip().lower() for a in m.group(2).split(",") if a.strip())
    return m.group(1).lower(), Function(args, m.group(3).strip(), line.where)


def global_scope(lib: Library, overrides: Mapping[str, str] = ()) -> Scope:
    """The library's ``.PARAM`` and ``.FUNC`` lines as the outermost scope (``overrides``:
    values given for some of them, ``--param``).

    >>> from spicethermal.io.spice_read import Library
    >>> lib = Library("f", [], [Line("f", 1, ".param a=2 b={a*3}")])
    >>> global_scope(lib)["b"], global_scope(lib, {"a": "1"})["b"]
    (6.0, 3.0)
    """
    defs = {}
    for line in lib.params:
        defs.update({k: Definition(v, line.where) for k, v in _params(line).items()})
    funcs = dict(parse_func(line) for line in lib.funcs)
    defs.update({k: Definition(v, "--param") for k, v in dict(overrides).items() if k in defs})
    return Scope(defs, None, funcs)


def flatten(lib: Library, sub: Subckt, params: Mapping[str, str] | None = None) -> Netlist:
    """Every element of subcircuit ``sub``, its instances expanded.

    Parameters
    ----------
    lib : Library
        The library that defines ``sub`` and the subcircuits it instantiates.
    sub : Subckt
        The subcircuit to flatten.
    params : mapping of str to str, optional
        Parameter values that replace the library's (``--param NAME=VALUE``; names lower
        case): a ``PARAMS:`` default, a ``.PARAM`` of the subcircuit or of the library.

    Returns
    -------
    Netlist

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from spicethermal.io.spice_read import read_library
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "v.lib"
    >>> _ = p.write_text(".SUBCKT IN a b PARAMS: r=1\\nR1 a b {r}\\n.ENDS\\n"
    ...                  ".SUBCKT TOP Tj Tc\\nX1 Tj n1 IN PARAMS: r=2\\nR2 n1 Tc 3\\n.ENDS\\n")
    >>> lib = read_library(p)
    >>> net = flatten(lib, lib.get("TOP"))
    >>> [(e.name, e.nodes) for e in net.elements]
    [('X1.R1', ('tj', 'n1')), ('R2', ('n1', 'tc'))]
    """
    given = {k.lower(): v for k, v in (params or {}).items()}
    known = set(sub.defaults) | {k for line in sub.body if line.text.lower().startswith(".param")
                                 for k in _params(line)}
    outer = global_scope(lib, given)
    unknown = sorted(set(given) - known - set(outer.defs) - {"temp"})
    if unknown:
        names = ", ".join(sorted(known | set(outer.defs))) or "none"
        raise DataFormatError(f"--param {unknown[0]}: no such parameter in .SUBCKT {sub.name} "
                              f"or its library (its parameters: {names})")
    if "temp" in given:
        outer.defs["temp"] = Definition(given["temp"], "--param")
    top = _scope(lib, sub, outer, {k: Definition(v, "--param") for k, v in given.items()
                                   if k in known})
    pins = tuple(node(p) for p in sub.pins)
    net = Netlist(sub, pins, [], top)
    net.spelling = {node(p): p for p in reversed(sub.pins)}
    _expand(lib, sub, {p: p for p in pins}, "", top, net, [sub.name.lower()])
    return net


def _expand(lib: Library, sub: Subckt, nodes: dict[str, str], prefix: str, scope: Scope,
            net: Netlist, stack: list[str]) -> None:
    def name_of(n: str) -> str:
        low = node(n)
        out = low if low == GROUND else nodes.get(low, f"{prefix.lower()}{low}")
        net.spelling.setdefault(out, n if out == low else f"{prefix}{n}")
        return out

    for line in sub.body:
        text = line.text
        if text.startswith("."):
            continue
        kind = text[0].lower()
        if kind == "x":
            _instance(lib, sub, line, name_of, prefix, scope, net, stack)
            continue
        words = text.split()
        count = NODE_COUNT.get(kind, 0)
        if len(words) < count + 1:
            net.notes.append(f"{line.where}: {words[0]} has fewer than {count} nodes: ignored")
            continue
        tail = text.split(None, count + 1)[count + 1] if len(words) > count + 1 else ""
        net.elements.append(Element(prefix + words[0], kind,
                                    tuple(name_of(w) for w in words[1:count + 1]), tail, line,
                                    scope, name_of))


def _instance(lib: Library, parent: Subckt, line: Line, name_of, prefix: str, scope: Scope,
              net: Netlist, stack: list[str]) -> None:
    m = re.search(r"\s+params?\s*:", line.text, re.I)
    head, tail = (line.text[:m.start()], line.text[m.end():]) if m else (line.text, "")
    words = re.sub(r"\s*=\s*", "=", head).split()
    plain = [w for w in words if "=" not in w]
    tail = " ".join(w for w in words if "=" in w) + " " + tail
    if len(plain) < 2:
        net.notes.append(f"{line.where}: {plain[0]}: no subcircuit name: ignored")
        return
    inst, pins, subname = plain[0], plain[1:-1], plain[-1]
    if subname.startswith("{"):  # a subcircuit chosen by a parameter (Wolfspeed modules)
        try:
            value = evaluate(subname, scope, scope.functions())
            subname = str(int(value)) if value == int(value) else repr(value)
        except (ValueError, KeyError, OverflowError):
            pass
    child = lib.find(subname, parent)
    mapped = tuple(name_of(p) for p in pins)
    if child is not None and len(pins) < len(child.pins) and \
            all(p.lower() in child.optional for p in child.pins[len(pins):]):
        mapped += tuple(node(child.optional[p.lower()]) for p in child.pins[len(pins):])
    if child is None or len(child.pins) != len(mapped):
        why = ("is not in this library" if child is None else
               f"has {len(child.pins)} pins, the instance {len(pins)}")
        net.notes.append(f"{line.where}: {inst}: subcircuit {subname} {why}: its inside is not "
                         "read")
        net.elements.append(Element(prefix + inst, "x", mapped, subname, line, scope, name_of))
        return
    if child.name.lower() in stack or len(stack) > MAX_DEPTH:
        raise DataFormatError(f"{line.where}: {inst} instantiates {child.name} inside itself")
    overrides = {k: Definition(v, line.where, scope) for k, v in assignments(tail).items()}
    outer = scope if child.parent is parent else _root(scope)
    child_scope = _scope(lib, child, outer, overrides)
    pin_map = {node(p): n for p, n in zip(child.pins, mapped, strict=True)}
    _expand(lib, child, pin_map, f"{prefix}{inst}.", child_scope, net,
            [*stack, child.name.lower()])


def _root(scope: Scope) -> Scope:
    while scope.parent is not None:
        scope = scope.parent
    return scope


@dataclass(frozen=True)
class Linear:
    """A resistor or capacitor read as linear: its value (Ω or F, multiplier applied), the
    resistors and capacitor its options stand for, and the options that change nothing."""

    value: float
    rpar: float | None = None
    rser: float | None = None
    cpar: float = 0.0
    ignored: tuple[str, ...] = ()
    note: str = ""


#: The simulators' nominal temperature (degC), where a temperature coefficient changes nothing.
TNOM = 27.0


def _temperature_coefficient(el: Element, value: float, opts: dict[str, str]) -> tuple[float, str]:
    """``value`` at the simulator temperature: ``TC=tc1[,tc2]`` (or ``TC1=``, ``TC2=``) scale
    it by ``1 + tc1·ΔT + tc2·ΔT²`` with ``ΔT = TEMP − TNOM``; without ``--param TEMP`` it is
    taken at ``TNOM``, where it is the value as written (said in the note)."""
    funcs = el.scope.functions()
    tc = [0.0, 0.0]
    if "tc" in opts:
        parts = [x for x in re.split(r"[,\s]+", unwrap(opts.pop("tc")).strip("()")) if x]
        for k, x in enumerate(parts[:2]):
            tc[k] = evaluate(x, el.scope, funcs)
    for k, key in enumerate(("tc1", "tc2")):
        if key in opts:
            tc[k] = evaluate(opts.pop(key), el.scope, funcs)
    if not any(tc):
        return value, ""
    tnom = evaluate(opts["tnom"], el.scope, funcs) if "tnom" in opts else TNOM
    if "temp" not in el.scope:
        return value, (f"{el.name}: TC={tc[0]:g},{tc[1]:g} taken at TNOM = {tnom:g} degC, the "
                       "value as written (--param TEMP=... evaluates it at another temperature)")
    dt = el.scope["temp"] - tnom
    return value * (1 + tc[0] * dt + tc[1] * dt * dt), \
        f"{el.name}: TC={tc[0]:g},{tc[1]:g} evaluated at TEMP = {el.scope['temp']:g} degC"


_HARMLESS = {"ic", "temp", "dtemp", "noiseless", "tnom"}


def linear_value(el: Element) -> Linear:
    """The value of resistor or capacitor ``el`` as a linear element.

    Raises
    ------
    spicethermal.io.spice_expr.NotConstant
        The value reads the circuit (``V()``, ``I()``, ``TIME``, ``TEMP``).
    ValueError
        Anything that is not a linear R or C (a non-zero ``TC``, ``Q=``, a model, an
        inductance ``Lser``), with the reason.

    Examples
    --------
    >>> from spicethermal.io.spice_read import Line
    >>> el = Element("C_CT6", "c", ("a", "0"), "115.1624u TC=0,0 Rpar=1G", Line("f", 1, ""),
    ...              Scope())
    >>> v = linear_value(el)
    >>> v.value, v.rpar, v.ignored
    (0.0001151624, 1000000000.0, ('TC=0,0',))
    """
    words = split_words(el.tail)
    if not words:
        raise ValueError("no value")
    first = words[0]
    letter = el.kind
    if re.match(rf"{letter}\s*=", first, re.I) or re.match(r"(value)\s*=", first, re.I):
        first = first.split("=", 1)[1]
    elif "=" in first:
        raise ValueError(f"cannot represent {el.tail!r}"
                         + (" (a charge Q=: not a linear C)" if first.lower().startswith("q")
                            else ""))
    rest = words[1:]
    if rest and "=" not in rest[0] and not first.startswith(("{", "'")) \
            and re.match(r"[a-z_]", first, re.I) and first.lower() not in el.scope:
        raise ValueError(f"uses model {first} (its parameters are not read): cannot represent "
                         f"{el.tail!r}")
    funcs = el.scope.functions()
    value = evaluate(first, el.scope, funcs)
    opts: dict[str, str] = {}
    flags: list[str] = []
    for w in rest:
        if "=" in w:
            k, v = w.split("=", 1)
            opts[k.lower()] = v
        else:
            flags.append(w)
    ignored = [w for w in rest if w.split("=")[0].lower() in _HARMLESS | {"tc", "tc1", "tc2"}]
    bad = [f for f in flags if f.lower() not in _HARMLESS]
    if bad:
        raise ValueError(f"cannot represent {el.tail!r} ({bad[0]!r})")
    value, note = _temperature_coefficient(el, value, opts)
    if note:
        ignored = [w for w in ignored if w.split("=")[0].lower() not in ("tc", "tc1", "tc2")]
    extra = {k: evaluate(v, el.scope, funcs) for k, v in opts.items() if k not in _HARMLESS}
    m = extra.pop("m", 1.0)
    if m <= 0:
        raise ValueError(f"multiplier M={m!r} must be > 0")
    lser = extra.pop("lser", 0.0)
    out = Linear(value / m if letter == "r" else value * m, extra.pop("rpar", None),
                 extra.pop("rser", None) or None, extra.pop("cpar", 0.0), tuple(ignored), note)
    if lser:
        raise ValueError(f"cannot represent {el.tail!r}: Lser={lser!r} is an inductance")
    if extra:
        raise ValueError(f"cannot represent {el.tail!r} (option {next(iter(extra))})")
    return out

