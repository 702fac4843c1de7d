"""Does a named device effect's physics hold on the data, beyond the numbers it lowers?

A device effect (a resistance that follows temperature, a latent heat) changes the cooling
*dynamics*: after the cut the network relaxes through temperature-dependent elements. An
error in the heating power (a heater whose power sags as it warms, a power meter's gain, a
current that drifts with the supply) changes only the *amplitude* of each cooling curve:
with the power off the network is linear, so every curve is the linear Zth shape scaled by
the power actually dissipated before the cut.

:func:`amplitude_only` fits that alternative: the linear ladder jointly to every cooling curve
with one free power scale per curve (the reference curve's held at 1). When it fits the
cooling curves at the noise and decisively better than every form of the device effect does
(its BIC lower by :data:`~spicethermal.analysis.verdict.MIN_BIC_DROP`), the effect only mimics an
amplitude change that its own dynamics contradict: the physics at work is not the catalogued
one (:func:`device_effect_contradicted`). A coefficient of the junction form scales the whole
steady rise as a power other than the recorded one does; when its dynamics are within the
noise, both fit alike and the data cannot tell them apart: it is not named either. When the
amplitudes alone leave a misfit, the test says nothing (an effect of another form may be at
work).

A setup that changed between the curves is the other linear alternative
(:func:`outer_only`): a device remounted, a thermal interface reseated or a heatsink clamped
anew changes the outermost layer's resistance from one curve to the next, and each curve is
then the response of a linear ladder, the same but for that layer. A resistance that follows
temperature changes as the device cools *within* each curve; a contact that changed between
the curves does not. When the linear ladder with the outer resistance free per curve fits the
cooling curves at the noise and decisively better than every form of the effect, the effect
only mimics a change of setup.

An electrical transient is an error of the first readings after the cut: those readings
(within its fitted span) must stand out of their curves, their noise-weighted ``χ²`` per point
at least :data:`EARLY_FACTOR` × the noise's and × the rest of the curves'
(:func:`transient_hidden`), in the model it would extend or in the ladder fitted with it (a
transient proportional to the power cut off passes for a fast stage of the first). A
transient fitted to readings that do not stand out only reshapes a misfit spread over the whole
curve (an approximate form of another effect) and is not named.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..core.errors import DataFormatError, FitError, SimulationError
from ..core.ladder import Cauer, Foster
from ..effects import DEVICE, Effect
from ..effects.temperature_coefficient import LOCAL_FORMS
from ..fit.effectfit import NUMERICAL_ERRORS, BundleData, as_foster, robust_lsq, transient_spans
from .verdict import AT_NOISE_CHI2, MIN_BIC_DROP

if TYPE_CHECKING:  # pragma: no cover
    from .compare import Comparison

__all__ = ["EARLY_FACTOR", "Alternative", "alternatives", "amplitude_only",
           "device_effect_contradicted", "outer_only", "transient_hidden"]

#: The readings within an electrical transient's span must show a noise-weighted χ² per point
#: at least this many times the noise's (1) and the rest of the curves'.
EARLY_FACTOR = 3.0


def _kept(data: BundleData) -> dict[str, np.ndarray]:
    """Per cooling curve, the points outside its detected electrical transient."""
    spans = transient_spans(data)
    return {c.name: c.t_s >= spans.get(c.name, 0.0) for c in data.cooling}


def amplitude_only(data: BundleData, ladder: Foster | Cauer) -> tuple[float, int]:
    """Noise-weighted χ² of the cooling curves (outside their transients) under the linear
    ladder refitted jointly with a free power scale per curve, and the number of scales.

    Parameters
    ----------
    data : BundleData
        The bundle's arrays, with the noise scales set.
    ladder : Foster or Cauer
        Start of the ladder's fit.

    Returns
    -------
    tuple of (float, int)
        χ² and the number of free scales (cooling curves − 1).

    Examples
    --------
    >>> from spicethermal.io.bundle import Bundle, CoolingTable
    >>> lad = Foster.from_tau([10.0, 30.0], [0.01, 1.0])
    >>> t = np.geomspace(1e-3, 10, 40)
    >>> curves = [CoolingTable(t, p, tj_c=25 + p * s * lad.cooling(t))
    ...           for p, s in ((1.0, 1.0), (2.0, 0.9))]  # the hot curve's power sagged 10 %
    >>> data = BundleData.from_bundle(Bundle(ambient_c=25.0, cooling=curves))
    >>> chi2, k = amplitude_only(data, Foster.from_tau([12.0, 25.0], [0.02, 0.8]))
    >>> chi2 < 1e-8, k
    (True, 1)
    """
    f = as_foster(ladder)
    m = f.order
    ref = data.reference_curve
    kept = _kept(data)
    rest = [c for c in data.cooling if c is not ref]

    def fun(x: np.ndarray) -> np.ndarray:
        lad = Foster.from_tau(np.exp(x[:m]), np.exp(x[m:2 * m]))
        scales = dict(zip((c.name for c in rest), np.exp(x[2 * m:]), strict=True))
        parts = []
        for c in data.cooling:
            keep = kept[c.name]
            model = c.tref_c[keep] + scales.get(c.name, 1.0) * c.power_w * lad.cooling(
                c.t_s[keep])
            parts.append((model - c.tj_c[keep]) / data.scale(c.name))
        return np.concatenate(parts)

    x0 = np.concatenate([np.log(f.r), np.log(f.tau), np.zeros(len(rest))])
    big = np.full(x0.size, np.inf)
    res = robust_lsq(fun, x0, -big, big)
    return 2.0 * float(res.cost), len(rest)


def outer_only(data: BundleData, ladder: Foster | Cauer) -> tuple[float, int, dict[str, float]]:
    """Noise-weighted χ² of the cooling curves (outside their transients) under the linear
    ladder, refitted jointly in its Cauer form, with the outermost layer's resistance free per
    curve (the reference curve's held); the number of free resistances; and each other
    curve's change of that resistance (K/W).

    Parameters
    ----------
    data : BundleData
        The bundle's arrays, with the noise scales set.
    ladder : Foster or Cauer
        Start of the ladder's fit.

    Returns
    -------
    tuple of (float, int, dict)
        χ², the number of free resistances (cooling curves − 1) and, per other curve, the
        change of the outer resistance.

    Examples
    --------
    >>> from spicethermal.io.bundle import Bundle, CoolingTable
    >>> lad = Cauer([10.0, 30.0], [1e-4, 0.03])
    >>> moved = Cauer([10.0, 35.0], [1e-4, 0.03])  # remounted: the contact gained 5 K/W
    >>> t = np.geomspace(1e-3, 10, 40)
    >>> curves = [CoolingTable(t, p, tj_c=25 + p * c.cooling(t))
    ...           for p, c in ((1.0, lad), (2.0, moved))]
    >>> data = BundleData.from_bundle(Bundle(ambient_c=25.0, cooling=curves))
    >>> chi2, k, change = outer_only(data, Cauer([12.0, 25.0], [2e-4, 0.02]))
    >>> chi2 < 1e-8, k, round(change["cooling_2"], 3)
    (True, 1, 5.0)
    """
    start = ladder if isinstance(ladder, Cauer) else ladder.to_cauer()
    m = start.order
    ref = data.reference_curve
    kept = _kept(data)
    rest = [c.name for c in data.cooling if c is not ref]

    def curves_of(x: np.ndarray) -> dict[str, Cauer]:
        r, c = np.exp(x[:m]), np.exp(x[m:2 * m])
        out = {ref.name: Cauer(r, c)}
        for name, g in zip(rest, np.exp(x[2 * m:]), strict=True):
            out[name] = Cauer(np.concatenate([r[:-1], [r[-1] * g]]), c)
        return out

    def fun(x: np.ndarray) -> np.ndarray:
        ladders = curves_of(x)
        parts = []
        for c in data.cooling:
            keep = kept[c.name]
            model = c.tref_c[keep] + c.power_w * ladders[c.name].cooling(c.t_s[keep])
            parts.append((model - c.tj_c[keep]) / data.scale(c.name))
        return np.concatenate(parts)

    full = start.with_capacitances()
    x0 = np.concatenate([np.log(full.r), np.log(full.c), np.zeros(len(rest))])
    big = np.full(x0.size, np.inf)
    res = robust_lsq(fun, x0, -big, big)
    ladders = curves_of(np.asarray(res.x))
    base = ladders[ref.name].r[-1]
    return 2.0 * float(res.cost), len(rest), {name: ladders[name].r[-1] - base
                                               for name in rest}


@dataclass(frozen=True)
class Alternative:
    """A linear explanation of the cooling curves that no device effect is: its noise-weighted
    χ² (outside the transients), its number of free parameters beyond the ladder, and what it
    says (the verdict's words)."""

    chi2: float
    n_params: int
    what: str
    #: Whether a device effect acts on the very element this alternative changes between the
    #: curves (when it fits them only as closely, the data cannot tell the two apart) ...
    rivals: Callable[[Effect], bool] = lambda _effect: False
    #: ... and what the data then cannot tell apart (the verdict's words).
    alike: str = ""


def outer_layers(effect: Effect) -> bool:
    """Whether ``effect`` is a temperature coefficient of the outer layers only (a local form
    with ``first_layer`` ≥ 1): the layers whose resistance a remount or an airflow changes."""
    return effect.name == "temperature-coefficient" and effect.form in LOCAL_FORMS and \
        effect.params.get("first_layer", 0.0) >= 1


def whole_path(effect: Effect) -> bool:
    """Whether ``effect`` is a temperature coefficient of the junction form: every layer's
    resistance scaled by one law of the junction temperature, which before the cut scales the
    whole steady rise as a heating power other than the recorded one does (only its change
    while the device cools tells them apart)."""
    return effect.name == "temperature-coefficient" and effect.form == "junction"


def alternatives(data: BundleData, ladder: Foster | Cauer) -> list[Alternative]:
    """The linear alternatives to a device effect fitted to ``data`` from ``ladder``: a power
    per curve (:func:`amplitude_only`) and an outer resistance per curve (:func:`outer_only`).
    An alternative whose fit fails numerically is left out."""
    out = []
    try:
        chi2, k = amplitude_only(data, ladder)
        out.append(Alternative(chi2, k, "the linear ladder's shape scaled per curve, at the "
                                        "noise (a power that is not the recorded one",
                               whole_path, "a resistance that follows the junction temperature "
                                           "from a heating power other than the recorded one "
                                           "(a heater whose resistance, or a diode whose "
                                           "forward voltage, changes as it warms: measure the "
                                           "power at the cut)"))
    except (FitError, SimulationError, DataFormatError, *NUMERICAL_ERRORS):
        pass
    try:
        chi2, k, change = outer_only(data, ladder)
        moved = ", ".join(f"{name} {dr:+.3g} K/W" for name, dr in change.items())
        out.append(Alternative(chi2, k, f"the linear ladder with its outermost layer's "
                                        f"resistance changed between curves ({moved}), at the "
                                        f"noise (a contact or mounting that changed between the "
                                        f"measurements",
                               outer_layers, "that layer's temperature dependence from a "
                                             "change of setup between the curves"))
    except (FitError, SimulationError, DataFormatError, *NUMERICAL_ERRORS):
        pass
    return out


def device_effect_contradicted(data: BundleData, ladder: Foster | Cauer, effect: Effect,
                               n_params: int, comparisons: Sequence[Comparison],
                               linear: Sequence[Alternative] | None = None) -> str:
    """Why device effect ``effect`` is refused by the cooling dynamics ("" when it is not, or
    when the test does not apply: a measurement effect, fewer than two cooling curves).

    Refused when a linear alternative (:func:`alternatives`: a power per curve, an outer
    resistance per curve) fits the cooling curves at the noise (χ²/n within the white-noise
    bound of :data:`~spicethermal.analysis.verdict.AT_NOISE_CHI2`) and

    * decisively better than every form of the effect as fitted, even one switched off for
      the whole bundle (BIC lower by :data:`~spicethermal.analysis.verdict.MIN_BIC_DROP`): the
      effect only mimics what the alternative does, and its own dynamics contradict it; or
    * no more than that margin worse, when it changes the effect's own element between the
      curves (:attr:`Alternative.rivals`): the cooling curves cannot tell the two apart, and
      the effect's name would rest on the amplitudes alone, which the alternative explains as
      well. A change of setup rivals an outer layer's coefficient (a convection that switches
      at 33 °C was named a coefficient this way); a power other than the recorded one rivals a
      junction coefficient, which before the cut scales the whole steady rise as that power
      does, every later data set alike (a heater whose power falls 0.1 to 0.3 %/K of its own
      temperature was named a coefficient this way, its every data set at the noise).

    Parameters
    ----------
    data : BundleData
        The bundle's arrays, with the noise scales set.
    ladder : Foster or Cauer
        The ladder of the model the effect extends (start of the alternatives' fits).
    effect : Effect
        The effect (its best form), for the sentence.
    n_params : int
        Its number of fitted parameters.
    comparisons : sequence of Comparison
        The model with each form of the effect against the bundle.
    linear : sequence of Alternative, optional
        :func:`alternatives` of ``data`` if already computed.

    Returns
    -------
    str
        The reason (the alternative that beats the effect by most, else the rival it ties
        with), or "".
    """
    if effect.kind != DEVICE or len(data.cooling) < 2 or not comparisons:
        return ""
    kept = _kept(data)
    n = sum(int(np.sum(k)) for k in kept.values())

    def cooling_chi2(comparison: Comparison) -> float:
        by_set = comparison.by_dataset()
        return sum(float(np.sum(by_set[c.name].residuals_k[kept[c.name]] ** 2))
                   / data.scale(c.name) ** 2 for c in data.cooling)

    chi2_effect = min(cooling_chi2(c) for c in comparisons)
    log_n = math.log(max(n, 2))
    bound = AT_NOISE_CHI2 + 3 * math.sqrt(2 / max(n, 1))
    found = [((chi2_effect + n_params * log_n) - (alt.chi2 + alt.n_params * log_n), alt)
             for alt in (linear if linear is not None else alternatives(data, ladder))
             if alt.chi2 / max(n, 1) <= bound]
    beaten = [(gap, alt) for gap, alt in found if gap >= MIN_BIC_DROP]
    if beaten:
        gap, alt = max(beaten, key=lambda x: x[0])
        return (f"{effect.name} would change the cooling dynamics, but the cooling curves are "
                f"{alt.what}; χ² {alt.chi2:.0f} on {n} points against {chi2_effect:.0f} with "
                f"the effect: BIC {gap:.0f} lower)")
    # an alternative that changes the effect's own element between the curves, as close:
    # the data cannot tell that element's temperature dependence from a change between them
    tied = [(gap, alt) for gap, alt in found if gap > -MIN_BIC_DROP and alt.rivals(effect)]
    if not tied:
        return ""
    gap, alt = max(tied, key=lambda x: x[0])
    layers = (f", layers {effect.params['first_layer']:.0f} outwards"
              if effect.form in LOCAL_FORMS else "")
    return (f"{effect.name} ({effect.form}{layers}) fits the cooling curves no more closely "
            f"than {alt.what}; χ² {alt.chi2:.0f} on {n} points against {chi2_effect:.0f} "
            f"with the effect: BIC within {MIN_BIC_DROP:g}): the data cannot tell {alt.alike}")


def transient_hidden(before: Comparison, effect: Effect, noise: Mapping[str, float]) -> str:
    """Why the electrical transient ``effect`` is not seen in the first readings of the model
    it would extend (``before``) ("" when it is): within its span (``masked_s`` after the
    cut) the cooling readings' noise-weighted ``χ²`` per point is below :data:`EARLY_FACTOR` ×
    the larger of 1 and the rest of the curves' (module docstring).

    >>> from spicethermal.analysis.compare import Comparison, ComparisonPoint
    >>> def cmp(res):
    ...     return Comparison(tuple(ComparisonPoint("cooling_1", {"t_s": 10.0 ** (k - 6)}, r,
    ...                                             0.0) for k, r in enumerate(res)))
    >>> tr = Effect.create("electrical-transient", "fixed", amplitude_k=-1.0, masked_s=2e-5)
    >>> transient_hidden(cmp([-1.0, -0.4, 0.02, -0.01, 0.01]), tr, {"cooling_1": 0.02})
    ''
    >>> transient_hidden(cmp([-0.03, 0.02, 0.04, -0.03, 0.03]), tr, {"cooling_1": 0.02})
    ... # doctest: +NORMALIZE_WHITESPACE
    'the readings within 20 µs of the cut do not stand out of their curves (χ²/n 1.62 against
    2.83 after it)'
    """
    span = float(effect.params["masked_s"])
    early = late = 0.0
    n_early = n_late = 0
    for name, sub in before.by_dataset().items():
        if not name.startswith("cooling"):
            continue
        t = np.array([p.at["t_s"] for p in sub.points])
        z2 = sub.residuals_k ** 2 / noise[name] ** 2
        early += float(np.sum(z2[t < span]))
        late += float(np.sum(z2[t >= span]))
        n_early += int(np.sum(t < span))
        n_late += int(np.sum(t >= span))
    if not n_early:
        return f"no reading within {span * 1e6:.3g} µs of the cut"
    per_early, per_late = early / n_early, late / max(n_late, 1)
    if per_early >= EARLY_FACTOR * max(1.0, per_late):
        return ""
    return (f"the readings within {span * 1e6:.3g} µs of the cut do not stand out of their "
            f"curves (χ²/n {per_early:.3g} against {per_late:.3g} after it)")
