"""The verdict rule: when an effect is decisively better than the model without it, how much
of the misfit it explains, whether a structured residual remains, and the reason given.

Criterion: ``BIC = Σ_d RSS_d / σ_d² + k ln N`` (noise-weighted χ² plus ``k ln N`` for ``k``
effect parameters over ``N`` points). An effect is decisive when it lowers the BIC by at least
:data:`MIN_BIC_DROP`, the pooled RMS by :data:`MIN_IMPROVEMENT` × and explains at least
:data:`MIN_EXPLAINED` of the misfit beyond the noise (:func:`explained_fraction`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from ..fit.measfit import LONGEST_TRANSIENT_S
from .residuals import EXPLAINED_RATIO, fmt_against, localise

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

    from .compare import Comparison

__all__ = ["AT_NOISE_CHI2", "DIRECT", "MAX_LEFT_CHI2", "MAX_STEPS", "MIN_BIC_DROP",
           "MIN_EXPLAINED", "MIN_IMPROVEMENT", "MIN_TOTAL_EXPLAINED", "RUNS_MIN", "RUNS_Z",
           "at_noise", "beyond_noise", "bic_drop", "can_be_decisive", "chi2", "criterion",
           "decisive", "early_excess", "explained_fraction", "far_left", "improvement",
           "partial_fit", "passes", "runs_z", "structured", "unexplained", "verdict_reason"]

#: An effect must lower the pooled RMS at least this many times ...
MIN_IMPROVEMENT = 1.15
#: ... lower the BIC by at least this much ...
MIN_BIC_DROP = 10.0
#: ... and explain at least this fraction of the misfit beyond the noise,
#: ``(χ²_before − χ²_after) / (χ²_before − N)``.
MIN_EXPLAINED = 0.4
#: Effects that leave a structured residual are named only when together they explain at
#: least this fraction of the baseline's misfit beyond the noise (else: not in the catalogue).
MIN_TOTAL_EXPLAINED = 0.97
#: The residual is at the noise when every data set's ``χ² / n`` is below this (plus its
#: statistical spread) and none has a structured residual (:func:`runs_z` below :data:`RUNS_Z`).
AT_NOISE_CHI2 = 1.5
#: Several effects that leave a structured residual whose noise-weighted ``χ²/N`` is above
#: this (an RMS above 3× the noise) are not named, nor any that leave a data set's structured
#: residual above it (:func:`unexplained`, :func:`far_left`).
MAX_LEFT_CHI2 = 9.0
#: Effects that a data set of their own measures directly (a TSP's calibration: the sensor
#: alone, no thermal model in it): their gain counts there too (:func:`improvement`).
DIRECT = {"tsp-nonlinearity": ("calibration",)}
#: Effects a diagnosis adds at most, one per step.
MAX_STEPS = 3
#: A data set's residual is structured when its runs test gives z below this ...
RUNS_Z = -3.0
#: ... which needs this many residuals (fewer: :func:`structured` judges their size alone).
RUNS_MIN = 8


def criterion(comparison: Comparison, noise: Mapping[str, float], k: int) -> float:
    return chi2(comparison, noise) + k * math.log(max(len(comparison.points), 2))


def chi2(comparison: Comparison, noise: Mapping[str, float]) -> float:
    with np.errstate(over="ignore", invalid="ignore"):  # a diverged candidate: inf
        return sum(float(np.sum(sub.residuals_k ** 2)) / noise[name] ** 2
                   for name, sub in comparison.by_dataset().items())


def explained_fraction(before: Comparison, after: Comparison,
                       noise: Mapping[str, float], within: Sequence[str] = ()) -> float:
    """Fraction of ``before``'s misfit beyond the noise that ``after`` removes,
    ``(χ²_before − χ²_after) / (χ²_before − N)`` with noise-weighted χ² (1 when ``before``
    is already at the noise and ``after`` is no worse). ``within``: data sets that measure
    the effect directly (:func:`improvement`); the larger of the overall fraction and theirs.

    >>> from spicethermal.analysis.compare import Comparison, ComparisonPoint
    >>> c = lambda r: Comparison(tuple(ComparisonPoint("x", {"t_s": i + 1.0}, x, 0.0)
    ...                                for i, x in enumerate(r)))
    >>> round(explained_fraction(c([3.0, -3.0]), c([1.0, 1.0]), {"x": 1.0}), 3)
    1.0
    >>> round(explained_fraction(c([3.0, -3.0]), c([2.0, 2.0]), {"x": 1.0}), 3)
    0.625
    """
    b, a = _own(before, within), _own(after, within)
    own = explained_fraction(b, a, noise) if b and a else -math.inf
    c0, c1 = chi2(before, noise), chi2(after, noise)
    excess = c0 - len(before.points)
    if excess <= 0:
        return max(own, 1.0 if c1 <= c0 else 0.0)
    return float(max(own, min(1.0, (c0 - c1) / excess)))


def runs_z(residuals: NDArray) -> float:
    """Wald–Wolfowitz runs test on the signs of ``residuals`` in data order: z of the number
    of runs (very negative: too few runs, a structured residual; about 0 for white noise;
    0 for fewer than :data:`RUNS_MIN` residuals or one sign only).

    >>> runs_z(np.array([1.0] * 10 + [-1.0] * 10)) < -3
    True
    >>> abs(runs_z(np.array([1.0, -1.0] * 10))) > 3
    True
    """
    r = np.asarray(residuals, dtype=float)
    r = r[r != 0]
    pos = int(np.sum(r > 0))
    neg = r.size - pos
    if r.size < RUNS_MIN or pos == 0 or neg == 0:
        return 0.0
    runs = 1 + int(np.sum(np.diff(np.sign(r)) != 0))
    n = r.size
    mu = 2.0 * pos * neg / n + 1
    var = (mu - 1) * (mu - 2) / (n - 1)
    return float((runs - mu) / math.sqrt(var)) if var > 0 else 0.0


def structured(comparison: Comparison, noise: Mapping[str, float]) -> list[str]:
    """Data sets whose residual is beyond their noise (RMS above :data:`EXPLAINED_RATIO` ×)
    and structured (:func:`runs_z` below :data:`RUNS_Z`), and those whose residual is beyond
    3× their noise (``χ²/n`` above :data:`MAX_LEFT_CHI2`) whatever its signs: such a misfit
    is no noise, and a runs test may not see it: it needs :data:`RUNS_MIN` readings, and more
    to have any power (of twelve, only two runs reach z = −3). A convection that switches,
    taken for an outer layer's coefficient, left a PWM grid of 18 readings at 7× its noise,
    below the model at 20 and 50 % duty and above it at 80 %: four runs, z = −2.85, "no
    structure". A PWM grid's noise comes from the sensor that reads the curves and the
    calibration (:func:`~spicethermal.analysis.residuals.noise_estimates`).

    >>> from spicethermal.analysis.compare import Comparison, ComparisonPoint
    >>> c = Comparison(tuple(ComparisonPoint(d, {"t_s": i + 1.0}, x, 0.0) for i, (d, x)
    ...                      in enumerate([("a", 1.0)] * 10 + [("a", -1.0)] * 10
    ...                                   + [("b", 4.0), ("b", -4.0)] * 3)))
    >>> structured(c, {"a": 0.1, "b": 1.0}), structured(c, {"a": 0.1, "b": 2.0})
    (['a', 'b'], ['a'])
    """
    out = []
    for name, sub in comparison.by_dataset().items():
        r = sub.residuals_k
        if _per_point(sub, noise[name]) > MAX_LEFT_CHI2 or (
                r.size >= RUNS_MIN and sub.rms_k > EXPLAINED_RATIO * noise[name]
                and runs_z(r) < RUNS_Z):
            out.append(name)
    return out


def _per_point(sub: Comparison, sigma: float) -> float:
    """One data set's noise-weighted ``χ² / n`` (``sub`` holds that data set only)."""
    return float(np.sum(sub.residuals_k ** 2)) / sigma ** 2 / max(len(sub.points), 1)


def at_noise(comparison: Comparison, noise: Mapping[str, float]) -> bool:
    """Every data set within its noise: ``χ²_d / n_d`` at most :data:`AT_NOISE_CHI2` plus
    three standard deviations of that ratio for white noise (``3 √(2/n_d)``: a small data
    set such as the calibration is judged on its own, not drowned in the curves' points),
    and no structured residual."""
    return not beyond_noise(comparison, noise) and not structured(comparison, noise)


def early_excess(comparison: Comparison, noise: Mapping[str, float]) -> float:
    """How far the cooling readings within an electrical transient's reach of the cut
    (:data:`~spicethermal.fit.measfit.LONGEST_TRANSIENT_S`) stand out of their noise: their
    noise-weighted χ² beyond their number, less three standard deviations of white noise's
    (``3 √(2n)``); 0 when they do not stand out. A misfit confined to a few readings, such as
    a ringing over the first 10 µs, is averaged away by a data set's ``χ²/n``
    (:func:`at_noise`): a ringing of −0.32 K on three curves of five readings a decade, 6× the
    noise in their first readings, left them at 1.6× the noise variance overall (seed 41's
    draw 023 of the random validation set).

    >>> from spicethermal.analysis.compare import Comparison, ComparisonPoint
    >>> c = lambda first: Comparison(tuple(
    ...     ComparisonPoint("cooling_1", {"t_s": 10.0 ** (k / 5 - 6)}, x, 0.0)
    ...     for k, x in enumerate(first + [0.05, -0.05] * 20)))
    >>> early_excess(c([0.3, -0.3, 0.3]), {"cooling_1": 0.05}) > 50
    True
    >>> early_excess(c([0.05, -0.05, 0.05]), {"cooling_1": 0.05})
    0.0
    """
    z2, n = 0.0, 0
    for name, sub in comparison.by_dataset().items():
        if not name.startswith("cooling"):
            continue
        early = np.array([p.at["t_s"] < LONGEST_TRANSIENT_S for p in sub.points])
        z2 += float(np.sum(sub.residuals_k[early] ** 2)) / noise[name] ** 2
        n += int(np.sum(early))
    return max(0.0, z2 - n - 3 * math.sqrt(2 * n)) if n else 0.0


def beyond_noise(comparison: Comparison, noise: Mapping[str, float]) -> dict[str, float]:
    """The data sets whose ``χ²_d / n_d`` is above :data:`AT_NOISE_CHI2` plus three standard
    deviations of that ratio for white noise (``3 √(2/n_d)``), with that ratio.

    >>> from spicethermal.analysis.compare import Comparison, ComparisonPoint
    >>> c = Comparison(tuple(ComparisonPoint(d, {"t_s": i + 1.0}, x, 0.0) for i, (d, x)
    ...                      in enumerate([("a", 1.0), ("a", -1.0)] * 10 + [("b", 3.0)] * 8)))
    >>> {k: round(v, 1) for k, v in beyond_noise(c, {"a": 1.0, "b": 1.0}).items()}
    {'b': 9.0}
    """
    over = {}
    for name, sub in comparison.by_dataset().items():
        ratio = _per_point(sub, noise[name])
        if ratio > AT_NOISE_CHI2 + 3 * math.sqrt(2 / max(len(sub.points), 1)):
            over[name] = ratio
    return over


def far_left(final: Comparison, noise: Mapping[str, float]) -> dict[str, float]:
    """The data sets whose structured residual stays above 3× their noise (``χ²_d/n_d``
    above :data:`MAX_LEFT_CHI2`), with that ratio: whatever the effects explain in total,
    physics they do not hold is at work there (a convection that switches at 34 °C passes
    for an outer layer's temperature coefficient in the cooling curves, 99 % of the misfit,
    and leaves the PWM readings at 5× their noise)."""
    over = beyond_noise(final, noise)
    return {name: over[name] for name in structured(final, noise)
            if over.get(name, 0.0) > MAX_LEFT_CHI2}


def unexplained(final: Comparison, noise: Mapping[str, float], n_steps: int) -> bool:
    """Whether the effects leave a misfit too large to call them the diagnosis (the caller
    asks only when the residual is structured): a data set whose structured residual is
    above 3× its noise (:func:`far_left`); after two, a noise-weighted ``χ²/N`` above
    :data:`MAX_LEFT_CHI2`; after three, any (a structured residual that three catalogued
    effects leave is physics they only approximate together: a convection that switches
    passes for a temperature coefficient, a sample window and a latent heat)."""
    if n_steps >= MAX_STEPS:
        return True
    if n_steps > 1 and chi2(final, noise) / max(len(final.points), 1) > MAX_LEFT_CHI2:
        return True
    return bool(far_left(final, noise))


def partial_fit(base: Comparison, final: Comparison, noise: Mapping[str, float],
                n_steps: int) -> bool:
    """Whether ``n_steps`` effects that take the misfit of ``base`` to ``final`` explain only
    part of it, so that they are no diagnosis: a structured residual remains
    (:func:`structured`), and they explain less than :data:`MIN_TOTAL_EXPLAINED` of the misfit
    beyond the noise or leave too much of it (:func:`unexplained`)."""
    return bool(structured(final, noise)) and (
        explained_fraction(base, final, noise) < MIN_TOTAL_EXPLAINED
        or unexplained(final, noise, n_steps))


def can_be_decisive(comparison: Comparison, noise: Mapping[str, float],
                    datasets: Sequence[str], n_params: int) -> bool:
    """Whether an effect that acts only on ``datasets`` could lower the BIC of ``comparison``
    by :data:`MIN_BIC_DROP` with ``n_params`` parameters: their χ² must exceed what white noise
    can leave (``n − 3 √(2n)`` for their ``n`` points) by at least that drop plus
    ``n_params ln N`` (a cheap test that prunes candidates before any fit).

    >>> from spicethermal.analysis.compare import Comparison, ComparisonPoint
    >>> c = Comparison(tuple(ComparisonPoint("pwm", {"freq_hz": 1e3, "duty": 0.5}, x, 0.0)
    ...                      for x in (1.0, -1.0) * 20))
    >>> can_be_decisive(c, {"pwm": 2.0}, ["pwm"], 1), can_be_decisive(c, {"pwm": 0.5}, ["pwm"], 1)
    (False, True)
    """
    sets = comparison.by_dataset()
    subs = [sets[d] for d in datasets if d in sets]
    n = sum(len(sub.points) for sub in subs)
    if not n:
        return False
    excess = sum(float(np.sum(sub.residuals_k ** 2)) / noise[sub.points[0].dataset] ** 2
                 for sub in subs) - (n - 3 * math.sqrt(2 * n))
    return excess >= MIN_BIC_DROP + n_params * math.log(max(len(comparison.points), 2))


def improvement(before: Comparison, after: Comparison,
                noise: Mapping[str, float] | None = None, within: Sequence[str] = ()) -> float:
    """How many times ``after`` lowers the misfit of ``before``: the pooled RMS ratio, or
    (given ``noise``) the larger of that and the noise-weighted ratio
    ``√(χ²_before / χ²_after)``. The pooled RMS weighs every point alike, so an effect seen in
    one small data set only (a TSP's bow in the calibration, once another effect has taken up
    the curves) barely moves it; in units of each data set's noise it shows. ``within``:
    data sets that measure the effect directly (a TSP's own calibration), whose noise-weighted
    ratio counts too: beside a few hundred curve readings a calibration of twelve left at
    12× its noise variance by the curves' effect moved the overall ratio only 1.1×.

    >>> from spicethermal.analysis.compare import Comparison, ComparisonPoint
    >>> c = lambda r, d: Comparison(tuple(ComparisonPoint(n, {"t_s": i + 1.0}, x, 0.0)
    ...                                   for i, (x, n) in enumerate(zip(r, d))))
    >>> sets = ["x"] * 18 + ["y"] * 2
    >>> before, after = c([0.5] * 18 + [0.3, -0.3], sets), c([0.5] * 18 + [0.01, -0.01], sets)
    >>> noise = {"x": 1.0, "y": 0.01}
    >>> round(improvement(before, after), 2), round(improvement(before, after, noise), 1)
    (1.02, 16.7)
    >>> noise = {"x": 0.1, "y": 0.05}
    >>> round(improvement(before, after, noise), 2), round(improvement(before, after, noise,
    ...                                                                ["y"]), 1)
    (1.08, 30.0)
    """
    pooled = before.rms_k / after.rms_k if after.rms_k > 0 else math.inf
    if noise is None:
        return pooled
    c0, c1 = chi2(before, noise), chi2(after, noise)
    weighted = math.sqrt(c0 / c1) if c1 > 0 else math.inf
    b, a = _own(before, within), _own(after, within)
    if b and a:
        own0, own1 = chi2(b, noise), chi2(a, noise)
        weighted = max(weighted, math.sqrt(own0 / own1) if own1 > 0 else math.inf)
    return max(pooled, weighted)


def _own(comparison: Comparison, within: Sequence[str]) -> Comparison | None:
    """The points of ``comparison`` in the data sets ``within`` (None when there are none)."""
    points = tuple(p for p in comparison.points if p.dataset in within)
    return type(comparison)(points, comparison.engine) if points else None


def passes(bic_drop: float, gain: float, explained: float,
           min_improvement: float = MIN_IMPROVEMENT, min_explained: float = MIN_EXPLAINED) -> bool:
    """The decision rule: a BIC drop of :data:`MIN_BIC_DROP`, an improvement of
    ``min_improvement`` and an explained fraction of ``min_explained``.

    >>> passes(12.0, 1.2, 0.5), passes(12.0, 1.1, 0.5)
    (True, False)
    """
    return bic_drop >= MIN_BIC_DROP and gain >= min_improvement and explained >= min_explained


def decisive(cand: Any, bic_before: float, min_improvement: float = MIN_IMPROVEMENT,
             min_explained: float = MIN_EXPLAINED) -> bool:
    """True when candidate ``cand`` is decisively better than a model of BIC ``bic_before``
    (:func:`passes`, on its ``gain``, :func:`improvement` with the noise, when it has one, else
    its ``improvement``)."""
    return passes(bic_before - cand.bic, getattr(cand, "gain", cand.improvement),
                  cand.explained, min_improvement, min_explained)


def verdict_reason(base: Comparison, final: Comparison, noise: Mapping[str, float],
                   first: Sequence[Any], steps: Sequence[Any],
                   skipped: Mapping[str, str]) -> str:
    """The verdict's reason: what was added and why, what is left, and where."""
    if not steps and at_noise(base, noise):
        return (f"the model fits every data set at its noise (RMS {base.rms_k:.3g} K, "
                f"{chi2(base, noise) / max(len(base.points), 1):.2f}× the noise variance, no "
                f"structured residual): no effect is missing")
    parts = []
    prev = base
    for s in steps:
        c = s.chosen
        # an effect measured in a small data set of its own (a TSP's calibration) may lower
        # the misfit in units of the noise while the pooled RMS barely moves or rises
        # (or barely moves: then the gain in units of the noise that made it decisive is given
        # too, and where the explained share is measured when it is its own data set's:
        # a cubic bow lowered the RMS 1.07× and "explained 100 %", of its calibration)
        rms = f"{prev.rms_k:.3g} → {c.rms_k:.3g} K"
        gain = getattr(c, "gain", c.improvement)
        if c.improvement < 1:
            lowers = f"lowers the misfit {gain:.3g}× in units of the noise (RMS {rms})"
        elif c.improvement < MIN_IMPROVEMENT <= gain:
            lowers = (f"lowers the RMS {c.improvement:.3g}× ({rms}; {gain:.3g}× in units of "
                      f"the noise)")
        else:
            lowers = f"lowers the RMS {c.improvement:.3g}× ({rms})"
        within = DIRECT.get(c.effect.name, ())
        overall = explained_fraction(prev, c.comparison, noise)
        where = (f" in its {', '.join(within)} ({100 * max(overall, 0):.0f} % overall)"
                 if within and f"{100 * c.explained:.0f}" != f"{100 * max(overall, 0):.0f}"
                 else "")
        parts.append(f"{c.effect.name} ({c.effect.form}) {lowers} and explains "
                     f"{100 * c.explained:.0f} % of the misfit beyond the noise{where}")
        prev = c.comparison
    left = structured(final, noise)
    if steps and not left:
        over = beyond_noise(final, noise)
        tail = ("the residual is at the noise" if not over else
                "what is left has no structure, though " + ", ".join(
                    f"{name} stays at {ratio:.3g}× its noise variance"
                    for name, ratio in over.items()))
        return "; then ".join(parts) + f"; {tail}"
    if not steps:
        if first:
            c = first[0]
            why = (f"the best candidate, {c.effect.name} ({c.effect.form}), lowers the RMS only "
                   f"{fmt_against(c.improvement, MIN_IMPROVEMENT)}× "
                   f"({fmt_against(c.gain, MIN_IMPROVEMENT)}× weighted by the noise) and explains "
                   f"{fmt_against(100 * max(c.explained, 0), 100 * MIN_EXPLAINED, 2)} % of the "
                   f"misfit (needs {MIN_IMPROVEMENT:g}×, {100 * MIN_EXPLAINED:.0f} % and a BIC "
                   f"drop of {MIN_BIC_DROP:g}; it gives "
                   f"{fmt_against(bic_drop(c, base, noise), MIN_BIC_DROP, 2)})")
        else:
            why = "no candidate effect could be fitted"
        located = localise(final, noise) or localise(final)
        return (f"no catalogued effect explains the misfit: {why}; not in the catalogue: the "
                f"error sits in {'; and in '.join(located[:2])}")
    located = localise(final, noise) or localise(final)
    return ("; then ".join(parts) + "; a structured residual remains that no catalogued effect "
            f"explains (not in the catalogue): "
            f"{'; and '.join(located[:2]) if located else ', '.join(left)}")


def bic_drop(cand: Any, base: Comparison, noise: Mapping[str, float]) -> float:
    """BIC of ``base`` (no extra parameter) minus the candidate's."""
    return criterion(base, noise, 0) - cand.bic
