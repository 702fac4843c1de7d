"""``phase-change`` (device): latent heat absorbed across a temperature band at one node.

Latent heat ``latent_j`` absorbed across a band centred at ``t_c`` adds heat capacity at node
``node`` (0 = junction) of the ladder's Cauer form (a Foster ladder's inner nodes are no
physical layers: a model with a band at ``node > 0`` is simulated and exported on its Cauer
form). The band's shape is the effect's form; in each the extra capacity ``c(T)`` is the
derivative of the heat ``H(T)`` absorbed up to ``T``, ``H(−∞) = 0`` and ``H(+∞) = latent_j``:

* ``logistic`` (the default): standard deviation ``width_k``,
  ``H = L / (1 + e^{−(T − t_c)/s})`` with ``s = width_k·√3/π``;
* ``gaussian``: standard deviation ``width_k``, ``H = L Φ((T − t_c)/width_k)`` (a melting
  range spread by impurities or by a temperature gradient across the layer);
* ``plateau``: a flat-topped band of full width ``width_k`` whose edges are logistic steps of
  scale ``edge_k``: ``c = (L/width_k)(σ((T − a)/e) − σ((T − b)/e))``, ``a, b = t_c ∓
  width_k/2`` (boiling in a cavity, a eutectic that melts over its range).

The SPICE renderings give the stored heat ``H`` as a charge whose ``ddt`` is the element's
current (stable in ngspice where ``C(V)·ddt(V)`` is not) with ``EXP``, ``LOG``, ``MAX`` and
``MIN``: the logistic and plateau forms are exact; SPICE has no erf, so the gaussian form uses
the logistic-cubic approximation ``Φ(z) ≈ 1/(1 + e^{−(1.5976 z + 0.070566 z³)})`` (Bowling et
al. 2009; error below :data:`GAUSSIAN_SPICE_ERROR` of ``L``) on ``z`` clipped to ±8.

>>> from spicethermal.effects import Effect
>>> e = Effect.create("phase-change", t_c=60.0, width_k=1.0, latent_j=2.0, node=1)
>>> [round(x, 6) for x in heat(e, [0.0, 60.0], 1)]
[0.0, 1.0]
>>> g = Effect.create("phase-change", "gaussian", t_c=60.0, width_k=1.0, latent_j=2.0)
>>> round(heat(g, [61.0])[0], 6), round(capacity(g, [60.0])[0], 6)
(1.682689, 0.797885)
>>> p = Effect.create("phase-change", "plateau", t_c=60.0, width_k=4.0, edge_k=0.1,
...                   latent_j=2.0)
>>> round(capacity(p, [60.0])[0], 6), round(heat(p, [60.0])[0], 6)
(0.5, 1.0)
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np
from scipy.special import expit, log_expit, ndtr

from ..core.errors import DataFormatError
from .base import COOLING, PWM, STEADY, DeviceEffect, Evidence, Param, Traits, scalar_params
from .spice import number

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import ArrayLike, NDArray

    from .base import Effect

#: Bound on |Φ_SPICE(z) − Φ(z)| of the gaussian form's SPICE rendering (fraction of L).
GAUSSIAN_SPICE_ERROR = 1.5e-4
#: Coefficients of that approximation, ``Φ(z) ≈ 1/(1 + exp(−(a z + b z³)))``.
GAUSSIAN_LOGIT = (1.5976, 0.070566)
#: Where a fit's first starts put the band: these fractions of the node's hottest rise.
START_FRACTIONS = (0.4, 0.75)
#: ... holding at least this fraction of the heat the node's capacity stores over that rise.
START_HEAT = 0.1


def _bump(t: NDArray, residual: NDArray) -> tuple[int, NDArray, float]:
    """The largest residual's index, the indices of the readings around it above half of
    it, and the integral over time of the residual where it stays positive around it."""
    peak = int(np.argmax(residual))
    if residual[peak] <= 0:
        return peak, np.array([], dtype=int), 0.0
    lo, hi = peak, peak
    while lo > 0 and residual[lo - 1] > 0:
        lo -= 1
    while hi < residual.size - 1 and residual[hi + 1] > 0:
        hi += 1
    half = np.nonzero(residual[lo:hi + 1] >= 0.5 * residual[peak])[0] + lo
    return peak, half, float(np.trapezoid(residual[lo:hi + 1], t[lo:hi + 1]))


def _softplus(x: NDArray) -> NDArray:
    """``ln(1 + eˣ)`` without overflow."""
    return -log_expit(-x)


def _band(form: str, p: Mapping[str, NDArray], t: NDArray) -> tuple[NDArray, NDArray]:
    """``(H, dH/dT)`` of the band at temperatures ``t`` (any node)."""
    latent, mid, width = p["latent_j"], p["t_c"], p["width_k"]
    if form == "gaussian":
        z = (t - mid) / width
        return latent * ndtr(z), latent * np.exp(-0.5 * np.minimum(z * z, 1e4)) / (
            width * math.sqrt(2 * math.pi))
    if form == "plateau":
        e = p["edge_k"]
        lo, hi = (t - (mid - 0.5 * width)) / e, (t - (mid + 0.5 * width)) / e
        h = latent * e / width * (_softplus(lo) - _softplus(hi))
        return np.minimum(h, latent), latent / width * (expit(lo) - expit(hi))
    s = width * math.sqrt(3.0) / math.pi
    x = expit((t - mid) / s)
    return latent * x, latent * x * (1.0 - x) / s


def heat(effect: Effect, t_c: ArrayLike, node: int = 0) -> list[float]:
    """Heat (J) the band of ``effect`` holds at node ``node`` at each temperature (°C).

    Parameters
    ----------
    effect : Effect
    t_c : array_like
    node : int

    Returns
    -------
    list of float
    """
    t = np.asarray(t_c, dtype=float)[None, :]
    if node != int(effect.params["node"]):
        return [0.0] * t.size
    return [float(x) for x in _band(effect.form, scalar_params(effect), t)[0][0]]


def capacity(effect: Effect, t_c: ArrayLike, node: int = 0) -> list[float]:
    """Extra heat capacity (J/K) of the band at node ``node`` at each temperature (°C).

    Parameters
    ----------
    effect : Effect
    t_c : array_like
    node : int

    Returns
    -------
    list of float
    """
    t = np.asarray(t_c, dtype=float)[None, :]
    if node != int(effect.params["node"]):
        return [0.0] * t.size
    return [float(x) for x in _band(effect.form, scalar_params(effect), t)[1][0]]


def gaussian_cdf_spice(z: str) -> str:
    """The SPICE approximation of ``Φ(z)`` for the expression ``z``.

    Parameters
    ----------
    z : str

    Returns
    -------
    str

    >>> gaussian_cdf_spice("V(A)")
    '1/(1+EXP(-(1.5976*MAX(-8,MIN(8,V(A)))+0.070566*PWR(MAX(-8,MIN(8,V(A))),3))))'
    """
    a, b = GAUSSIAN_LOGIT
    zc = f"MAX(-8,MIN(8,{z}))"
    return f"1/(1+EXP(-({a}*{zc}+{b}*PWR({zc},3))))"


class PhaseChange(DeviceEffect):
    """Latent heat over a temperature band at one node (see the module docstring)."""

    name = "phase-change"
    summary = ("latent heat (cavity fluid, solder, TIM): extra heat capacity over a "
               "temperature band")
    forms = ("logistic", "gaussian", "plateau")
    params = {
        "t_c": Param("°C", 64.7, -273.15, 1000.0, "centre of the band (methanol boils at "
                     "64.7 °C)", typical=10.0),
        "width_k": Param("K", 2.0, 0.05, 100.0, "standard deviation of the band (logistic, "
                         "gaussian) or its full width (plateau)", log=True),
        "latent_j": Param("J", 0.0, 0.0, 1e6, "latent heat absorbed across the band",
                          log=True),
        "node": Param("", 0, 0, 1000, "ladder node holding the latent heat (0 = junction)",
                      fitted=False),
        "edge_k": Param("K", 0.2, 0.005, 100.0, "logistic scale of the plateau's edges "
                        "(form plateau)", ("plateau",), log=True),
    }
    traits = Traits(frozenset({COOLING, STEADY, PWM}), cost=6.0,
                    confusable_with={"temperature-coefficient": "cooling curves at more "
                                     "powers, some below and some above the band"},
                    shown_alone_by="readings over the temperatures where it would act")

    def stored_heat(self, form: str, p: Mapping[str, NDArray], t_node_c: NDArray,
                    c_node: NDArray) -> tuple[NDArray, NDArray] | None:
        at = np.arange(t_node_c.shape[1])[None, :] == p["node"]
        h, c = _band(form, p, t_node_c)
        return np.where(at, h, 0.0), np.where(at, c, 0.0)

    def physical_nodes(self, effect: Effect) -> bool:
        return int(effect.params["node"]) > 0

    def check(self, effect: Effect) -> None:
        if effect.params["node"] != math.floor(effect.params["node"]):
            raise DataFormatError(f"effect phase-change: node = {effect.params['node']!r} is "
                                  f"not a node index")

    def variants(self, form: str, evidence: Evidence) -> Sequence[Mapping[str, float]]:
        return tuple({"node": float(k)} for k in range(evidence.n_nodes))

    def unshown(self, effect: Effect, evidence: Evidence) -> str:
        """A band is shown only where the temperatures its node reaches (from the coldest
        reference to the hottest the node is before a cut, or the PWM grid's hottest reading)
        cross its centre, where half its heat is absorbed: a band centred outside them shows
        only its tail, a smooth change of heat capacity, and no transition."""
        node = int(effect.params["node"])
        hot = [float(c.nodes_c[node]) for c in evidence.cooling if node < c.nodes_c.size]
        if evidence.pwm is not None:
            hot.append(float(np.max(evidence.pwm[4])))
        hot = [x for x in hot if math.isfinite(x)]
        if not hot or not evidence.cooling:
            return ""
        lo, hi = min(c.tref_c for c in evidence.cooling), max(hot)
        mid = float(effect.params["t_c"])
        if lo <= mid <= hi or not math.isfinite(mid):
            return ""
        where = "the junction" if node == 0 else f"node {node}"
        return (f"its band is centred at {mid:.4g} °C, outside the {lo:.4g}–{hi:.4g} °C "
                f"that {where} reaches: only its tail shows, a smooth change of heat capacity")

    def guess(self, form: str, fixed: Mapping[str, float],
              evidence: Evidence) -> Sequence[Mapping[str, float]]:
        """Starts from what the band would leave in the cooling curves. Heat ``L`` given off
        at node ``k`` while the curve cools through the band keeps the junction above the
        model by a bump whose integral over time is ``L`` times the transfer resistance from
        node ``k`` to the junction: ``L ≈ ∫ r dt / Σ_{i≥k} R_i`` over the bump (the readings
        around the largest residual where it stays positive), on the curve where that
        integral is largest; the band sits where the model's node ``k`` is when the bump
        peaks, about as wide as that node's fall over the bump's half-height span. Two more
        starts place a band at fractions of the node's hottest rise, holding at least
        :data:`START_HEAT` of what the node's own capacity stores over that rise (a model
        that took the band into its capacities leaves a bump too small to measure it)."""
        node = int(fixed.get("node", 0))
        curves = [c for c in evidence.cooling if c.node_paths_c is not None
                  and node < c.node_paths_c.shape[1] and c.t_s.size >= 3]
        if not curves:
            return ()
        tref = min(c.tref_c for c in evidence.cooling)
        rise = max(max(float(c.nodes_c[node]) for c in curves) - tref, 1e-3)
        r_layers = evidence.layer_r_k_per_w
        transfer = sum(r_layers[node:]) if r_layers else evidence.rth_k_per_w
        bumps = [(c, *_bump(c.t_s, c.residual_k)) for c in curves]
        best, peak, span, area = max(bumps, key=lambda b: b[3])
        latent = max(area / max(transfer, 1e-30), 1e-12)
        path = best.node_paths_c[:, node]
        width = max(0.25 * float(path[span[0]] - path[span[-1]]), 0.01 * rise) \
            if span.size else 0.05 * rise
        found = {"t_c": float(path[peak]), "width_k": width, "latent_j": latent}
        c_node = evidence.node_c_j_per_k[node] if node < len(evidence.node_c_j_per_k) else 0.0
        floor = START_HEAT * c_node * rise
        starts = [found] + [{"t_c": tref + f * rise, "width_k": 0.06 * rise,
                             "latent_j": max(latent, floor)} for f in START_FRACTIONS]
        if form == "plateau":
            starts = [{**s, "width_k": 4 * s["width_k"], "edge_k": s["width_k"] / 2}
                      for s in starts]
        return tuple(starts)

    def spice_stored_heat(self, effect: Effect, node: int, t_node: str,
                          c_node: float) -> str | None:
        if node != int(effect.params["node"]):
            return None
        p = effect.params
        if effect.form == "gaussian":
            z = f"({t_node}-({number(p['t_c'])}))/({number(p['width_k'])})"
            return f"({number(p['latent_j'])})*{gaussian_cdf_spice(z)}"
        if effect.form == "plateau":
            e = p["edge_k"]

            def sp(edge: float) -> str:  # ln(1 + eˣ) without overflow
                x = f"(({t_node})-({number(edge)}))/({number(e)})"
                return f"(MAX({x},0)+LOG(1+EXP(MIN({x},-{x}))))"

            a, b = p["t_c"] - 0.5 * p["width_k"], p["t_c"] + 0.5 * p["width_k"]
            return f"({number(p['latent_j'] * e / p['width_k'])})*({sp(a)}-{sp(b)})"
        s = p["width_k"] * math.sqrt(3.0) / math.pi
        return (f"({number(p['latent_j'])})/(1+EXP(-({t_node}-({number(p['t_c'])}))"
                f"/({number(s)})))")

    def describe(self, effect: Effect) -> str:
        p = effect.params
        where = "the junction" if int(p["node"]) == 0 else f"node {int(p['node'])}"
        return (f"{p['latent_j']:.3g} J of latent heat at {where} over a {effect.form} band "
                f"at {p['t_c']:.4g} °C ({'full width' if effect.form == 'plateau' else 'σ'} "
                f"{p['width_k']:.3g} K)")
