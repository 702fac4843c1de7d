"""Argument types shared by the commands: numbers that argparse rejects in one clear line.

Every numeric option goes through :func:`parse_si`: a number with an optional SI prefix and an
optional unit, so ``1k``, ``25kHz``, ``100u``, ``100us``, ``2.5m``, ``1e-4`` and ``20%`` all
read as expected (case matters as in SI: ``m`` is milli, ``M`` mega, ``K`` kelvin).
"""

from __future__ import annotations

import argparse
import copy
import math
import re
from collections.abc import Callable, Sequence
from decimal import Decimal
from typing import Any

#: SI prefixes (powers of ten) accepted before a unit or alone (``u`` and ``µ``: micro).
PREFIXES = {"f": -15, "p": -12, "n": -9, "u": -6, "µ": -6, "μ": -6, "m": -3, "k": 3, "M": 6,
            "G": 9}
#: Units accepted after a number (and its prefix); ``%`` takes no prefix and means 1/100.
UNITS = ("Hz", "s", "W", "K", "J", "V", "A", "%")
#: What an error message shows as accepted forms.
FORMS = "e.g. 1k, 25kHz, 100u, 100us, 2.5m, 1e-4, 20% (prefixes f p n u m k M G; units " \
        + " ".join(UNITS) + ")"
_SI = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*"
                 r"(?:(%)|([fpnuµμmkMG])?(Hz|s|W|K|J|V|A)?)\s*$")


def parse_si(text: str, unit: str | None = None) -> float:
    """A number with an optional SI prefix and unit: ``25kHz`` -> 25000.0.

    Parameters
    ----------
    text : the text of the option, e.g. ``1k``, ``25kHz``, ``100us``, ``2.5m``, ``20%``.
    unit : the only unit the option accepts, if given (``1K`` is not a frequency).

    Returns
    -------
    float : the value in SI base units (the unit itself is not converted, only checked).

    Examples
    --------
    >>> [parse_si(x) for x in ("1k", "25kHz", "100u", "100us", "2.5m", "1e-4", "20%", "-3 K")]
    [1000.0, 25000.0, 0.0001, 0.0001, 0.0025, 0.0001, 0.2, -3.0]
    >>> parse_si("1 kHzz")
    Traceback (most recent call last):
    ...
    argparse.ArgumentTypeError: '1 kHzz' is not a number: e.g. 1k, 25kHz, 100u, 100us, 2.5m, \
1e-4, 20% (prefixes f p n u m k M G; units Hz s W K J V A %)
    """
    match = _SI.match(text)
    if match is None:
        try:  # inf, nan: numbers, refused below with their own message
            return float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not a number: {FORMS}") from None
    value, percent, prefix, given = match.groups()
    if unit is not None and (given or percent or unit) != unit:
        raise argparse.ArgumentTypeError(f"{text!r}: the unit is {unit} (e.g. 1k, 25k{unit})")
    exponent = -2 if percent else PREFIXES.get(prefix or "", 0)
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
    """A frequency > 0 in Hz (``25k``, ``25kHz``; ``1K`` is refused, K being kelvin).

    >>> frequency("25kHz")
    25000.0
    """
    return number(text, low=0.0, open_low=True, unit="Hz")


def nonnegative(text: str) -> float:
    """A finite float >= 0."""
    return number(text, low=0.0)


def duty(text: str) -> float:
    """A duty cycle in [0, 1]."""
    return number(text, low=0.0, high=1.0)


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


def add_option(parser: argparse.ArgumentParser, *names: str, old: Sequence[str] = (),
               **kwargs: Any) -> argparse.Action:
    """``parser.add_argument(*names, **kwargs)`` that also accepts the ``old`` spellings.

    The old spellings parse exactly as the new ones but are left out of ``--help``, docs/cli.md
    and the spelling rules of ``tests/test_cli_spelling.py``.

    Parameters
    ----------
    parser : the command's parser.
    names : the option's spellings (``"-o", "--output"``).
    old : earlier spellings kept working (``"--out"``).
    kwargs : as for :meth:`argparse.ArgumentParser.add_argument`.

    Returns
    -------
    argparse.Action : the option, with ``hidden_aliases`` set to ``old``.

    Examples
    --------
    >>> p = argparse.ArgumentParser(prog="x")
    >>> _ = add_option(p, "--freq", old=("--f-pwm",), type=float)
    >>> p.parse_args(["--f-pwm", "5"]).freq, "--f-pwm" in p.format_help()
    (5.0, False)
    """
    action = parser.add_argument(*names, *old, **kwargs)
    action.hidden_aliases = tuple(old)  # type: ignore[attr-defined]
    parser.formatter_class = AliasFormatter
    return action


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
    parser.add_argument("--engine", choices=choices, default="auto", help=engine_help)
    parser.add_argument("-q", "--quiet", action="store_true", help=QUIET_HELP)
