"""``capacity-drop`` (device): a test plugin that lives outside the package.

A node's heat capacity falls by a fraction above a temperature (a filler that de-bonds, a
phase that stops storing heat): ``C(T) = C0 (1 − f σ((T − t_d)/w))``. The heat it stores beyond
the linear capacity is ``H(T) = −f C0 w ln(1 + e^{(T − t_d)/w})``. Nothing in spicethermal names
it: it is registered through the entry-point group ``spicethermal.effects`` by its own
``pyproject.toml`` and found by the registry like the built-in effects.
"""

from __future__ import annotations

import numpy as np
from scipy.special import expit, log_expit

from spicethermal.effects import COOLING, PWM, STEADY, DeviceEffect, Param, Traits
from spicethermal.effects.spice import number


class CapacityDrop(DeviceEffect):
    """A node's heat capacity falls by a fraction above a temperature."""

    name = "capacity-drop"
    summary = "a node's heat capacity falls by a fraction above a temperature"
    params = {
        "fraction": Param("", 0.0, 0.0, 0.9, "share of the node's capacity lost", typical=0.1),
        "t_d_c": Param("°C", 50.0, -273.15, 1000.0, "where it falls", typical=10.0),
        "width_k": Param("K", 1.0, 0.05, 50.0, "over how many kelvin", log=True),
        "node": Param("", 0, 0, 1000, "the node", fitted=False),
    }
    traits = Traits(frozenset({COOLING, STEADY, PWM}), cost=6.0)

    def stored_heat(self, form, p, t_node_c, c_node):
        x = (t_node_c - p["t_d_c"]) / p["width_k"]
        at = np.arange(t_node_c.shape[1])[None, :] == p["node"]
        k = p["fraction"] * c_node
        heat = -k * p["width_k"] * -log_expit(-x)
        return np.where(at, heat, 0.0), np.where(at, -k * expit(x), 0.0)

    def physical_nodes(self, effect):
        return int(effect.params["node"]) > 0

    def variants(self, form, evidence):
        return tuple({"node": float(k)} for k in range(evidence.n_nodes))

    def guess(self, form, fixed, evidence):
        node = int(fixed["node"])
        curves = [c for c in evidence.cooling if node < c.nodes_c.size]
        if not curves:
            return ()
        tref = min(c.tref_c for c in curves)
        rise = max(float(c.nodes_c[node]) for c in curves) - tref
        return tuple({"fraction": 0.3, "t_d_c": tref + f * rise, "width_k": 0.05 * rise}
                     for f in (0.3, 0.6))

    def spice_stored_heat(self, effect, node, t_node, c_node):
        p = effect.params
        if node != int(p["node"]) or not c_node:
            return None
        x = f"(({t_node})-({number(p['t_d_c'])}))/({number(p['width_k'])})"
        return (f"(-{number(p['fraction'] * c_node * p['width_k'])})"
                f"*(MAX({x},0)+LOG(1+EXP(MIN({x},-{x}))))")
