"""``phase-change`` (device): latent heat absorbed across a temperature band at one node.

Latent heat ``latent_j`` absorbed across a band centred at ``t_c`` adds heat capacity from
node ``node`` (index into the ladder, 0 = junction; the fit tries every node) to the
reference. The band is logistic with standard deviation ``width_k``: the heat absorbed up to
T is ``latent_j / (1 + exp(−(T − t_c)/s))`` with ``s = width_k·√3/π``, and the extra capacity
is its derivative. (A logistic band rather than a Gaussian one: SPICE has no erf, and writing
the element as ``ddt`` of this charge keeps ngspice stable where ``C(V)·ddt(V)`` is not.)
Both are written without overflow far from the band.

>>> from spicethermal.effects import Effect
>>> e = Effect.create("phase-change", t_c=60.0, width_k=1.0, latent_j=2.0, node=1)
>>> e.latent_heat(1, 60.0), e.latent_heat(0, 60.0), e.latent_heat(1, -1e9)
(1.0, 0.0, 0.0)
"""

from __future__ import annotations

import math

from .catalogue import DEVICE, EffectSpec, Param, register
from .spice import number


def _z(effect, node: int, t_c: float) -> float | None:
    if node != int(effect.params["node"]):
        return None
    return (t_c - effect.params["t_c"]) / effect.logistic_scale_k


def latent_heat(effect, node: int, t_c: float, _c_node: float = 0.0) -> float:
    """Heat (J) absorbed up to ``t_c``: ``L / (1 + e^{−z})``."""
    z = _z(effect, node, t_c)
    if z is None:
        return 0.0
    return effect.params["latent_j"] * 0.5 * (1.0 + math.tanh(0.5 * max(-700.0, min(700.0, z))))


def extra_capacitance(effect, node: int, t_c: float, _c_node: float = 0.0) -> float:
    """Its derivative, ``L e^{−|z|} / (s (1 + e^{−|z|})²)`` (J/K)."""
    z = _z(effect, node, t_c)
    if z is None:
        return 0.0
    e = math.exp(-abs(z))
    return effect.params["latent_j"] * e / (effect.logistic_scale_k * (1.0 + e) ** 2)


def spice_stored_heat(effect, node: int, t_node: str, _c_node: float = 0.0) -> str | None:
    """The heat absorbed up to ``t_node`` as a SPICE expression (``None`` at other nodes)."""
    if node != int(effect.params["node"]):
        return None
    p = effect.params
    return (f"({number(p['latent_j'])})/(1+EXP(-({t_node}-({number(p['t_c'])}))"
            f"/({number(effect.logistic_scale_k)})))")


SPEC = register(EffectSpec(
    "phase-change", DEVICE,
    "latent heat (cavity fluid, solder, TIM): extra heat capacity over a temperature band",
    {"t_c": Param("°C", 64.7, -273.15, 1000.0, "centre of the band (methanol boils at 64.7 °C)"),
     "width_k": Param("K", 2.0, 0.05, 100.0, "standard deviation of the band"),
     "latent_j": Param("J", 0.0, 0.0, 1e6, "latent heat absorbed across the band"),
     "node": Param("", 0, 0, 1000, "ladder node holding the latent heat (0 = junction)")},
    ("logistic",), extra_capacitance=extra_capacitance, latent_heat=latent_heat,
    spice_stored_heat=spice_stored_heat))
