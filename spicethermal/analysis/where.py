"""Where a residual sits: one sentence per data set beyond its noise, and the number formats
the diagnosis's sentences share.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import TYPE_CHECKING

import numpy as np

from ..effects.base import CALIBRATION, PWM, STEADY
from .compare import Comparison

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

__all__ = ["fmt_number", "fmt_time", "localise", "rms"]


def rms(x: NDArray) -> float:
    """Root mean square of ``x`` (NaN when empty)."""
    return float(np.sqrt(np.mean(x * x))) if x.size else math.nan


def fmt_time(t: float) -> str:
    """A time in s, ms, µs or ns, without scientific notation.

    >>> fmt_time(1e-4), fmt_time(2.5)
    ('100 µs', '2.5 s')
    """
    for unit, scale in (("s", 1.0), ("ms", 1e-3), ("µs", 1e-6), ("ns", 1e-9)):
        if t >= scale * 0.999:
            return f"{fmt_number(t / scale)} {unit}"
    return f"{fmt_number(t / 1e-9)} ns"


def fmt_number(x: float, digits: int = 3) -> str:
    """``x`` to ``digits`` significant digits, positional (never ``1e-05``), ``−`` for minus.

    >>> fmt_number(-1.23456e-5), fmt_number(146.0)
    ('−0.0000123', '146')
    """
    x = float(x) if abs(x) >= 1e-9 else 0.0
    text = np.format_float_positional(x, precision=digits, unique=False, fractional=False,
                                      trim="-")
    return text.replace("-", "−")


def _groupings(sub: Comparison, name: str) -> list[list[tuple[str, NDArray]]]:
    """Ways to split one data set: the PWM grid by frequency and by duty, the calibration by
    20 K band, a cooling curve by time decade (a sparse end decade joins its neighbour)."""
    pts, r = sub.points, sub.residuals_k

    def split(labels: list[str]) -> list[tuple[str, NDArray]]:
        groups: dict[str, list[float]] = {}
        for lab, x in zip(labels, r, strict=True):
            groups.setdefault(lab, []).append(float(x))
        return [(k, np.array(v)) for k, v in groups.items()]

    if name == PWM:
        return [split([f"{p.at['freq_hz'] / 1e3:g} kHz" for p in pts]),
                split([f"duty {100 * p.at['duty']:g} %" for p in pts])]
    if name == CALIBRATION:
        lows = [20 * math.floor(p.at["temp_c"] / 20) for p in pts]
        return [split([f"{lo:g}-{lo + 20:g} °C" for lo in lows])]
    if name == STEADY:
        return [split([f"{p.at['power_w']:.3g} W" for p in pts])]
    ks = np.floor(np.log10([p.at["t_s"] for p in pts]) + 1e-9).astype(int)
    for end, step in ((ks.max(), -1), (ks.min(), 1)):
        if np.sum(ks == end) < 3 and np.unique(ks).size > 1:
            ks[ks == end] = end + step
    return [split([f"{fmt_time(10.0 ** k)}-{fmt_time(10.0 ** (k + 1))}" for k in ks])]


def localise(comparison: Comparison, noise: Mapping[str, float],
             beyond: Mapping[str, bool]) -> list[str]:
    """One sentence per data set marked ``beyond`` its noise, worst first (by RMS over
    noise): where its residuals are largest and their sign.

    Parameters
    ----------
    comparison : Comparison
    noise : mapping of data set name to noise (K)
    beyond : mapping of data set name to whether it is beyond its noise

    Returns
    -------
    list of str
    """
    found = []
    for name, sub in comparison.by_dataset().items():
        if not beyond.get(name):
            continue
        total, sigma = sub.rms_k, noise[name]
        parts = []
        for grouping in _groupings(sub, name):
            label, worst = max(grouping, key=lambda g: rms(g[1]))
            mean = float(np.mean(worst))
            parts.append(f"{label} (RMS {rms(worst):.3g} K, readings "
                         f"{'above' if mean > 0 else 'below'} the model by {abs(mean):.3g} K "
                         f"on average)")
        found.append((total / sigma, f"{name}: RMS {total:.3g} K ({total / sigma:.1f}× its "
                      f"noise), largest at " + " and at ".join(parts)))
    return [s for _, s in sorted(found, key=lambda x: -x[0])]
