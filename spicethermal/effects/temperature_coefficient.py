"""``temperature-coefficient`` (device): the resistances (and heat capacities) change with T.

Forms (``junction`` is the default; files that do not name a form read as junction):

* ``junction``: every resistance of the ladder follows the junction temperature,
  ``R(T) = R0 · (1 + alpha_per_k · (Tj − t0_c))`` (clipped at 5 % of R0). It also stands in,
  to first order, for the forms below with an effective α.
* ``local``: the resistance of each Cauer layer ``i`` (joining node ``i`` to node ``i + 1``,
  the last one to the reference) follows the layer's own mean temperature
  ``(T_i + T_{i+1})/2`` with the same linear law.
* ``power-law``: as ``local`` with ``R0 · ((T + 273.15)/(t0_c + 273.15))^exponent`` (T in
  kelvin: a conductivity ``k ∝ T^−n`` gives ``exponent = n``; silicon about +1.3).
* ``quadratic``: as ``local`` with ``R0 · (1 + alpha_per_k·(T − t0_c) + curvature_per_k2·(T −
  t0_c)²)`` (clipped at 5 % of R0): any smooth law to second order about ``t0_c``, a
  conductivity with a minimum (a resistance with a maximum) included.

In the local forms only the layers ``first_layer`` to ``last_layer`` change (0 = the layer at
the junction; ``last_layer`` is clipped to the ladder's last layer, so the defaults mean every
layer): an *inner* subset is ``first_layer = 0, last_layer = k − 1``, an *outer* one (package,
solder, TIM) ``first_layer = n − k``. The heat capacity of the same layers' nodes may rise
with their temperature, ``C_i(T) = C0_i (1 + c_slope_per_k (T_i − t0_c))``; the junction form
has no capacity slope and no subset. Local forms need physical node temperatures: a model with
one is simulated and exported on its ladder's Cauer form.

>>> from spicethermal.effects import Effect
>>> e = Effect.create("temperature-coefficient", alpha_per_k=-3e-3)
>>> float(law(e, 125.0))
0.7
>>> p = Effect.create("temperature-coefficient", "power-law", exponent=1.0, first_layer=2)
>>> float(law(p, 25.0 + 298.15)), applies(p, 1), applies(p, 2)
(2.0, False, True)
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np

from ..core.errors import DataFormatError
from .base import COOLING, PWM, STEADY, DeviceEffect, Evidence, Param, Traits
from .spice import number

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

    from .base import Effect

KELVIN = 273.15
#: Forms whose resistances follow their own layer's temperature (simulated on a Cauer ladder).
LOCAL_FORMS = ("local", "power-law", "quadratic")
#: Smallest resistance factor of the linear law (a resistance never vanishes).
FLOOR = 0.05
#: ``last_layer`` default: clipped to the ladder's last layer, i.e. every layer.
LAST = 1000.0


def _law(form: str, p: Mapping[str, NDArray], t: NDArray) -> NDArray:
    if form == "power-law":
        return (np.maximum(t + KELVIN, 1.0) / (p["t0_c"] + KELVIN)) ** p["exponent"]
    d = t - p["t0_c"]
    if form == "quadratic":
        return np.maximum(FLOOR, 1.0 + d * (p["alpha_per_k"] + p["curvature_per_k2"] * d))
    return np.maximum(FLOOR, 1.0 + p["alpha_per_k"] * d)


def law(effect: Effect, t_c: float | NDArray) -> NDArray:
    """``R(T)/R0`` of the effect's law at the controlling temperature ``t_c`` (°C).

    Parameters
    ----------
    effect : Effect
        A ``temperature-coefficient`` effect.
    t_c : float or array_like
        Temperature (°C).

    Returns
    -------
    ndarray
    """
    p = {k: np.asarray(v, dtype=float) for k, v in effect.params.items()}
    return _law(effect.form, p, np.asarray(t_c, dtype=float))


def _subset(p: Mapping[str, NDArray], n: int) -> NDArray:
    """``(B, n)`` mask of the layers in the subset."""
    idx = np.arange(n)[None, :]
    return (idx >= p["first_layer"]) & (idx <= p["last_layer"])


def applies(effect: Effect, layer: int) -> bool:
    """True when layer (or node) ``layer`` changes with temperature under ``effect``.

    Parameters
    ----------
    effect : Effect
    layer : int
        Layer index (0 = at the junction); node ``i`` belongs to layer ``i``.

    Returns
    -------
    bool
    """
    p = effect.params
    return effect.form == "junction" or p["first_layer"] <= layer <= p["last_layer"]


class TemperatureCoefficient(DeviceEffect):
    """Rth changes with temperature (see the module docstring)."""

    name = "temperature-coefficient"
    summary = "Rth changes with temperature, R(T) = R0·(1 + α·(T − T0))"
    forms = ("junction", *LOCAL_FORMS)
    params = {
        "alpha_per_k": Param("1/K", 0.0, -0.02, 0.02, "relative change of R per kelvin",
                             ("junction", "local", "quadratic"), typical=1e-3),
        "t0_c": Param("°C", 25.0, -273.15, 1000.0, "temperature at which R = R0 (and C = C0)",
                      fitted=False),
        "exponent": Param("", 0.0, -4.0, 6.0, "power-law exponent n of R ∝ T^n, T in kelvin",
                          ("power-law",), typical=0.3),
        "curvature_per_k2": Param("1/K²", 0.0, -1e-3, 1e-3,
                                  "relative change of R per kelvin squared (quadratic)",
                                  ("quadratic",), typical=1e-5),
        "c_slope_per_k": Param("1/K", 0.0, -0.01, 0.02,
                               "relative rise of the subset's heat capacities per kelvin",
                               LOCAL_FORMS, typical=1e-3),
        "first_layer": Param("", 0.0, 0.0, LAST, "first layer that changes (0 = junction)",
                             LOCAL_FORMS, fitted=False),
        "last_layer": Param("", LAST, 0.0, LAST, "last layer that changes (clipped: all)",
                            LOCAL_FORMS, fitted=False),
    }
    traits = Traits(frozenset({COOLING, STEADY, PWM}), cost=4.0,
                    confusable_with={"phase-change": "cooling curves at more powers"})

    # -- physics ----------------------------------------------------------------------------
    def resistance_scale(self, form: str, p: Mapping[str, NDArray], t_layer_c: NDArray,
                         t_junction_c: NDArray) -> NDArray | None:
        if form == "junction":
            return np.broadcast_to(_law(form, p, t_junction_c), t_layer_c.shape)
        return np.where(_subset(p, t_layer_c.shape[1]), _law(form, p, t_layer_c), 1.0)

    def stored_heat(self, form: str, p: Mapping[str, NDArray], t_node_c: NDArray,
                    c_node: NDArray) -> tuple[NDArray, NDArray] | None:
        if form == "junction" or not np.any(p["c_slope_per_k"]):
            return None
        d = t_node_c - p["t0_c"]
        k = np.where(_subset(p, t_node_c.shape[1]), c_node * p["c_slope_per_k"], 0.0)
        return 0.5 * k * d * d, k * d

    def physical_nodes(self, effect: Effect) -> bool:
        return effect.form in LOCAL_FORMS

    def check(self, effect: Effect) -> None:
        p = effect.params
        if effect.form == "junction":
            if p["c_slope_per_k"] or p["first_layer"] or p["last_layer"] != LAST:
                raise DataFormatError("effect temperature-coefficient: c_slope_per_k, "
                                      "first_layer and last_layer need a local form (local or "
                                      "power-law), not junction")
        elif p["first_layer"] > p["last_layer"]:
            raise DataFormatError(f"effect temperature-coefficient: first_layer "
                                  f"{p['first_layer']:g} > last_layer {p['last_layer']:g}")
        for key in ("first_layer", "last_layer"):
            if p[key] != math.floor(p[key]):
                raise DataFormatError(f"effect temperature-coefficient: {key} = {p[key]!r} "
                                      f"is not a layer index")

    # -- fitting ----------------------------------------------------------------------------
    def variants(self, form: str, evidence: Evidence) -> Sequence[Mapping[str, float]]:
        n_nodes = evidence.n_nodes
        if form == "junction":
            return ({},)
        out: list[Mapping[str, float]] = [{"first_layer": 0.0, "last_layer": LAST}]
        for k in range(1, n_nodes):
            out.append({"first_layer": 0.0, "last_layer": float(k - 1)})
            out.append({"first_layer": float(n_nodes - k), "last_layer": LAST})
        return tuple(out)

    def guess(self, form: str, fixed: Mapping[str, float],
              evidence: Evidence) -> Sequence[Mapping[str, float]]:
        alpha = _apparent_alpha(evidence)
        t0 = evidence.reference_c
        starts = []
        for a in (alpha, -alpha):
            if form == "power-law":
                starts.append({"exponent": float(np.clip(a * (t0 + KELVIN), -3.9, 5.9)),
                               "c_slope_per_k": 0.0, "t0_c": t0})
            else:
                starts.append({"alpha_per_k": a, "t0_c": t0,
                               **({"c_slope_per_k": 0.0} if form != "junction" else {}),
                               **({"curvature_per_k2": 0.0} if form == "quadratic" else {})})
        return starts

    # -- SPICE --------------------------------------------------------------------------------
    def spice_resistance_scale(self, effect: Effect, layer: int, t_layer: str,
                               t_junction: str) -> str | None:
        if not applies(effect, layer):
            return None
        p = effect.params
        if effect.form == "power-law":
            return (f"PWR(MAX({t_layer}+{number(KELVIN)},1)/({number(p['t0_c'] + KELVIN)}),"
                    f"{number(p['exponent'])})")
        t = t_junction if effect.form == "junction" else t_layer
        d = f"({t}-({number(p['t0_c'])}))"
        if effect.form == "quadratic":
            return (f"MAX({number(FLOOR)},1+{d}*(({number(p['alpha_per_k'])})"
                    f"+({number(p['curvature_per_k2'])})*{d}))")
        return f"MAX({number(FLOOR)},1+({number(p['alpha_per_k'])})*{d})"

    def spice_stored_heat(self, effect: Effect, node: int, t_node: str,
                          c_node: float) -> str | None:
        p = effect.params
        if effect.form == "junction" or not applies(effect, node) or not p["c_slope_per_k"] \
                or not c_node:
            return None
        t0 = number(p["t0_c"])
        return (f"({number(0.5 * c_node * p['c_slope_per_k'])})*({t_node}-({t0}))"
                f"*({t_node}-({t0}))")

    def describe(self, effect: Effect) -> str:
        p = effect.params
        last = "last" if p["last_layer"] >= LAST else str(int(p["last_layer"]))
        where = ("every layer on the junction temperature" if effect.form == "junction" else
                 f"layers {int(p['first_layer'])}..{last} on their own temperature")
        if effect.form == "power-law":
            law_text = f"R ∝ T^{p['exponent']:.3g} (T in kelvin)"
        elif effect.form == "quadratic":
            law_text = (f"R = R0·(1 {p['alpha_per_k']:+.3g}·ΔT {p['curvature_per_k2']:+.3g}·ΔT²),"
                        " ΔT in K")
        else:
            law_text = f"R changes {100 * p['alpha_per_k']:+.3g} %/K"
        slope = (f", heat capacity {100 * p['c_slope_per_k']:+.3g} %/K"
                 if effect.form != "junction" and p["c_slope_per_k"] else "")
        return f"{law_text} from {p['t0_c']:.4g} °C, {where}{slope}"


def _apparent_alpha(evidence: Evidence) -> float:
    """A first α (1/K): how the ratio of measured to modelled rise at the first reading of
    each cooling curve changes with that curve's rise (two curves or more), else how the PWM
    residual changes with the mean rise; 1e-3 when nothing says."""
    xs, ys = [], []
    for c in evidence.cooling:
        rise_m = float(c.model_c[0] - c.tref_c)
        if abs(rise_m) > 0:
            xs.append(rise_m)
            ys.append(float(c.reading_c[0] - c.tref_c) / rise_m - 1.0)
    if len(xs) < 2 and evidence.pwm is not None:
        _f, duty, power, reading, model = evidence.pwm
        rise = duty * power * evidence.rth_k_per_w
        ok = rise > 0
        xs, ys = list(rise[ok]), list(((reading - model)[ok]) / rise[ok])
    if len(xs) >= 2 and np.ptp(xs) > 0:
        slope = float(np.polyfit(xs, ys, 1)[0])
        if math.isfinite(slope) and slope != 0:
            return float(np.clip(slope, -1e-2, 1e-2))
    return 1e-3
