"""``temperature-coefficient`` (device): the resistances (and heat capacities) change with T.

Forms (the form is part of the model file and of the diagnosis JSON; ``junction`` is the
default, and the other forms were added later without changing it — files that do not name a
form read as before):

* ``junction``: every resistance of the ladder follows the junction temperature,
  ``R(T) = R0 · (1 + alpha_per_k · (Tj − t0_c))`` (clipped at 5 % of R0). It also stands in,
  to first order, for the forms below with an effective α.
* ``local``: the resistance of each Cauer layer ``i`` (joining node ``i`` to node ``i + 1``,
  the last one to the reference) follows the layer's own mean temperature
  ``(T_i + T_{i+1})/2`` with the same linear law.
* ``power-law``: as ``local`` with ``R0 · ((T + 273.15)/(t0_c + 273.15))^exponent`` (T in
  kelvin: a conductivity ``k ∝ T^−n`` gives ``exponent = n``; silicon about +1.3).

In the local forms only the layers ``first_layer`` to ``last_layer`` change (0 = the layer at
the junction; ``last_layer`` is clipped to the ladder's last layer, so the defaults mean every
layer): an *inner* subset is ``first_layer = 0, last_layer = k − 1``, an *outer* one (package,
solder, TIM) ``first_layer = n − k``. The heat capacity of the same layers' nodes may rise
with their temperature, ``C_i(T) = C0_i (1 + c_slope_per_k (T_i − t0_c))`` (valid while that
factor stays positive); the junction form has no capacity slope and no subset.

Local forms need physical node temperatures: a Foster ladder's inner nodes are not physical,
so a model with a local form is simulated on its ladder's exact Cauer equivalent (the hook
``physical_nodes``) and exported to SPICE on the Cauer topology.

>>> from spicethermal.effects import Effect
>>> Effect.create("temperature-coefficient", alpha_per_k=-3e-3).resistance_scale(0, 25.0, 125.0)
0.7
>>> e = Effect.create("temperature-coefficient", "power-law", exponent=1.0, first_layer=2)
>>> e.resistance_scale(1, 25.0 + 298.15, 0.0), e.resistance_scale(2, 25.0 + 298.15, 0.0)
(1.0, 2.0)
"""

from __future__ import annotations

import math

import numpy as np

from ..core.errors import DataFormatError
from .catalogue import DEVICE, EffectSpec, Param, register
from .spice import number

KELVIN = 273.15
#: Forms whose resistances follow their own layer's temperature (simulated on a Cauer ladder).
LOCAL_FORMS = ("local", "power-law")
#: Not a form of the catalogue: the law of a change of regime, a resistance that steps by the
#: fraction ``drop`` around ``t_switch_c`` over ``width_k``,
#: ``R(T) = R0 · (1 − drop / (1 + e^{−(T − t_switch_c)/width_k}))`` (a convection that changes
#: regime, a fan that starts). No effect takes it; :mod:`spicethermal.analysis.regime` fits it
#: as the rival of a coefficient's smooth law, and :func:`law` evaluates it for the forward
#: models of the local forms.
SWITCH = "switch"
#: Smallest resistance factor of the linear law (a resistance never vanishes).
FLOOR = 0.05
#: ``last_layer`` default: clipped to the ladder's last layer, i.e. every layer.
LAST = 1000.0


def applies(effect, layer: int) -> bool:
    """True when layer (or node) ``layer`` changes with temperature under ``effect``.

    Parameters
    ----------
    effect : Effect
        A ``temperature-coefficient`` effect.
    layer : int
        Layer index (0 = at the junction); node ``i`` belongs to layer ``i``.

    Returns
    -------
    bool
        Whether the layer is in the effect's subset (every layer in the junction form).

    >>> from spicethermal.effects import Effect
    >>> applies(Effect.create("temperature-coefficient", "local", first_layer=2), 1)
    False
    """
    p = effect.params
    return effect.form == "junction" or p["first_layer"] <= layer <= p["last_layer"]


def law(effect, t_c: float) -> float:
    """``R(T)/R0`` of the effect's law at temperature ``t_c`` (°C).

    Parameters
    ----------
    effect : Effect
        A ``temperature-coefficient`` effect.
    t_c : float or array_like
        The controlling temperature (junction or layer), °C.

    Returns
    -------
    float or ndarray
        The factor on R0 (an array for an array of temperatures).

    >>> from spicethermal.effects import Effect
    >>> law(Effect.create("temperature-coefficient", alpha_per_k=0.01), 35.0)
    1.1
    """
    p = effect.params
    t = np.asarray(t_c, dtype=float)
    if effect.form == "power-law":
        out = (np.maximum(t + KELVIN, 1.0) / (p["t0_c"] + KELVIN)) ** p["exponent"]
    elif effect.form == SWITCH:
        out = 1.0 - p["drop"] * _step(effect, t)
    else:
        out = np.maximum(FLOOR, 1.0 + p["alpha_per_k"] * (t - p["t0_c"]))
    return out if out.ndim else float(out)


def law_slope(effect, t_c: float) -> float:
    """``d(R/R0)/dT`` (1/K) of :func:`law` at ``t_c``.

    Parameters
    ----------
    effect : Effect
        A ``temperature-coefficient`` effect.
    t_c : float or array_like
        Temperature, °C.

    Returns
    -------
    float or ndarray
        The slope (0 where the linear law is clipped).

    >>> from spicethermal.effects import Effect
    >>> law_slope(Effect.create("temperature-coefficient", "power-law", exponent=2.0), 25.0)
    0.0067...
    """
    p = effect.params
    t = np.asarray(t_c, dtype=float)
    if effect.form == "power-law":
        x = np.maximum(t + KELVIN, 1.0) / (p["t0_c"] + KELVIN)
        out = p["exponent"] * x ** (p["exponent"] - 1.0) / (p["t0_c"] + KELVIN)
    elif effect.form == SWITCH:
        step = _step(effect, t)
        out = -p["drop"] * step * (1.0 - step) / p["width_k"]
    else:
        out = np.where(1.0 + p["alpha_per_k"] * (t - p["t0_c"]) > FLOOR, p["alpha_per_k"], 0.0)
    return out if out.ndim else float(out)


def size(effect) -> float:
    """The parameter that sets how far the law moves R from R0, with its sign for the
    catalogue's forms (0: the law is flat): the exponent of the power law, the step's drop
    (positive when R falls), α otherwise.

    >>> from spicethermal.effects import Effect
    >>> size(Effect.create("temperature-coefficient", "power-law", exponent=1.3))
    1.3
    """
    p = effect.params
    if effect.form == "power-law":
        return p["exponent"]
    return p["drop"] if effect.form == SWITCH else p["alpha_per_k"]


def _step(effect, t: np.ndarray) -> np.ndarray:
    """The logistic step ``1/(1 + e^{−(T − t_switch_c)/width_k})`` of the :data:`SWITCH` law."""
    p = effect.params
    return 1.0 / (1.0 + np.exp(-np.clip((t - p["t_switch_c"]) / p["width_k"], -60.0, 60.0)))


def resistance_scale(effect, layer: int, t_layer_c: float, tj_c: float) -> float:
    """Factor on layer ``layer``'s resistance: the law of the junction temperature (form
    ``junction``) or of the layer's mean temperature (local forms, layers of the subset)."""
    if not applies(effect, layer):
        return 1.0
    return float(law(effect, tj_c if effect.form == "junction" else t_layer_c))


def extra_capacitance(effect, node: int, t_c: float, c_node: float = 0.0) -> float:
    """``C0 β (T − T0)`` (J/K) at the nodes of the subset (local forms); ``c_node`` is C0."""
    if effect.form == "junction" or not applies(effect, node):
        return 0.0
    return c_node * effect.params["c_slope_per_k"] * (t_c - effect.params["t0_c"])


def latent_heat(effect, node: int, t_c: float, c_node: float = 0.0) -> float:
    """Heat (J) stored beyond the linear capacity from T0 up to ``t_c``: ``C0 β (T − T0)²/2``."""
    if effect.form == "junction" or not applies(effect, node):
        return 0.0
    return 0.5 * c_node * effect.params["c_slope_per_k"] * (t_c - effect.params["t0_c"]) ** 2


def spice_resistance_scale(effect, layer: int, t_layer: str, t_junction: str) -> str | None:
    """The factor of :func:`resistance_scale` as a SPICE expression (``None`` outside the
    subset)."""
    if not applies(effect, layer):
        return None
    p = effect.params
    t0 = number(p["t0_c"])
    if effect.form == "power-law":
        return (f"PWR(MAX({t_layer}+{number(KELVIN)},1)/({number(p['t0_c'] + KELVIN)}),"
                f"{number(p['exponent'])})")
    t = t_junction if effect.form == "junction" else t_layer
    return f"MAX({number(FLOOR)},1+({number(p['alpha_per_k'])})*({t}-({t0})))"


def spice_stored_heat(effect, node: int, t_node: str, c_node: float = 0.0) -> str | None:
    """:func:`latent_heat` as a SPICE expression (``None`` without a capacity slope)."""
    p = effect.params
    if effect.form == "junction" or not applies(effect, node) or not p["c_slope_per_k"] \
            or not c_node:
        return None
    return (f"({number(0.5 * c_node * p['c_slope_per_k'])})*({t_node}-({number(p['t0_c'])}))"
            f"*({t_node}-({number(p['t0_c'])}))")


def physical_nodes(effect) -> bool:
    """True for the local forms: they are simulated and exported on the Cauer ladder."""
    return effect.form in LOCAL_FORMS


def check(effect) -> None:
    """Reject parameters the form does not use (a junction form with a subset or a capacity
    slope would be silently ignored) and an empty subset."""
    p = effect.params
    if effect.form == "junction":
        if p["c_slope_per_k"] or p["first_layer"] or p["last_layer"] != LAST:
            raise DataFormatError("effect temperature-coefficient: c_slope_per_k, first_layer "
                                  "and last_layer need a local form (local or power-law), "
                                  "not junction")
    elif p["first_layer"] > p["last_layer"]:
        raise DataFormatError(f"effect temperature-coefficient: first_layer "
                              f"{p['first_layer']:g} > last_layer {p['last_layer']:g}")
    for key in ("first_layer", "last_layer"):
        if p[key] != math.floor(p[key]):
            raise DataFormatError(f"effect temperature-coefficient: {key} = {p[key]!r} is not "
                                  f"a layer index")


SPEC = register(EffectSpec(
    "temperature-coefficient", DEVICE, "Rth changes with temperature, R(T) = R0·(1 + α·(T − T0))",
    {"alpha_per_k": Param("1/K", 0.0, -0.02, 0.02, "relative change of R per kelvin",
                          ("junction", "local")),
     "t0_c": Param("°C", 25.0, -273.15, 1000.0, "temperature at which R = R0 (and C = C0)",
                   fitted=False),
     "exponent": Param("", 0.0, -4.0, 6.0, "power-law exponent n of R ∝ T^n, T in kelvin",
                       ("power-law",)),
     "c_slope_per_k": Param("1/K", 0.0, -0.01, 0.02,
                            "relative rise of the subset's heat capacities per kelvin",
                            LOCAL_FORMS),
     "first_layer": Param("", 0.0, 0.0, LAST, "first layer that changes (0 = junction)",
                          LOCAL_FORMS, fitted=False),
     "last_layer": Param("", LAST, 0.0, LAST, "last layer that changes (clipped: all)",
                         LOCAL_FORMS, fitted=False)},
    ("junction", *LOCAL_FORMS), resistance_scale=resistance_scale,
    extra_capacitance=extra_capacitance, latent_heat=latent_heat,
    spice_resistance_scale=spice_resistance_scale, spice_stored_heat=spice_stored_heat,
    physical_nodes=physical_nodes, check=check,
    fit="spicethermal.fit.tcfit:fit_temperature_coefficient"))
