"""Argument types shared by the commands: numbers that argparse rejects in one clear line."""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable


def number(text: str, low: float | None = None, open_low: bool = False,
           high: float | None = None, open_high: bool = False) -> float:
    """A finite float, optionally bounded (``open_*`` excludes the bound).

    >>> number("2.5", low=0)
    2.5
    """
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
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
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
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
