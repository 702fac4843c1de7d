"""Argument types shared by the commands: numbers that argparse rejects in one clear line.

Every numeric option goes through :func:`parse_si`: a number, an optional prefix, an optional
unit (spaces allowed between them: ``25 kHz``). The rule reads SPICE and SI spellings alike
wherever they agree:

* **prefixes**, any case: ``f`` femto, ``p`` pico, ``n`` nano, ``u`` or ``µ`` micro, ``m``
  milli, ``k``/``K`` kilo, ``meg`` mega (``MEG``, ``Meg``), ``g``/``G`` giga;
* a capital **M** is refused, alone or before a unit (``94M``, ``25MHz``): it is milli in
  SPICE and mega in SI, and the error names both (write ``94m`` or ``94meg``);
* **units**, any case, checked but not converted: ``Hz``, ``s``, ``W``, ``J``, ``V``, ``A``
  (``25KHz``, ``94mw``, ``100us``); ``%`` takes no prefix and means 1/100;
* **K** is kilo, as in SPICE (``25K`` is 25000), except on an option measured in kelvin (its
  metavar is ``K``, e.g. ``drive --tol``), where a trailing ``K`` is the unit (``--tol 0.5K``);
  temperatures in °C take no unit;
* an option that has a unit refuses the others (``--freq 1s``); a **negative** value reads as
  a value, not as an option (``--ambient -40``, ``--k-factor -2.1``), and is refused in one line
  where it makes no sense (``--power -94m``: must be >= 0).
"""

from __future__ import annotations

import argparse
import copy
import math
import re
import sys
from collections.abc import Callable, Sequence
from decimal import Decimal
from typing import Any

#: Prefixes (powers of ten), read in any case (``u`` and ``µ``: micro; ``meg``: mega); a
#: capital ``M`` alone is refused (:data:`AMBIGUOUS`).
PREFIXES = {"f": -15, "p": -12, "n": -9, "u": -6, "µ": -6, "μ": -6, "m": -3, "k": 3, "meg": 6,
            "g": 9}
#: Units accepted after a number (and its prefix), in any case; ``%`` takes no prefix and means
#: 1/100. ``K`` (kelvin) only on an option measured in kelvin: elsewhere it is kilo.
UNITS = ("Hz", "s", "W", "J", "V", "A", "%")
#: What an error message shows as accepted forms.
FORMS = ("e.g. 1k, 25kHz, 100u, 100us, 2.5m, 94mW, 25meg, 1e-4, 20% (prefixes f p n u m k meg "
         "g, any case; units " + " ".join(UNITS) + ", any case)")
#: Why a capital M is refused.
AMBIGUOUS = "M is milli in SPICE and mega in SI: write {m} (milli) or {meg} (mega)"
_NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
_SI = re.compile(rf"^\s*({_NUMBER})\s*([^\s\d.+-]*)\s*$")
#: What argparse reads as a negative number rather than an option (``-94m``, ``-40``, ``-2.5e3``).
NEGATIVE = re.compile(r"^-(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?\s*[^\s\d.+-]*$")


def _split(suffix: str, unit: str | None) -> tuple[str, str]:
    """``(prefix, unit)`` of the letters after a number (the unit matched case-insensitively,
    kelvin only when the option's ``unit`` is ``K``)."""
    units = (*UNITS[:-1], "K") if unit == "K" else UNITS[:-1]
    for name in sorted(units, key=len, reverse=True):
        if name == "K" and suffix.endswith("K") or name != "K" and \
                suffix.lower().endswith(name.lower()):
            return suffix[:len(suffix) - len(name)], name
    return suffix, ""


def parse_si(text: str, unit: str | None = None) -> float:
    """A number with an optional prefix and unit, SPICE or SI spelling: ``25kHz`` -> 25000.0.

    Parameters
    ----------
    text : the text of the option, e.g. ``1k``, ``25KHz``, ``100us``, ``94mw``, ``25meg``,
        ``20%`` (the rule: the module's docstring).
    unit : the only unit the option accepts, if given (``1s`` is not a frequency); ``"K"``
        makes a trailing ``K`` kelvin instead of kilo.

    Returns
    -------
    float : the value in SI base units (the unit itself is not converted, only checked).

    Examples
    --------
    >>> [parse_si(x) for x in ("1k", "25KHz", "100u", "100us", "2.5m", "94mw", "25meg", "20%")]
    [1000.0, 25000.0, 0.0001, 0.0001, 0.0025, 0.094, 25000000.0, 0.2]
    >>> parse_si("5K"), parse_si("0.5K", unit="K"), parse_si("-94m")
    (5000.0, 0.5, -0.094)
    >>> parse_si("94M")
    Traceback (most recent call last):
    ...
    argparse.ArgumentTypeError: '94M': M is milli in SPICE and mega in SI: write 94m (milli) \
or 94meg (mega)
    """
    match = _SI.match(text)
    if match is None:
        try:  # inf, nan: numbers, refused below with their own message
            return float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not a number: {FORMS}") from None
    value, suffix = match.groups()
    if suffix == "%":
        prefix, given, exponent = "", "%", -2
    else:
        prefix, given = _split(suffix, unit)
        if prefix == "M":
            rest = f"{value}{{}}{given}"
            raise argparse.ArgumentTypeError(
                f"{text!r}: " + AMBIGUOUS.format(m=rest.format("m"), meg=rest.format("meg")))
        if prefix.lower() not in PREFIXES and prefix:
            raise argparse.ArgumentTypeError(f"{text!r} is not a number: {FORMS}")
        exponent = PREFIXES.get(prefix.lower(), 0)
    if unit is not None and given and given.lower() != unit.lower():
        raise argparse.ArgumentTypeError(f"{text!r}: the unit is {unit} (e.g. 1k, 25k{unit})")
    return float(Decimal(value).scaleb(exponent))  # exact: 100u is 1e-4, not 9.999...e-05


def number(text: str, low: float | None = None, open_low: bool = False,
           high: float | None = None, open_high: bool = False, unit: str | None = None) -> float:
    """A finite number (:func:`parse_si`), optionally bounded (``open_*`` excludes the bound).

    >>> number("2.5", low=0)
    2.5
    >>> number("25kHz", low=0)
    25000.0
    """
    value = parse_si(text, unit)
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"{text!r} is not a finite number")
    if low is not None and (value <= low if open_low else value < low):
        raise argparse.ArgumentTypeError(f"{text!r} must be {'>' if open_low else '>='} {low:g}")
    if high is not None and (value >= high if open_high else value > high):
        raise argparse.ArgumentTypeError(f"{text!r} must be {'<' if open_high else '<='} "
                                         f"{high:g}")
    return value


def positive(text: str) -> float:
    """A finite float > 0."""
    return number(text, low=0.0, open_low=True)


def frequency(text: str) -> float:
    """A frequency > 0 in Hz (``25k``, ``25KHz``, ``25meg``; ``1s`` is refused).

    >>> frequency("25kHz"), frequency("25K")
    (25000.0, 25000.0)
    """
    return number(text, low=0.0, open_low=True, unit="Hz")


def nonnegative(text: str) -> float:
    """A finite float >= 0."""
    return number(text, low=0.0)


def duty(text: str) -> float:
    """A duty cycle in [0, 1]."""
    return number(text, low=0.0, high=1.0)


def quantity(unit: str, low: float | None = 0.0, open_low: bool = False
             ) -> Callable[[str], float]:
    """The argument type of an option measured in ``unit`` (``W``, ``s``, ``K``), bounded below
    by ``low`` (``open_low`` excludes it; None: any sign).

    >>> watts = quantity("W")
    >>> watts("94mw"), watts("94 mW"), watts("0.094")
    (0.094, 0.094, 0.094)
    >>> watts("-94m")
    Traceback (most recent call last):
    ...
    argparse.ArgumentTypeError: '-94m' must be >= 0
    """
    def parse(text: str) -> float:
        return number(text, low=low, open_low=open_low, unit=unit)

    parse.__name__ = f"quantity_{unit}"
    return parse


#: A power in W (>= 0), a power in W (> 0), a time in s (>= 0), a time in s (> 0).
power = quantity("W")
positive_power = quantity("W", open_low=True)
duration = quantity("s")
positive_duration = quantity("s", open_low=True)


def integer(text: str, low: int = 1) -> int:
    """A whole number >= ``low`` (default: a count, >= 1)."""
    try:
        value = int(text)
    except ValueError:
        try:
            real = parse_si(text)
        except argparse.ArgumentTypeError:
            real = math.nan
        if not (math.isfinite(real) and real == round(real)):
            raise argparse.ArgumentTypeError(f"{text!r} is not a whole number (e.g. 3, 10k)"
                                             ) from None
        value = int(round(real))
    if value < low:
        raise argparse.ArgumentTypeError(f"{text!r} must be >= {low}")
    return value


def count(text: str) -> int:
    """A whole number >= 1."""
    return integer(text, 1)


def index(text: str) -> int:
    """A whole number >= 0 (a node or curve index)."""
    return integer(text, 0)


def listed(kind: Callable[[str], float]) -> Callable[[str], tuple[float, ...]]:
    """A comma-separated list of ``kind`` values.

    >>> listed(positive)("1,2.5")
    (1.0, 2.5)
    """
    def parse(text: str) -> tuple[float, ...]:
        parts = [x.strip() for x in text.split(",") if x.strip()]
        if not parts:
            raise argparse.ArgumentTypeError("expected a comma-separated list of numbers")
        return tuple(kind(x) for x in parts)

    return parse


# ------------------------------------------------------------------------------ spellings
class AliasFormatter(argparse.HelpFormatter):
    """``--help`` without the old spellings an option still accepts (:func:`add_option`)."""

    def _format_action_invocation(self, action: argparse.Action) -> str:
        hidden = getattr(action, "hidden_aliases", ())
        if not hidden:
            return super()._format_action_invocation(action)
        shown = copy.copy(action)
        shown.option_strings = [s for s in action.option_strings if s not in hidden]
        return super()._format_action_invocation(shown)


#: How long an old spelling keeps working.
DEPRECATION = "it goes in the next release"


def deprecated(prog: str, old: str, new: str) -> None:
    """One line on stderr: ``old`` (an option, or a use of one) is deprecated for ``new``.

    >>> deprecated("spicethermal pwm", "--tref", "--ambient")  # on stderr
    """
    print(f"{prog}: note: {old} is deprecated, use {new} ({DEPRECATION})", file=sys.stderr)


_DEPRECATING: dict[type, type] = {}


def _deprecating(cls: type[argparse.Action]) -> type[argparse.Action]:
    """``cls`` that notes on stderr when it is given by one of its ``hidden_aliases``."""
    if cls not in _DEPRECATING:
        def __call__(self, parser, namespace, values, option_string=None):  # noqa: N807
            if option_string in self.hidden_aliases:
                shown = [s for s in self.option_strings if s not in self.hidden_aliases]
                deprecated(parser.prog, option_string, "/".join(shown))
            return cls.__call__(self, parser, namespace, values, option_string)

        _DEPRECATING[cls] = type(f"Deprecating{cls.__name__}", (cls,), {"__call__": __call__})
    return _DEPRECATING[cls]


def add_option(parser: argparse.ArgumentParser, *names: str, old: Sequence[str] = (),
               **kwargs: Any) -> argparse.Action:
    """``parser.add_argument(*names, **kwargs)`` that also accepts the ``old`` spellings.

    The old spellings parse exactly as the new ones, print a one-line deprecation note on
    stderr (:func:`deprecated`), and are left out of ``--help``, docs/cli.md and the spelling
    rules of ``tests/test_cli_spelling.py``.

    Parameters
    ----------
    parser : the command's parser.
    names : the option's spellings (``"-o", "--output"``).
    old : earlier spellings kept working for one release (``"--out"``).
    kwargs : as for :meth:`argparse.ArgumentParser.add_argument`.

    Returns
    -------
    argparse.Action : the option, with ``hidden_aliases`` set to ``old``.

    Examples
    --------
    >>> p = argparse.ArgumentParser(prog="x")
    >>> _ = add_option(p, "--freq", old=("--f-pwm",), type=float)
    >>> p.parse_args(["--freq", "5"]).freq, "--f-pwm" in p.format_help()
    (5.0, False)
    """
    action = parser.add_argument(*names, *old, **kwargs)
    action.hidden_aliases = tuple(old)  # type: ignore[attr-defined]
    if old:
        action.__class__ = _deprecating(type(action))
    parser.formatter_class = AliasFormatter
    return action


#: Suffixes of a figure file.
FIGURE_SUFFIXES = (".png", ".svg", ".pdf")


def old_figure_output(args: argparse.Namespace, dest: str = "output") -> str | None:
    """``-o FIG.png``, the figure's old spelling: taken out of ``args.<dest>`` into
    ``args.plot`` (unless ``--plot`` is given) with a deprecation note; returns that figure path.

    ``args.<dest>`` may be a path or a list of paths (an ``append`` option).

    Examples
    --------
    >>> args = argparse.Namespace(command="curves", output="fig.png", plot=None)
    >>> old_figure_output(args), args.plot, args.output
    ('fig.png', 'fig.png', None)
    """
    value = getattr(args, dest)
    paths = value if isinstance(value, list) else [value] if value is not None else []
    figures = [x for x in paths if x.lower().endswith(FIGURE_SUFFIXES)]
    if not figures:
        return None
    deprecated(f"spicethermal {args.command}", f"-o {figures[0]} (a figure)",
               f"--plot {figures[0]}; -o is the data output")
    args.plot = args.plot or figures[0]
    rest = [x for x in paths if x not in figures]
    setattr(args, dest, rest if isinstance(value, list) else rest[0] if rest else None)
    return figures[0]


# ------------------------------------------------------------------------------ shared options
#: Help of ``-q/--quiet`` where a command shows a progress bar.
QUIET_HELP = "no progress bar on stderr (none either when it is not a terminal)"


def add_engine_options(parser: argparse.ArgumentParser, choices: Sequence[str],
                       engine_help: str) -> None:
    """``--engine`` (one of ``choices``, default ``auto``) and ``-q/--quiet`` (no progress bar).

    Parameters
    ----------
    parser : the command's parser.
    choices : the engines the command accepts.
    engine_help : what ``--engine`` chooses in this command.

    Returns
    -------
    None : the options are added to ``parser``.

    Examples
    --------
    >>> p = argparse.ArgumentParser(prog="x")
    >>> add_engine_options(p, ("auto", "ngspice"), "engine of the check")
    >>> p.parse_args(["-q"]), p.parse_args(["--engine", "ngspice"]).engine
    (Namespace(engine='auto', quiet=True), 'ngspice')
    """
    parser.add_argument("--engine", choices=choices, default="auto",
                        help=f"{engine_help} (default auto)")
    parser.add_argument("-q", "--quiet", action="store_true", help=QUIET_HELP)
