"""Vendors' thermal models: SPICE subcircuits of R and C elements, and datasheet Foster tables.

:func:`read_library` reads a SPICE library the way simulators do (continuation lines, ``*``
and ``;`` comments, any letter case, ``.param`` constants and simple expressions of them,
``PARAMS:`` defaults, number suffixes such as ``1.51m``, ``204.865u``, ``2meg``).
:func:`import_subckt` turns one subcircuit into a :class:`~spicethermal.model.ThermalModel`,
exactly (no refit): a Foster chain (each capacitor across its resistor) or a Cauer ladder
(capacitors to node 0, to a pin used as thermal ground, or to the reference pin; a missing or
zero capacitor is a node without heat capacity; a capacitor on the reference pin is the case
capacitance). Anything else (behavioural or dependent sources, subcircuit instances, branches
off the chain) is refused with a one-line error naming the file and line.
"""

from __future__ import annotations

import ast
import math
import os
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path

from ..core.errors import DataFormatError
from ..core.ladder import Cauer, Foster
from ..model import ThermalModel
from .datasheet import read_foster_table

_EXPONENT = {"t": 12, "g": 9, "meg": 6, "k": 3, "m": -3, "u": -6, "n": -9, "p": -12, "f": -15}
_NUMBER = re.compile(r"([0-9]+\.?[0-9]*|\.[0-9]+)(e[+-]?[0-9]+)?(meg|mil|[tgkmunpf])?[a-z]*",
                     re.I)
_TOKEN = re.compile(r"\s*(?:(?P<num>(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:e[+-]?[0-9]+)?"
                    r"(?:meg|mil|[tgkmunpf])?[a-z]*)|(?P<name>[a-z_][a-z0-9_.]*)"
                    r"|(?P<op>\*\*|[-+*/^(),]))", re.I)
_FUNCS: dict[str, Callable[..., float]] = {
    "limit": lambda x, lo, hi: min(max(x, min(lo, hi)), max(lo, hi)), "min": min, "max": max,
    "abs": abs, "sqrt": math.sqrt, "exp": math.exp, "log": math.log, "ln": math.log,
    "log10": math.log10, "pow": math.pow, "pwr": math.pow}
_GROUND = {"0", "gnd"}
_JUNCTION = re.compile(r"t?_?j(unction|unc)?[0-9]*|tjunction|die", re.I)
_AMBIENT = re.compile(r"t?_?a(mb|mbient)?[0-9]*|tamb.*|ambient", re.I)


def spice_number(text: str) -> float:
    """A SPICE number: scale suffixes (``meg``, ``k``, ``m``, ``u``, ...) in any case, trailing
    unit letters ignored.

    >>> spice_number("1.51m"), spice_number("862.111u"), spice_number("2MEG"), spice_number("1uF")
    (0.00151, 0.000862111, 2000000.0, 1e-06)
    """
    m = _NUMBER.fullmatch(text.strip())
    if not m:
        raise ValueError(f"{text!r} is not a number")
    exponent = int((m.group(2) or "e0")[1:])
    suffix = (m.group(3) or "").lower()
    if suffix == "mil":
        return float(f"{m.group(1)}e{exponent}") * 25.4e-6
    return float(f"{m.group(1)}e{exponent + _EXPONENT.get(suffix, 0)}")  # exact decimal


def evaluate(expr: str, params: Mapping[str, float]) -> float:
    """Value of a SPICE expression of numbers, parameters (any case), ``+ - * / ** ^``,
    parentheses and the functions limit, min, max, abs, sqrt, exp, log, log10, pow.

    >>> evaluate("{1.2m+limit(Zthtype,0,1)*448.29u}", {"zthtype": 1.0})
    0.00164829
    """
    text = expr.strip()
    if len(text) >= 2 and (text[0], text[-1]) in (("{", "}"), ("'", "'")):
        text = text[1:-1]
    parts, pos = [], 0
    while pos < len(text):
        m = _TOKEN.match(text, pos)
        if not m or m.end() == pos:
            if text[pos:].strip() == "":
                break
            raise ValueError(f"cannot read {text[pos:]!r} in expression {expr!r}")
        pos = m.end()
        if m.group("num"):
            parts.append(repr(spice_number(m.group("num"))))
        elif m.group("name"):
            name = m.group("name").lower()
            if name in _FUNCS:
                parts.append(name)
            elif name in params:
                parts.append(repr(float(params[name])))
            else:
                raise ValueError(f"unknown parameter {m.group('name')!r}")
        else:
            parts.append("**" if m.group("op") == "^" else m.group("op"))
    return _safe_eval(" ".join(parts), expr)


_ALLOWED = (ast.Expression, ast.BinOp, ast.UnaryOp, ast.Constant, ast.Call, ast.Name, ast.Load,
            ast.Add, ast.Sub, ast.Mult, ast.Div, ast.Pow, ast.USub, ast.UAdd)


def _safe_eval(code: str, expr: str) -> float:
    try:
        tree = ast.parse(code, mode="eval")
    except SyntaxError:
        raise ValueError(f"expression {expr!r} is not valid") from None
    for node in ast.walk(tree):
        if not isinstance(node, _ALLOWED) or (isinstance(node, ast.Name) and node.id not in _FUNCS):
            raise ValueError(f"expression {expr!r} is not a simple expression")
    try:
        value = eval(compile(tree, "<spice>", "eval"), {"__builtins__": {}}, dict(_FUNCS))
    except (ArithmeticError, TypeError, ValueError) as exc:
        raise ValueError(f"expression {expr!r} cannot be evaluated ({exc})") from None
    return float(value)


@dataclass(frozen=True)
class Line:
    """One logical line (continuations joined): its first physical line number and text."""

    number: int
    text: str


@dataclass
class Subckt:
    """A subcircuit definition: name, pins, ``PARAMS:`` defaults and its body lines."""

    name: str
    pins: tuple[str, ...]
    number: int
    defaults: dict[str, str] = field(default_factory=dict)
    body: list[Line] = field(default_factory=list)


@dataclass
class Library:
    """A SPICE library: its subcircuits (in file order) and its global ``.param`` lines."""

    source: str
    subckts: list[Subckt]
    params: list[Line]

    def get(self, name: str | None) -> Subckt:
        """The subcircuit called ``name`` (any case), or the only one when ``name`` is None."""
        if name is None:
            if len(self.subckts) == 1:
                return self.subckts[0]
            raise DataFormatError(f"{self.source}: {len(self.subckts)} subcircuits "
                                  f"({', '.join(s.name for s in self.subckts) or 'none'}); "
                                  "choose one with --subckt")
        for s in self.subckts:
            if s.name.lower() == name.lower():
                return s
        raise DataFormatError(f"{self.source}: no subcircuit {name!r} (there are: "
                              f"{', '.join(s.name for s in self.subckts) or 'none'})")


def logical_lines(text: str) -> list[Line]:
    """Lines with ``+`` continuations joined and comments removed (``*`` lines, ``;`` and
    `` $ `` inline comments); the first line of a deck is not treated as a title.

    >>> [l.text for l in logical_lines("* c\\nR1 a b 1k ; r\\n+ TC=0\\n")]
    ['R1 a b 1k TC=0']
    """
    out: list[Line] = []
    for k, raw in enumerate(text.splitlines(), 1):
        line = re.split(r";| \$ ", raw, maxsplit=1)[0].strip()
        if not line or line.startswith("*"):
            continue
        if line.startswith("+"):
            if not out:
                raise DataFormatError(f"line {k}: a continuation line with nothing to continue")
            out[-1] = Line(out[-1].number, f"{out[-1].text} {line[1:].strip()}")
        else:
            out.append(Line(k, line))
    return out


def _assignments(text: str) -> dict[str, str]:
    """``a=1 b = {a*2}`` -> {"a": "1", "b": "{a*2}"} (names lower-cased)."""
    out = {}
    for m in re.finditer(r"([a-z_][a-z0-9_]*)\s*=\s*(\{[^}]*\}|'[^']*'|\S+)", text, re.I):
        out[m.group(1).lower()] = m.group(2)
    return out


def read_library(path: str | os.PathLike) -> Library:
    """Read the subcircuits and global parameters of a SPICE library file.

    Parameters
    ----------
    path : str or os.PathLike
        The SPICE library file.

    Returns
    -------
    Library
        Its subcircuits (by name) and ``.param`` values.
    """
    path = Path(path)
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        raise DataFormatError(f"{path}: file not found") from None
    except IsADirectoryError:
        raise DataFormatError(f"{path}: is a directory, expected a SPICE library") from None
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        text = raw.decode("latin-1")  # vendors' libraries often carry a Latin-1 degree sign
    try:
        lines = logical_lines(text)
    except DataFormatError as exc:
        raise DataFormatError(f"{path}, {exc}") from None
    subckts: list[Subckt] = []
    params: list[Line] = []
    stack: list[Subckt] = []
    for line in lines:
        word = line.text.split()[0].lower()
        if word == ".subckt":
            m = re.search(r"\s+params:", line.text, re.I)
            head, defaults = (line.text[:m.start()], line.text[m.end():]) if m else \
                (line.text, "")
            words = head.split()
            if len(words) < 2:
                raise DataFormatError(f"{path}, line {line.number}: .SUBCKT without a name")
            pins = tuple(w for w in words[2:] if "=" not in w)
            sub = Subckt(words[1], pins, line.number,
                         _assignments(" ".join(w for w in words[2:] if "=" in w) + " "
                                      + defaults))
            stack.append(sub)
            subckts.append(sub)
        elif word == ".ends":
            if not stack:
                raise DataFormatError(f"{path}, line {line.number}: .ENDS without .SUBCKT")
            stack.pop()
        elif stack:
            stack[-1].body.append(line)
        elif word == ".param":
            params.append(line)
    if stack:
        raise DataFormatError(f"{path}, line {stack[-1].number}: .SUBCKT {stack[-1].name} has "
                              "no .ENDS")
    return Library(str(path), subckts, params)


def _resolve(raw: dict[str, str], where: Callable[[str], str]) -> dict[str, float]:
    values: dict[str, float] = {}

    def get(name: str, seen: tuple[str, ...]) -> float:
        if name in values:
            return values[name]
        if name in seen:
            raise DataFormatError(f"{where(name)}parameter {name!r} depends on itself")
        deps = {}
        for ref in re.findall(r"[a-z_][a-z0-9_]*", raw[name].lower()):
            if ref in raw and ref != name:
                deps[ref] = get(ref, (*seen, name))
        try:
            values[name] = evaluate(raw[name], deps)
        except ValueError as exc:
            raise DataFormatError(f"{where(name)}parameter {name}: {exc}") from None
        return values[name]

    for name in raw:
        get(name, ())
    return values


def _elements(lib: Library, sub: Subckt) -> tuple[list[tuple], list[tuple]]:
    """Resistors and capacitors of ``sub`` as (name, a, b, value, line), nodes lower-cased."""
    src = lib.source
    lines_of = {}
    raw: dict[str, str] = {}
    for line in lib.params:
        for k, v in _assignments(line.text[len(".param"):]).items():
            raw[k], lines_of[k] = v, line.number
    for k, v in sub.defaults.items():
        raw[k], lines_of[k] = v, sub.number
    body = []
    for line in sub.body:
        if line.text.lower().startswith(".param"):
            for k, v in _assignments(line.text[len(".param"):]).items():
                raw[k], lines_of[k] = v, line.number
        else:
            body.append(line)
    params = _resolve(raw, lambda n: f"{src}, line {lines_of[n]}: ")
    rs, cs = [], []
    for line in body:
        words = line.text.split()
        kind = words[0][0].lower()
        at = f"{src}, line {line.number}: "
        if words[0].startswith("."):
            raise DataFormatError(f"{at}{words[0]} inside .SUBCKT {sub.name} cannot be imported "
                                  "(only R, C and .param)")
        if kind not in "rc":
            what = {"b": "a behavioural source", "e": "a dependent source",
                    "g": "a dependent source", "f": "a dependent source",
                    "h": "a dependent source", "x": "a subcircuit instance",
                    "v": "a source", "i": "a source", "l": "an inductor"}.get(kind, "an element")
            raise DataFormatError(f"{at}{words[0]} is {what}: a thermal network can be imported "
                                  "only when it is made of R and C elements")
        value = _element_value(words, at, params)
        a, b = words[1].lower(), words[2].lower()
        (rs if kind == "r" else cs).append((words[0], a, b, value, line.number))
    return rs, cs


def _element_value(words: list[str], at: str, params: Mapping[str, float]) -> float:
    if len(words) < 4:
        raise DataFormatError(f"{at}{words[0]} needs two nodes and a value")
    rest = " ".join(words[3:])
    m = re.fullmatch(r"(?:[rc]\s*=\s*)?(\{[^}]*\}|'[^']*'|[^\s=]+)\s*(.*)", rest, re.I)
    extra = _assignments(m.group(2)) if m else {}
    if not m or set(extra) - {"ic"} or (m.group(2) and not extra):
        raise DataFormatError(f"{at}{words[0]}: cannot represent {rest!r} (only a value, and "
                              "IC= on capacitors)")
    try:
        value = evaluate(m.group(1), params)
    except ValueError as exc:
        raise DataFormatError(f"{at}{words[0]}: {exc}") from None
    if not math.isfinite(value) or value < 0 or (value == 0 and words[0][0] in "rR"):
        raise DataFormatError(f"{at}{words[0]} = {value!r}: must be finite and "
                              f"{'> 0' if words[0][0] in 'rR' else '>= 0'}")
    return value


def _reference_label(pin: str) -> str:
    return "ambient" if _AMBIENT.fullmatch(pin) else "case"


def import_subckt(lib: Library, name: str | None = None,
                  reference: str | None = None) -> ThermalModel:
    """The thermal network of subcircuit ``name`` as a model, exactly as the vendor wrote it.

    Parameters
    ----------
    lib : Library
        From :func:`read_library`.
    name : str, optional
        Subcircuit name (any case); may be omitted when the library holds one.
    reference : str, optional
        ``case`` or ``ambient``; default from the reference pin's name (``Ta``, ``Tamb``:
        ambient; anything else: case, as vendors' device models are junction-to-case).

    Returns
    -------
    ThermalModel
        Foster or Cauer as the vendor wrote it (a Foster chain with a pure resistance becomes
        the equivalent Cauer ladder with a node without capacitance).

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
    sub = lib.get(name)
    rs, cs = _elements(lib, sub)
    at = f"{lib.source}, .SUBCKT {sub.name} (line {sub.number}): "
    pins = [p.lower() for p in sub.pins]
    if len(pins) < 2 or not rs:
        raise DataFormatError(f"{at}a thermal network needs two pins and resistors")
    junction = next((p for p in pins if _JUNCTION.fullmatch(p)), pins[0])
    chain, r = [junction], []
    used: set[int] = set()
    while chain[-1] not in pins or len(chain) == 1:
        nxt = [k for k, e in enumerate(rs) if k not in used and chain[-1] in e[1:3]]
        if not nxt:
            raise DataFormatError(f"{at}the resistor chain from pin {sub.pins[0]} ends at node "
                                  f"{chain[-1]}, not at a pin")
        if len(nxt) > 1:
            raise DataFormatError(f"{lib.source}, line {rs[nxt[1]][4]}: {rs[nxt[1]][0]} branches "
                                  f"off the chain at node {chain[-1]}: not a Foster or Cauer "
                                  "ladder")
        e = rs[nxt[0]]
        used.add(nxt[0])
        chain.append(e[2] if e[1] == chain[-1] else e[1])
        r.append(e[3])
        if chain[-1] in _GROUND or chain[-1] in chain[:-1]:
            raise DataFormatError(f"{lib.source}, line {e[4]}: {e[0]} closes the chain on "
                                  f"{chain[-1]}: not a Foster or Cauer ladder")
    for k, e in enumerate(rs):
        if k not in used:
            raise DataFormatError(f"{lib.source}, line {e[4]}: {e[0]} is not on the chain from "
                                  f"{chain[0]} to {chain[-1]}")
    idx = {n: i for i, n in enumerate(chain)}
    n = len(r)
    notes = []
    if cs and all(e[1] in idx and e[2] in idx and abs(idx[e[1]] - idx[e[2]]) == 1 for e in cs):
        c = [0.0] * n
        for e in cs:
            c[min(idx[e[1]], idx[e[2]])] += e[3]
        ladder = _foster_or_cauer(r, c)
        case_c = 0.0
    else:
        c, case_c, grounds = [0.0] * n, 0.0, set()
        for e in cs:
            ends = [(a, b) for a, b in ((e[1], e[2]), (e[2], e[1])) if a in idx
                    and (b in _GROUND or (b in pins and b not in idx))]
            ends += [(a, b) for a, b in ((e[1], e[2]), (e[2], e[1])) if a in idx
                     and b == chain[-1] and idx[a] < n]
            if not ends:
                raise DataFormatError(f"{lib.source}, line {e[4]}: {e[0]} connects {e[1]} and "
                                      f"{e[2]}: neither across a stage (Foster) nor to a "
                                      "thermal ground (Cauer)")
            node, gnd = ends[0]
            grounds.add(gnd)
            if idx[node] == n:
                case_c += e[3]
            else:
                c[idx[node]] += e[3]
        if len(grounds - _GROUND) > 1:
            raise DataFormatError(f"{at}capacitors connect to several grounds "
                                  f"({', '.join(sorted(grounds))})")
        if chain[-1] in grounds:
            notes.append(f"capacitors to the reference pin {chain[-1]}: imported as capacitors "
                         "to the thermal ground (the same with an ideal reference)")
        if not any(c):
            raise DataFormatError(f"{at}no capacitance on the chain from {chain[0]} to "
                                  f"{chain[-1]}")
        ladder = Cauer(r, c)
    pin_case = dict(zip(pins, sub.pins, strict=True))
    prov = {"source": Path(lib.source).name, "device": sub.name, "subckt": sub.name,
            "import": "vendor network, exact (no refit)",
            "pins": f"junction {pin_case[chain[0]]}, reference {pin_case[chain[-1]]}"}
    if notes:
        prov["note"] = "; ".join(notes)
    ref = reference or _reference_label(chain[-1])
    return ThermalModel(ladder, reference=ref, provenance=prov, case_c_j_per_k=case_c)


def _foster_or_cauer(r: list[float], c: list[float]) -> Foster | Cauer:
    """A Foster chain; stages without capacitance (pure resistances, τ = 0) make it the
    equivalent Cauer ladder whose junction node has no capacitance (exact)."""
    if all(c):
        return Foster(r, c)
    pure = sum(ri for ri, ci in zip(r, c, strict=True) if not ci)
    rest = Foster([ri for ri, ci in zip(r, c, strict=True) if ci], [ci for ci in c if ci])
    cauer = rest.to_cauer()
    return Cauer([pure, *cauer.r], [0.0, *cauer.c])


def import_table(path: str | os.PathLike, reference: str = "case") -> ThermalModel:
    """A datasheet Foster table (CSV: ``r_k_per_w`` and ``tau_s`` or ``c_j_per_k``) as a model."""
    foster = read_foster_table(path)
    return ThermalModel(foster, reference=reference,
                        provenance={"source": Path(path).name, "device": Path(path).stem,
                                    "import": "datasheet Foster table, exact (no refit)"})


def import_model(path: str | os.PathLike, subckt: str | None = None,
                 reference: str | None = None) -> ThermalModel:
    """A vendor's thermal model from a SPICE library or a datasheet Foster table (``.csv``).

    Parameters
    ----------
    path : str or os.PathLike
        A SPICE library (``.lib``, ``.mod``, ...) or a Foster table CSV.
    subckt : str, optional
        The subcircuit to import when the library holds several.
    reference : str, optional
        ``"case"`` or ``"ambient"``: what the network is measured to.

    Returns
    -------
    ThermalModel
        The vendor's network, exactly (no refit).
    """
    if Path(path).suffix.lower() == ".csv":
        if subckt is not None:
            raise DataFormatError(f"{path}: --subckt applies to SPICE libraries, not CSV tables")
        return import_table(path, reference or "case")
    return import_subckt(read_library(path), subckt, reference)
