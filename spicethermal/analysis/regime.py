"""A change of regime that passes for a temperature coefficient.

A convection that changes regime (natural to forced, a fan that starts, the onset of boiling)
changes an outer layer's resistance over a few kelvin around one temperature and leaves it
constant either side. Taken for a temperature coefficient, a smooth law of every temperature
the layer goes through, it fits the cooling curves and leaves the readings its smooth law
cannot bend to, the PWM grid's at the hottest duty (seed 67's draw 011 of the random
validation set: a convection switch at 39.6 °C, the coefficient of the outer layers explains
100 % of the misfit and leaves the PWM readings at 3.6× their noise variance).

:func:`regime_switch` fits the rival law, the coefficient's layers (the outermost one for the
junction form) stepping by a fraction around a temperature over a width
(:data:`~spicethermal.effects.temperature_coefficient.SWITCH`), on every data set: first with
the coefficient's ladder held, then with the ladder refitted from the best of those starts
(the coefficient then refitted with its ladder for as much work, so that a refit is no
advantage of the step's). When its criterion is lower than the coefficient's by
:data:`~spicethermal.analysis.verdict.MIN_BIC_DROP` (and, when later steps added effects, not
that much above their whole model's), the coefficient is contradicted: the physics at work is a
change of regime, which the catalogue does not hold. A real coefficient follows its smooth law;
a step fits it far worse (session 21, on four convection switches the coefficient was named
for, BIC 15 to 58 lower with the step; on seven real coefficients, of every form and strength,
34 to 41 569 higher, with the ladder held).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from ..core.errors import FitError, SimulationError
from ..core.ladder import Cauer, Foster
from ..effects.temperature_coefficient import LOCAL_FORMS, SWITCH, size
from ..fit.budget import TimeLimitError, bounded
from ..fit.effectfit import NUMERICAL_ERRORS, BundleData, joint_fit
from ..fit.tcforward import as_cauer, local_steady_nodes
from .compare import Comparison
from .diagnosis import Step
from .refits import joint_refit
from .residuals import comparison_of
from .verdict import MAX_LEFT_CHI2, MIN_BIC_DROP, beyond_noise, chi2, criterion

__all__ = ["REGIME_BUDGET_S", "REGIME_NFEV", "Switch", "regime_switch"]

#: Work (s, :mod:`~spicethermal.fit.budget`) allowed to each fit of the check (each start of
#: the rival law with the ladder held, its refit with the ladder, the coefficient's refit) ...
REGIME_BUDGET_S = 6.0
#: ... and its evaluations at most (three parameters, the ladder held).
REGIME_NFEV = 40
#: Where the step starts, as fractions of the way from the coldest reference temperature to
#: the layers' hottest mean temperature.
STARTS = (0.3, 0.6)


@dataclass(frozen=True)
class Switch:
    """The rival law in the place of a ``temperature-coefficient`` effect in the forward
    models (a local form's integration reads its name, form and parameters only); it is no
    effect of the catalogue, and no model holds it."""

    params: Mapping[str, float]
    name: str = "temperature-coefficient"
    form: str = SWITCH

    @classmethod
    def of(cls, drop: float, t_switch_c: float, width_k: float, first: int, last: int,
           t0_c: float) -> Switch:
        """The step of layers ``first`` to ``last``."""
        return cls({"drop": drop, "t_switch_c": t_switch_c, "width_k": width_k,
                    "first_layer": float(first), "last_layer": float(last), "t0_c": t0_c,
                    "alpha_per_k": 0.0, "exponent": 0.0, "c_slope_per_k": 0.0})


def regime_switch(data: BundleData, steps: Sequence[Step], noise: Mapping[str, float]) -> str:
    """Why the first of a diagnosis's ``steps``, a temperature coefficient, is a change of
    regime rather than a coefficient, or "" (module docstring). Asked only of a coefficient
    that leaves a data set beyond its noise (one at the noise leaves a step nothing to gain)
    and whose diagnosis's model, with every effect the steps added, leaves the whole bundle
    within 3× its noise (``χ²/N`` at most
    :data:`~spicethermal.analysis.verdict.MAX_LEFT_CHI2`): with another effect missing, a
    bend of the law takes up that effect's signature too (a TSP's bow beside a junction
    coefficient, χ²/N 99 with the coefficient: a step of 45 % over 12 K fitted it 509 lower,
    the validation set's pair temperature-coefficient+tsp-nonlinearity; found next, the bow
    brings the model to χ²/N 5.4, which the step alone does not approach). The step stands in
    for the first effect only: on top of others, held as fitted without it, their misfit is
    a bend's to take up too (seed 67's draw 021 of the random validation set, an outer
    coefficient after an averaged window, lost to a step 34 lower). When later steps added
    effects, the step alone must also fit within
    :data:`~spicethermal.analysis.verdict.MIN_BIC_DROP` of their whole model: effects that
    only mop up what the smooth law leaves of a step are not decisive on top of the step
    (seed 5's draw 023, a convection switch at 40.9 °C named the coefficient and a TSP's bow,
    which the step alone fits 7 lower; a real coefficient beside a real second effect: the
    step alone, the ladder held, 17 to 27 877 higher than the two, on six such pairs of the
    validation sets, and none of them lost with the ladder refitted)."""
    c = steps[0].chosen
    ladder, effect, comparison = c.ladder, c.effect, c.comparison
    whole = steps[-1].chosen.comparison
    if effect.name != "temperature-coefficient" or not data.cooling or \
            not beyond_noise(comparison, noise) or \
            chi2(whole, noise) > MAX_LEFT_CHI2 * len(whole.points):
        return ""
    cauer = as_cauer(ladder)
    n = cauer.order
    p = effect.params
    if effect.form in LOCAL_FORMS:
        first, last = int(p["first_layer"]), int(min(p["last_layer"], n - 1))
    else:
        first = last = n - 1
    t0 = float(p["t0_c"])
    hot = max(data.cooling, key=lambda c: c.power_w)
    try:
        rise = local_steady_nodes(cauer, Switch.of(0.0, t0, 1.0, first, last, t0),
                                  hot.tref_steady_c, hot.power_w)
    except (SimulationError, *NUMERICAL_ERRORS):
        return ""
    ends = hot.tref_steady_c + np.append(rise, 0.0)
    t_lo = min(c.tref_steady_c for c in data.cooling)
    t_hi = float(0.5 * (ends[first] + ends[first + 1]))
    if not t_hi > t_lo:
        return ""
    # R falls above the step where the coefficient's slope is negative
    sign = 1.0 if size(effect) <= 0 else -1.0
    names = list(data.datasets)

    def build(x: np.ndarray) -> list:
        return [Switch.of(float(x[0]), float(x[1]), float(x[2]), first, last, t0)]

    lo, hi = [-0.9, t_lo - 5.0, 0.1], [0.9, t_hi + 10.0, 20.0]
    Fit = tuple[float, Comparison, Foster, list]

    def attempt(start: Foster | Cauer, refit: bool, x0: list[float]) -> Fit | None:
        try:
            got = bounded(lambda: joint_fit(data, names, start, refit, x0, lo, hi, build,
                                            tol=1e-6, max_nfev=None if refit else REGIME_NFEV),
                          REGIME_BUDGET_S, None)
            if got is None:
                return None
            cmp = comparison_of(data, got[0], got[1])
        except (FitError, SimulationError, TimeLimitError, *NUMERICAL_ERRORS):
            return None
        bic = criterion(cmp, noise, 3)
        return (bic, cmp, got[0], got[1]) if math.isfinite(bic) else None

    fits = [attempt(ladder, False, [0.3 * sign, t_lo + q * (t_hi - t_lo), 1.5]) for q in STARTS]
    held = min((f for f in fits if f is not None), key=lambda f: f[0], default=None)
    if held is None:
        return ""
    # the ladder refitted with the step from its best start: the ladder fitted beside a
    # junction coefficient, which scales every layer with the junction's temperature, is no
    # ladder for a step of one layer (seed 67's draw 035, a convection switch at 31 °C: χ²/N
    # 439 with that ladder held, 1.07 refitted in 5 s of work)
    x = held[3][-1].params
    refitted = attempt(held[2], True, [x["drop"], x["t_switch_c"], x["width_k"]])
    best = min((f for f in (held, refitted) if f is not None), key=lambda f: f[0])
    bic, cmp, _, effs = best
    if best is refitted:
        # the coefficient given the same work with its ladder: a step that wins by a refit
        # the coefficient's own fit did not have is no evidence (seed 67's draw 032, a real
        # coefficient of the inner layers, whose form left the PWM readings at 5.9× their
        # noise: a step of +71 % over 13 K with the ladder refitted came 16 lower)
        rival = joint_refit(data, ladder, [effect], REGIME_BUDGET_S, comparison, noise)
        if rival is not None:
            comparison = rival[2]
    gap = criterion(comparison, noise, c.n_params) - bic
    if gap < MIN_BIC_DROP:
        return ""
    later = [st.chosen.effect.name for st in steps[1:]]
    lead = criterion(whole, noise, sum(st.chosen.n_params for st in steps)) - bic
    if later and lead <= -MIN_BIC_DROP:
        return ""  # the later effects are decisive on top of a step too
    q = effs[-1].params
    layers = f"layer {first}" if first == last else f"layers {first} to {last}"
    also = (f", and {'better than' if lead >= MIN_BIC_DROP else 'as well as'} it does with "
            f"{' and '.join(later)} added (χ² {chi2(whole, noise):.0f}: BIC {abs(lead):.0f} "
            f"{'lower' if lead >= 0 else 'higher'} with the step)" if later else "")
    return (f"{effect.name} bends the resistance smoothly with temperature, but a step of the "
            f"resistance of {layers}, {-100 * q['drop']:+.0f} % around {q['t_switch_c']:.3g} °C "
            f"over {q['width_k']:.2g} K, fits every data set decisively better (χ² "
            f"{chi2(cmp, noise):.0f} against {chi2(comparison, noise):.0f} on "
            f"{len(cmp.points)} points: BIC {gap:.0f} lower){also}: a change of regime (a "
            f"convection or a fan that switches, a contact that opens), which the catalogue "
            f"does not hold")

