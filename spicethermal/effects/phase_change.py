"""``phase-change`` (device): latent heat absorbed across a temperature band at one node.

Latent heat ``latent_j`` absorbed across a band centred at ``t_c`` adds heat capacity from
node ``node`` (0 = junction; the fit tries every node) to the reference. A node ``k > 0`` is
layer ``k`` of the ladder's exact Cauer form (a Foster ladder's inner nodes are no physical
layers): a model with such a band is simulated and exported on that form
(:func:`physical_nodes`). The band's shape is the effect's form; in each the extra capacity
``c(T)`` is the derivative of the heat ``H(T)`` absorbed up to ``T``, ``H(−∞) = 0`` and
``H(+∞) = latent_j``:

* ``logistic`` (the default): standard deviation ``width_k``,
  ``H = L / (1 + e^{−(T − t_c)/s})`` with ``s = width_k·√3/π``;
* ``gaussian``: standard deviation ``width_k``, ``H = L Φ((T − t_c)/width_k)`` (the normal
  CDF, exact through :func:`math.erf`; a melting range spread by impurities or by a
  temperature gradient across the layer);
* ``plateau``: a flat-topped band of full width ``width_k`` (between its edges' midpoints,
  ``a = t_c − width_k/2`` and ``b = t_c + width_k/2``) whose edges are logistic steps of
  scale ``edge_k``: ``c = (L/width_k)(σ((T − a)/e) − σ((T − b)/e))`` and
  ``H = (L e/width_k)(sp((T − a)/e) − sp((T − b)/e))`` with ``sp(x) = ln(1 + eˣ)`` (boiling
  in a cavity or a eutectic that melts at constant rate over its range).

Written without overflow far from the band. The SPICE renderings (``spice_stored_heat``,
charge ``H`` whose ``ddt`` is the element's current, which keeps ngspice stable where
``C(V)·ddt(V)`` is not) use ``EXP``, ``LOG`` (natural in ngspice, PSpice and LTspice),
``MAX`` and ``MIN``: the logistic and plateau forms are exact; SPICE has no erf, so the
gaussian form uses the logistic-cubic approximation of the normal CDF
``Φ(z) ≈ 1/(1 + e^{−(1.5976 z + 0.070566 z³)})`` (Bowling et al. 2009; |error| below
:data:`GAUSSIAN_SPICE_ERROR` of ``L``, checked in the tests) on ``z`` clipped to ±8.

Forms were added in a backward compatible way: a model file without ``form`` is logistic,
``edge_k`` defaults to a tenth of the default width and only the plateau reads it.

>>> from spicethermal.effects import Effect
>>> e = Effect.create("phase-change", t_c=60.0, width_k=1.0, latent_j=2.0, node=1)
>>> e.latent_heat(1, 60.0), e.latent_heat(0, 60.0), e.latent_heat(1, -1e9)
(1.0, 0.0, 0.0)
>>> g = Effect.create("phase-change", "gaussian", t_c=60.0, width_k=1.0, latent_j=2.0)
>>> round(g.latent_heat(0, 61.0), 6), round(g.extra_capacitance(0, 60.0), 6)
(1.682689, 0.797885)
>>> p = Effect.create("phase-change", "plateau", t_c=60.0, width_k=4.0, edge_k=0.1,
...                   latent_j=2.0)
>>> round(p.extra_capacitance(0, 60.0), 6), round(p.latent_heat(0, 60.0), 6)
(0.5, 1.0)
"""

from __future__ import annotations

import math
from collections.abc import Callable

from .catalogue import DEVICE, EffectSpec, Param, register
from .spice import number

#: Bound on |Φ_SPICE(z) − Φ(z)| of the gaussian form's SPICE rendering (fraction of L).
GAUSSIAN_SPICE_ERROR = 1.5e-4
#: Coefficients of that approximation, ``Φ(z) ≈ 1/(1 + exp(−(a z + b z³)))``.
GAUSSIAN_LOGIT = (1.5976, 0.070566)
#: The band's capacity is below 1e-6 of its peak further than these many scales from it
#: (logistic: 4 e^{−15.3} < 1e-6 in logistic scales; gaussian: e^{−z²/2} at 5.3 σ).
REACH_LOGISTIC_SCALES, REACH_GAUSSIAN_SIGMAS = 15.3, 5.3


def _sigmoid(x: float) -> float:
    return 0.5 * (1.0 + math.tanh(0.5 * max(-700.0, min(700.0, x))))


def _softplus(x: float) -> float:
    """``ln(1 + eˣ)`` without overflow."""
    return max(x, 0.0) + math.log1p(math.exp(-abs(x)))


def _edges(effect) -> tuple[float, float, float]:
    p = effect.params
    return p["t_c"] - 0.5 * p["width_k"], p["t_c"] + 0.5 * p["width_k"], p["edge_k"]


def band(effect) -> tuple[float, float]:
    """Temperatures (°C) outside which the band's extra capacity is below 1e-6 of its peak.

    Parameters
    ----------
    effect : Effect
        A ``phase-change`` effect (any form).

    Returns
    -------
    tuple of float
        ``(low, high)``.

    >>> from spicethermal.effects import Effect
    >>> band(Effect.create("phase-change", "gaussian", t_c=50.0, width_k=2.0))
    (39.4, 60.6)
    """
    p = effect.params
    if effect.form == "plateau":
        a, b, e = _edges(effect)
        return a - REACH_LOGISTIC_SCALES * e, b + REACH_LOGISTIC_SCALES * e
    if effect.form == "gaussian":
        reach = REACH_GAUSSIAN_SIGMAS * p["width_k"]
    else:
        reach = REACH_LOGISTIC_SCALES * effect.logistic_scale_k
    return p["t_c"] - reach, p["t_c"] + reach


def latent_heat(effect, node: int, t_c: float, _c_node: float = 0.0) -> float:
    """Heat (J) absorbed at ``node`` up to ``t_c`` (the form's ``H``)."""
    if node != int(effect.params["node"]):
        return 0.0
    p = effect.params
    if effect.form == "gaussian":
        return p["latent_j"] * 0.5 * math.erfc(-(t_c - p["t_c"]) / (p["width_k"] * math.sqrt(2)))
    if effect.form == "plateau":
        a, b, e = _edges(effect)
        lo, hi = (t_c - a) / e, (t_c - b) / e
        if hi > 30.0:  # both edges passed: L minus the (tiny) tail beyond the upper one
            return p["latent_j"] * (1.0 - e / p["width_k"] * (_softplus(-hi) - _softplus(-lo)))
        return p["latent_j"] * e / p["width_k"] * (_softplus(lo) - _softplus(hi))
    return p["latent_j"] * _sigmoid((t_c - p["t_c"]) / effect.logistic_scale_k)


def extra_capacitance(effect, node: int, t_c: float, _c_node: float = 0.0) -> float:
    """Its derivative (J/K)."""
    if node != int(effect.params["node"]):
        return 0.0
    return capacity_law(effect)(t_c)


def capacity_law(effect) -> Callable[[float], float]:
    """The band's extra capacity (J/K) at its own node as a function of that node's
    temperature (°C), with the form's constants computed once: the inner loop of the
    integrations calls it at every right-hand side.

    >>> from spicethermal.effects import Effect
    >>> e = Effect.create("phase-change", "gaussian", t_c=50.0, width_k=2.0, latent_j=1.0)
    >>> round(capacity_law(e)(50.0) * 2.0 * math.sqrt(2 * math.pi), 12)
    1.0
    """
    p = effect.params
    latent, t_mid, width = p["latent_j"], p["t_c"], p["width_k"]
    if effect.form == "gaussian":
        norm = width * math.sqrt(2 * math.pi)

        def gaussian(t_c: float) -> float:
            z = (t_c - t_mid) / width
            if abs(z) > 40.0:
                return 0.0
            return latent * math.exp(-0.5 * z * z) / norm
        return gaussian
    if effect.form == "plateau":
        a, b, e = _edges(effect)
        height = latent / width

        def plateau(t_c: float) -> float:
            return height * (_sigmoid((t_c - a) / e) - _sigmoid((t_c - b) / e))
        return plateau
    s = effect.logistic_scale_k

    def logistic(t_c: float) -> float:
        x = math.exp(-abs((t_c - t_mid) / s))
        return latent * x / (s * (1.0 + x) ** 2)
    return logistic


def gaussian_cdf_spice(z: str) -> str:
    """The SPICE approximation of ``Φ(z)`` (see the module docstring) for expression ``z``.

    Parameters
    ----------
    z : str
        A SPICE expression.

    Returns
    -------
    str
        A dialect-neutral expression.

    >>> gaussian_cdf_spice("V(A)")
    '1/(1+EXP(-(1.5976*MAX(-8,MIN(8,V(A)))+0.070566*PWR(MAX(-8,MIN(8,V(A))),3))))'
    """
    a, b = GAUSSIAN_LOGIT
    zc = f"MAX(-8,MIN(8,{z}))"
    return f"1/(1+EXP(-({a}*{zc}+{b}*PWR({zc},3))))"


def spice_stored_heat(effect, node: int, t_node: str, _c_node: float = 0.0) -> str | None:
    """The heat absorbed up to ``t_node`` as a SPICE expression (``None`` at other nodes)."""
    if node != int(effect.params["node"]):
        return None
    p = effect.params
    if effect.form == "gaussian":
        z = f"({t_node}-({number(p['t_c'])}))/({number(p['width_k'])})"
        return f"({number(p['latent_j'])})*{gaussian_cdf_spice(z)}"
    if effect.form == "plateau":
        a, b, e = _edges(effect)

        def sp(edge: float) -> str:  # ln(1 + eˣ) without overflow
            x = f"(({t_node})-({number(edge)}))/({number(e)})"
            return f"(MAX({x},0)+LOG(1+EXP(MIN({x},-{x}))))"

        return (f"({number(p['latent_j'] * e / p['width_k'])})*({sp(a)}-{sp(b)})")
    return (f"({number(p['latent_j'])})/(1+EXP(-({t_node}-({number(p['t_c'])}))"
            f"/({number(effect.logistic_scale_k)})))")


def physical_nodes(effect) -> bool:
    """True for a band away from the junction: it sits at a layer of the Cauer ladder."""
    return int(effect.params["node"]) > 0


SPEC = register(EffectSpec(
    "phase-change", DEVICE,
    "latent heat (cavity fluid, solder, TIM): extra heat capacity over a temperature band",
    {"t_c": Param("°C", 64.7, -273.15, 1000.0, "centre of the band (methanol boils at 64.7 °C)"),
     "width_k": Param("K", 2.0, 0.05, 100.0, "standard deviation of the band (logistic, "
                      "gaussian) or its full width (plateau)"),
     "latent_j": Param("J", 0.0, 0.0, 1e6, "latent heat absorbed across the band"),
     "node": Param("", 0, 0, 1000, "ladder node holding the latent heat (0 = junction)",
                   fitted=False),
     "edge_k": Param("K", 0.2, 0.005, 100.0, "logistic scale of the plateau's edges "
                     "(form plateau)")},
    ("logistic", "gaussian", "plateau"), extra_capacitance=extra_capacitance,
    latent_heat=latent_heat, spice_stored_heat=spice_stored_heat, physical_nodes=physical_nodes,
    fit="spicethermal.fit.pcfit:fit_phase_change"))
