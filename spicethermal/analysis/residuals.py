"""Residuals of a model against a bundle: the comparison at every point, each data set's noise
estimate, where the misfit sits (:func:`localise`), and the number formats the diagnosis's
sentences share.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np

from ..fit.effectfit import BundleData, predict
from .compare import Comparison, ComparisonPoint

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

    from ..core.ladder import Cauer, Foster
    from ..effects import Effect

__all__ = ["EXPLAINED_RATIO", "NOISE_FLOOR_K", "PWM_OWN_NOISE_MIN", "comparison_of",
           "fmt_number", "fmt_time", "localise", "noise_estimates", "rms"]

#: A data set fits "within its noise" when its RMS is within this many noise estimates.
EXPLAINED_RATIO = 2.0
#: Noise estimates are at least this (K): the resolution of any real bench.
NOISE_FLOOR_K = 0.005
#: The calibration's noise is its residuals' scatter about a polynomial in T of this degree
#: (a TSP's curvature is smooth in T; consecutive differences of a few points would count the
#: bow as noise).
CAL_POLY_DEGREE = 3
#: Fraction of the largest consecutive residual differences left out of the noise estimate.
NOISE_TRIM = 0.1
#: A PWM grid of fewer readings gets at least the noise of the sensor that reads it, as its
#: calibration measures it (scatter about a cubic, at most the curves'): an estimate from the
#: differences of six readings of white noise falls below 0.44× the truth one time in twenty
#: (below 0.27× one in a hundred), and a grid judged against a noise estimated that low is
#: "3× its noise" on its noise alone (seed 303's draw 027 of the random validation set: a grid
#: of six at 0.0137 K, calibration and curves at 0.05 K); of twelve, 0.59× and 0.45×. Not
#: the curves' own estimate: a misfit on sparse curves inflates it (seed 5's draw 024: 0.14 K
#: for a sensor of 0.05 K), and the grid weighed that lightly let a band's fit trade it away.
PWM_OWN_NOISE_MIN = 12


def comparison_of(data: BundleData, ladder: Foster | Cauer, effects: Sequence[Effect] = (),
                  engine: str = "analytic") -> Comparison:
    """Measured vs model at every point of every data set (calibration included), as a
    :class:`~spicethermal.analysis.compare.Comparison` (its points carry the data set and
    ``at``)."""
    pred = predict(data, ladder, effects)
    points: list[ComparisonPoint] = []
    for name in data.datasets:
        for at, meas, mod in zip(data.coordinates(name), data.measured(name), pred[name],
                                 strict=True):
            points.append(ComparisonPoint(name, at, float(meas), float(mod)))
    return Comparison(tuple(points), engine)


def noise_estimates(comparison: Comparison) -> dict[str, float]:
    """Noise standard deviation (K) of every data set from consecutive residual differences
    (see the module docstring; the calibration from its scatter about a cubic in T), at least
    :data:`NOISE_FLOOR_K`.

    The differences ``Δr`` of white noise σ have variance ``2σ²``; the largest
    :data:`NOISE_TRIM` of them are left out (an electrical transient or a jump between PWM
    duty blocks is not noise) and the trimmed mean square is corrected for the trimming
    (Gaussian), ``σ² = mean(Δr²) / (2 c)``, ``c = 1 − 2 q φ(q) / p`` for the kept fraction
    ``p`` and ``q = Φ⁻¹((1 + p)/2)``.

    >>> noise = np.random.default_rng(1).normal(0.0, 0.05, 400)
    >>> trend = np.linspace(0.0, 3.0, 400)  # a smooth misfit does not count as noise
    >>> c = Comparison(tuple(ComparisonPoint("x", {"t_s": i + 1.0}, float(x), 0.0)
    ...                      for i, x in enumerate(noise + trend)))
    >>> round(noise_estimates(c)["x"], 2)
    0.05
    """
    from scipy.stats import norm

    out = {}
    sets = comparison.by_dataset()
    for name, sub in sets.items():
        r = sub.residuals_k
        if r.size < 3:
            out[name] = max(float(np.std(r)), NOISE_FLOOR_K)
            continue
        if name == "calibration" and r.size >= CAL_POLY_DEGREE + 5:
            # a smooth function of temperature: its scatter about a cubic, not its bow
            t = np.array([p.at["temp_c"] for p in sub.points])
            x = (t - t.mean()) / max(float(np.ptp(t)), 1e-9)
            fit = np.polyval(np.polyfit(x, r, CAL_POLY_DEGREE), x)
            dof = r.size - CAL_POLY_DEGREE - 1
            out[name] = max(math.sqrt(float(np.sum((r - fit) ** 2)) / dof), NOISE_FLOOR_K)
            continue
        d = np.sort(np.abs(np.diff(r)))
        keep = max(2, int(math.floor((1 - NOISE_TRIM) * d.size)))
        frac = keep / d.size
        c = 1.0
        if frac < 1:
            q = float(norm.ppf(0.5 * (1 + frac)))
            c = 1 - 2 * q * float(norm.pdf(q)) / frac
        sigma = math.sqrt(float(np.mean(d[:keep] ** 2)) / (2 * c))
        out[name] = max(sigma, NOISE_FLOOR_K)
    curves = [v for k, v in out.items() if k.startswith("cooling")]
    if "pwm" in out and curves:
        # the same TSP reads the PWM grid: its few readings, ordered by frequency and duty,
        # mix the misfit's pattern into their differences, so the curves' noise caps theirs,
        # and a grid too small to estimate its own gets at least the calibration's
        sensor = max(min(curves), NOISE_FLOOR_K)
        if len(sets["pwm"].points) >= PWM_OWN_NOISE_MIN:
            out["pwm"] = min(out["pwm"], sensor)
        else:  # too few for its own: at least the sensor's, as the calibration measures it
            out["pwm"] = min(max(out["pwm"], min(out.get("calibration", sensor), sensor)),
                             sensor)
    return out


def rms(x: NDArray) -> float:
    """Root mean square of ``x`` (NaN when empty)."""
    return float(np.sqrt(np.mean(x * x))) if x.size else math.nan


def _groupings(sub: Comparison, name: str) -> list[list[tuple[str, NDArray]]]:
    """Ways to split one data set for localisation, each a list of (label, residuals): the
    PWM grid by frequency and by duty, the calibration by 20 K band, a cooling curve by time
    decade (a decade at either end with fewer than 3 points joins its neighbour)."""
    pts, r = sub.points, sub.residuals_k

    def split(labels: list[str]) -> list[tuple[str, NDArray]]:
        groups: dict[str, list[float]] = {}
        for lab, x in zip(labels, r, strict=True):
            groups.setdefault(lab, []).append(float(x))
        return [(k, np.array(v)) for k, v in groups.items()]

    if name == "pwm":
        return [split([f"{p.at['freq_hz'] / 1e3:g} kHz" for p in pts]),
                split([f"duty {100 * p.at['duty']:g} %" for p in pts])]
    if name == "calibration":
        lows = [20 * math.floor(p.at["temp_c"] / 20) for p in pts]
        return [split([f"{lo:g}-{lo + 20:g} °C" for lo in lows])]
    ks = np.floor(np.log10([p.at["t_s"] for p in pts]) + 1e-9).astype(int)
    for end, step in ((ks.max(), -1), (ks.min(), 1)):
        if np.sum(ks == end) < 3 and np.unique(ks).size > 1:
            ks[ks == end] = end + step
    return [split([f"{fmt_time(10.0 ** k)}-{fmt_time(10.0 ** (k + 1))}" for k in ks])]


def fmt_time(t: float) -> str:
    """A time in s, ms, µs or ns, without scientific notation.

    >>> fmt_time(1e-4), fmt_time(2.5)
    ('100 µs', '2.5 s')
    """
    for unit, scale in (("s", 1.0), ("ms", 1e-3), ("µs", 1e-6), ("ns", 1e-9)):
        if t >= scale * 0.999:
            return f"{fmt_number(t / scale)} {unit}"
    return f"{fmt_number(t / 1e-9)} ns"


def fmt_against(x: float, limit: float, digits: int = 3) -> str:
    """``x`` to ``digits`` significant digits, or as many more as it takes to keep it on its
    side of ``limit``: a value short of a threshold never reads as reaching it.

    >>> fmt_against(96.6, 97.0, 2), fmt_against(1.1496, 1.15), fmt_against(9.6, 10.0, 1)
    ('96.6', '1.1496', '9.6')
    >>> fmt_against(12.3, 10.0, 2), fmt_against(126000.0, 10.0, 2)
    ('12', '130000')
    """
    for d in range(max(digits, 1), 17):
        text = np.format_float_positional(x, precision=d, unique=False, fractional=False,
                                          trim="-")
        if (float(text) < limit) == (x < limit):
            return text
    return np.format_float_positional(x, trim="-")


def fmt_number(x: float, digits: int = 3) -> str:
    """``x`` to ``digits`` significant digits, positional (never ``1e-05``), ``−`` for minus.

    >>> fmt_number(-1.23456e-5), fmt_number(146.0)
    ('−0.0000123', '146')
    """
    x = float(x) if abs(x) >= 1e-9 else 0.0  # below a nano-unit: nothing to show
    text = np.format_float_positional(x, precision=digits, unique=False, fractional=False,
                                      trim="-")
    return text.replace("-", "−")


def localise(comparison: Comparison, noise: Mapping[str, float] | None = None) -> list[str]:
    """One sentence per data set whose misfit exceeds its noise (all data sets when ``noise``
    is None), worst first: where its residuals are largest and their sign."""
    noise = noise or {}
    found = []
    for name, sub in comparison.by_dataset().items():
        total = sub.rms_k
        sigma = noise.get(name)
        if sigma is not None and total <= EXPLAINED_RATIO * sigma:
            continue
        parts = []
        for grouping in _groupings(sub, name):
            label, worst = max(grouping, key=lambda g: rms(g[1]))
            mean = float(np.mean(worst))
            parts.append(f"{label} (RMS {rms(worst):.3g} K, readings "
                         f"{'above' if mean > 0 else 'below'} the model by {abs(mean):.3g} K "
                         f"on average)")
        found.append((total, f"{name}: RMS {total:.3g} K"
                      + (f" ({total / sigma:.0f}× its noise)" if sigma else "")
                      + ", largest at " + " and at ".join(parts)))
    return [s for _, s in sorted(found, key=lambda x: -x[0])]
