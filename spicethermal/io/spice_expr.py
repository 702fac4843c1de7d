"""SPICE numbers and parameter expressions, as PSpice, LTspice and ngspice libraries write them.

:func:`spice_number` reads ``1.51m``, ``2MEG``, ``10kOhm``, ``4k7``; :func:`evaluate` a
constant expression of numbers, parameters (any case), ``+ - * / ** ^``, comparisons, ``&``
``|`` ``!``, parentheses and the functions vendors use. ``limit(x, a, b)`` is PSpice's
*clamp* of ``x`` to ``[a, b]`` (ngspice's ``limit`` is a random Monte-Carlo function of another
meaning: spicethermal evaluates, it never writes ``limit`` into a netlist). Anything that
depends on the circuit — ``V(...)``, ``I(...)``, ``TIME``, ``TEMP`` unless given as a
parameter — raises :class:`NotConstant`. :class:`Scope` holds the parameters of one
subcircuit instance, evaluated on demand, and its ``.FUNC`` functions.
"""

from __future__ import annotations

import ast
import math
import re
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass

_EXPONENT = {"t": 12, "g": 9, "meg": 6, "k": 3, "m": -3, "u": -6, "µ": -6, "n": -9, "p": -12,
             "f": -15}
_NUMBER = re.compile(r"([0-9]+\.?[0-9]*|\.[0-9]+)(e[+-]?[0-9]+)?(meg|mil|[tgkmuµnpf])?([a-zµ]*)",
                     re.I)
_INFIX = re.compile(r"([0-9]+)(meg|[tgkmunpf])([0-9]+)", re.I)  # 4k7 = 4.7k
_TOKEN = re.compile(r"\s*(?:(?P<num>(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:e[+-]?[0-9]+)?[a-zµ]*)"
                    r"|(?P<name>[a-z_][a-z0-9_.$]*)"
                    r"|(?P<op>\*\*|==|!=|<>|<=|>=|&&|\|\||[-+*/^(),<>!&|]))", re.I)


def _clamp(x: float, lo: float, hi: float) -> float:
    return min(max(x, min(lo, hi)), max(lo, hi))


def _pwr(x: float, y: float) -> float:
    return math.pow(abs(x), y)


#: Functions an expression may call (lower case), with PSpice's meanings.
FUNCTIONS: dict[str, Callable[..., float]] = {
    "limit": _clamp, "min": min, "max": max, "abs": abs, "sqrt": math.sqrt, "exp": math.exp,
    "log": math.log, "ln": math.log, "log10": math.log10, "pow": math.pow, "pwr": _pwr,
    "pwrs": lambda x, y: math.copysign(_pwr(x, y), x), "sgn": lambda x: (x > 0) - (x < 0),
    "sign": lambda x, y=1.0: math.copysign(abs(x), y), "int": lambda x: float(int(x)),
    "floor": math.floor, "ceil": math.ceil, "round": round, "sin": math.sin, "cos": math.cos,
    "tan": math.tan, "atan": math.atan, "arctan": math.atan, "atan2": math.atan2,
    "sinh": math.sinh, "cosh": math.cosh, "tanh": math.tanh, "asinh": math.asinh,
    "hypot": math.hypot, "if": lambda c, a, b: a if c else b,
    "u": lambda x: float(x > 0), "stp": lambda x: float(x > 0)}
#: Names that read the circuit: an expression with one of them is no constant.
CIRCUIT = {"v": "a node voltage V(...)", "i": "a branch current I(...)", "time": "TIME",
           "ddt": "a derivative ddt(...)", "sdt": "an integral sdt(...)",
           "idt": "an integral idt(...)", "table": "a TABLE of a circuit quantity",
           "delay": "a delay", "temp": "the simulator temperature TEMP"}


class NotConstant(ValueError):
    """An expression that depends on the circuit (a voltage, a current, time, TEMP)."""


def spice_number(text: str) -> float:
    """A SPICE number: scale suffixes (``meg``, ``k``, ``m``, ``u``, ...) in any case, trailing
    unit letters ignored, and the infix form ``4k7``.

    >>> spice_number("1.51m"), spice_number("862.111u"), spice_number("2MEG"), spice_number("1uF")
    (0.00151, 0.000862111, 2000000.0, 1e-06)
    >>> spice_number("4k7"), spice_number("10kOhm")
    (4700.0, 10000.0)
    """
    text = text.strip()
    infix = _INFIX.fullmatch(text)
    if infix:
        text = f"{infix.group(1)}.{infix.group(3)}{infix.group(2)}"
    m = _NUMBER.fullmatch(text)
    if not m:
        raise ValueError(f"{text!r} is not a number")
    exponent = int((m.group(2) or "e0")[1:])
    suffix = (m.group(3) or "").lower()
    if suffix == "mil":
        return float(f"{m.group(1)}e{exponent}") * 25.4e-6
    return float(f"{m.group(1)}e{exponent + _EXPONENT.get(suffix, 0)}")  # exact decimal


def unwrap(expr: str) -> str:
    """An expression without its ``{...}`` or ``'...'`` delimiters.

    >>> unwrap(" {a*2} "), unwrap("'x'"), unwrap("3")
    ('a*2', 'x', '3')
    """
    text = expr.strip()
    while len(text) >= 2 and (text[0], text[-1]) in (("{", "}"), ("'", "'"), ('"', '"')):
        text = text[1:-1].strip()
    return text


def evaluate(expr: str, params: Mapping[str, float],
             funcs: Mapping[str, Callable[..., float]] | None = None) -> float:
    """Value of a constant SPICE expression.

    Parameters
    ----------
    expr : str
        The expression, with or without ``{}``/``''`` delimiters.
    params : mapping of str to float
        Parameter values by lower-case name (a :class:`Scope` evaluates them on demand).
    funcs : mapping of str to callable, optional
        More functions by lower-case name (a library's ``.FUNC`` definitions).

    Returns
    -------
    float

    Raises
    ------
    NotConstant
        The expression reads the circuit (``V()``, ``I()``, ``TIME``, ``TEMP``).
    ValueError
        Anything else that is not a valid constant expression.

    Examples
    --------
    >>> evaluate("{1.2m+limit(Zthtype,0,1)*448.29u}", {"zthtype": 1.0})
    0.00164829
    >>> evaluate("if(a>=2, 1k, 2k)", {"a": 2.0})
    1000.0
    """
    text = unwrap(expr)
    functions = {**FUNCTIONS, **(funcs or {})}
    parts: list[str] = []
    pos = 0
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
            parts.append(_name(m.group("name"), text[pos:].lstrip().startswith("("), params,
                               functions, expr))
        else:
            op = m.group("op")
            parts.append({"^": "**", "&&": " and ", "&": " and ", "||": " or ", "|": " or ",
                          "!": " not ", "<>": "!="}.get(op, op))
    return _safe_eval(" ".join(parts), expr, functions)


def _name(word: str, call: bool, params: Mapping[str, float],
          functions: Mapping[str, Callable[..., float]], expr: str) -> str:
    name = word.lower()
    if call and name in functions:
        return f"f_{name.replace('.', '_').replace('$', '_')}"
    if not call and name in params:
        return repr(float(params[name]))
    if name in CIRCUIT and (call or name in ("time", "temp")):
        hint = " (give --param TEMP=...)" if name == "temp" else ""
        raise NotConstant(f"{expr.strip()!r} depends on {CIRCUIT[name]}{hint}")
    if call:
        raise ValueError(f"unknown function {word!r} in expression {expr.strip()!r}")
    raise ValueError(f"unknown parameter {word!r}")


_ALLOWED = (ast.Expression, ast.BinOp, ast.UnaryOp, ast.BoolOp, ast.Compare, ast.Constant,
            ast.Call, ast.Name, ast.Load, ast.Add, ast.Sub, ast.Mult, ast.Div, ast.Pow,
            ast.USub, ast.UAdd, ast.Not, ast.And, ast.Or, ast.Eq, ast.NotEq, ast.Lt, ast.LtE,
            ast.Gt, ast.GtE)


def _safe_eval(code: str, expr: str, functions: Mapping[str, Callable[..., float]]) -> float:
    try:
        tree = ast.parse(code, mode="eval")
    except SyntaxError:
        raise ValueError(f"expression {expr!r} is not valid") from None
    env = {f"f_{k.replace('.', '_').replace('$', '_')}": v for k, v in functions.items()}
    for node in ast.walk(tree):
        if not isinstance(node, _ALLOWED) or (isinstance(node, ast.Name) and node.id not in env):
            raise ValueError(f"expression {expr!r} is not a simple expression")
    try:
        value = eval(compile(tree, "<spice>", "eval"), {"__builtins__": {}}, env)
    except (ArithmeticError, TypeError, ValueError) as exc:
        if isinstance(exc, NotConstant):
            raise
        raise ValueError(f"expression {expr!r} cannot be evaluated ({exc})") from None
    return float(value)


@dataclass(frozen=True)
class Definition:
    """A parameter's expression, where it is written (for messages) and the scope its names are
    read in (None: the scope that holds it; an instance's ``PARAMS:`` are read in the
    caller's)."""

    text: str
    where: str
    scope: Scope | None = None


@dataclass(frozen=True)
class Function:
    """A ``.FUNC name(args) {body}`` definition."""

    args: tuple[str, ...]
    body: str
    where: str


class Scope(Mapping[str, float]):
    """The parameters and functions one subcircuit instance sees, evaluated on demand: its own
    definitions, then its parent's (the library's global ``.PARAM`` lines).

    >>> g = Scope({"rtot": Definition("1.5", "line 1")})
    >>> s = Scope({"half": Definition("{rtot/2}", "line 3")}, parent=g)
    >>> s["half"], "rtot" in s, "nope" in s
    (0.75, True, False)
    """

    def __init__(self, defs: Mapping[str, Definition] | None = None, parent: Scope | None = None,
                 funcs: Mapping[str, Function] | None = None) -> None:
        self.defs = dict(defs or {})
        self.parent = parent
        self.funcs = dict(funcs or {})
        self._values: dict[str, float] = {}
        self._active: set[str] = set()

    def __getitem__(self, name: str) -> float:
        if name in self._values:
            return self._values[name]
        if name not in self.defs:
            if self.parent is None:
                raise KeyError(name)
            return self.parent[name]
        if name in self._active:
            raise ValueError(f"{self.defs[name].where}: parameter {name!r} depends on itself")
        d = self.defs[name]
        self._active.add(name)
        try:
            scope = d.scope or self
            value = evaluate(d.text, scope, scope.functions())
        except NotConstant as exc:
            raise NotConstant(f"{d.where}: parameter {name}: {exc}") from None
        except ValueError as exc:
            text = str(exc)
            raise ValueError(text if text.startswith(d.where) else
                             f"{d.where}: parameter {name}: {text}") from None
        finally:
            self._active.discard(name)
        self._values[name] = value
        return value

    def __contains__(self, name: object) -> bool:
        return name in self.defs or (self.parent is not None and name in self.parent)

    def __iter__(self) -> Iterator[str]:
        seen = set(self.defs)
        yield from self.defs
        if self.parent is not None:
            yield from (n for n in self.parent if n not in seen)

    def __len__(self) -> int:
        return sum(1 for _ in self)

    def functions(self) -> dict[str, Callable[..., float]]:
        """The ``.FUNC`` functions visible here, as callables (inner definitions first)."""
        out = self.parent.functions() if self.parent is not None else {}
        for name, f in self.funcs.items():
            out[name] = self._callable(name, f)
        return out

    def _callable(self, name: str, f: Function) -> Callable[..., float]:
        def call(*values: float) -> float:
            if len(values) != len(f.args):
                raise ValueError(f"{f.where}: {name}() takes {len(f.args)} arguments, "
                                 f"got {len(values)}")
            local = Scope({a: Definition(repr(float(v)), f.where) for a, v in
                           zip(f.args, values, strict=True)}, parent=self)
            return evaluate(f.body, local, local.functions())
        return call
