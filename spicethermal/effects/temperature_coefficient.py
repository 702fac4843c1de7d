"""``temperature-coefficient`` (device): the resistances change with temperature.

Form ``junction``: every resistance of the ladder scales with the junction temperature,
``R(T) = R0 · (1 + alpha_per_k · (Tj − t0_c))`` (clipped at 5 % of R0). It also stands in, to
first order, for a conductivity that follows each layer's own temperature or a power law in
kelvin: the fit then reports an effective α.

>>> from spicethermal.effects import Effect
>>> Effect.create("temperature-coefficient", alpha_per_k=-3e-3).resistance_scale(125.0)
0.7
"""

from __future__ import annotations

from .catalogue import DEVICE, EffectSpec, Param, register
from .spice import number


def resistance_scale(effect, tj_c: float) -> float:
    """``max(0.05, 1 + α (Tj − T0))``."""
    p = effect.params
    return max(0.05, 1.0 + p["alpha_per_k"] * (tj_c - p["t0_c"]))


def spice_resistance_scale(effect, _layer: int, _t_layer: str, t_junction: str) -> str:
    """The same factor as a SPICE expression of the junction temperature."""
    p = effect.params
    return f"MAX(0.05,1+({number(p['alpha_per_k'])})*({t_junction}-({number(p['t0_c'])})))"


SPEC = register(EffectSpec(
    "temperature-coefficient", DEVICE, "Rth changes with temperature, R(T) = R0·(1 + α·(T − T0))",
    {"alpha_per_k": Param("1/K", 0.0, -0.02, 0.02, "relative change of every R per kelvin"),
     "t0_c": Param("°C", 25.0, -273.15, 1000.0, "temperature at which R = R0")},
    ("junction",), resistance_scale=resistance_scale,
    spice_resistance_scale=spice_resistance_scale))
