"""``electrical-transient`` (measurement): the first readings after the cut are wrong.

A cooling reading at ``t`` after the cut is off by

* form ``fixed``: ``amplitude_k · exp(−5 t / masked_s)``;
* form ``power``: ``k_per_w · P · exp(−5 t / masked_s)``, proportional to the power ``P``
  before the cut (an artefact of the current switched off);
* form ``ringing``: ``amplitude_k · exp(−5 t / masked_s) · cos(2π ring_hz t)``, a damped
  ringing.

``masked_s`` is the span after which the error has fallen below 1 % (e⁻⁵); the fix is masking
and √t extrapolation (:mod:`spicethermal.identify.curves`).

>>> import numpy as np
>>> from spicethermal.effects import Effect
>>> from spicethermal.effects.base import Observation
>>> e = Effect.create("electrical-transient", "power", k_per_w=-10.0, masked_s=1e-4)
>>> obs = Observation("cooling", np.array([0.0]), np.array([0.3]), np.array([25.0]))
>>> e.plugin.read(e.form, {k: np.full((1, 1), v) for k, v in e.params.items()}, obs,
...               np.array([[30.0]])).round(9).tolist()
[[27.0]]
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np

from .base import COOLING, Evidence, MeasurementEffect, Observation, Param, Traits

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

    from .base import Effect

#: The error decays as ``exp(−RATE · t / masked_s)``: 1 % is left after ``masked_s``.
RATE = 5.0


class ElectricalTransient(MeasurementEffect):
    """The electrical transient after power cut-off spoils the first cooling readings."""

    name = "electrical-transient"
    summary = ("the electrical transient after power cut-off masks the first part of a "
               "cooling curve")
    forms = ("fixed", "power", "ringing")
    params = {
        "masked_s": Param("s", 1e-4, 0.0, 1.0, "span after the cut during which readings are "
                          "wrong", log=True),
        "amplitude_k": Param("K", 0.0, -1e3, 1e3, "error of the reading at the cut, decaying "
                             "over the masked span (forms fixed, ringing)", ("fixed", "ringing")),
        "k_per_w": Param("K/W", 0.0, -1e4, 1e4, "error at the cut per watt cut off (form "
                         "power)", ("power",)),
        "ring_hz": Param("Hz", 0.0, 0.0, 1e9, "ringing frequency (form ringing)", ("ringing",),
                         log=True),
    }
    traits = Traits(frozenset({COOLING}), cost=1.0,
                    confusable_with={"phase-change": "the steady reading just before the cut "
                                     "(a transient leaves it alone)"})
    stage = 2

    def read(self, form: str, p: Mapping[str, NDArray], obs: Observation,
             values: NDArray) -> NDArray:
        if obs.kind != COOLING:
            return values
        t = obs.x[None, :]
        amp = p["k_per_w"] * obs.power_w[None, :] if form == "power" else p["amplitude_k"]
        err = amp * np.exp(-RATE * t / np.maximum(p["masked_s"], 1e-300))
        if form == "ringing":
            err = err * np.cos(2 * math.pi * p["ring_hz"] * t)
        return values + err

    def guess(self, form: str, fixed: Mapping[str, float],
              evidence: Evidence) -> Sequence[Mapping[str, float]]:
        curves = [c for c in evidence.cooling if c.t_s.size >= 3]
        if not curves:
            return ()
        worst = max(curves, key=lambda c: abs(float(c.residual_k[0])))
        r, t = worst.residual_k, worst.t_s
        r0 = float(r[0])
        below = np.nonzero(np.abs(r) < abs(r0) / math.e)[0]
        t_e = float(t[below[0]]) if below.size else float(t[min(3, t.size - 1)])
        masked = float(np.clip(RATE * t_e, 2 * t[0], 0.3 * t[-1]))
        starts = []
        for m in (masked, 3 * masked):
            amp = r0 * math.exp(min(RATE * float(t[0]) / m, 50.0))
            if form == "power":
                starts.append({"masked_s": m, "k_per_w": amp / max(worst.power_w, 1e-30)})
            elif form == "ringing":
                starts += [{"masked_s": m, "amplitude_k": amp, "ring_hz": k / m}
                           for k in (0.5, 2.0)]
            else:
                starts.append({"masked_s": m, "amplitude_k": amp})
        return starts

    def describe(self, effect: Effect) -> str:
        p = effect.params
        size = (f"{p['k_per_w']:.3g} K per watt cut off" if effect.form == "power" else
                f"{p['amplitude_k']:+.3g} K at the cut")
        ring = f", ringing at {p['ring_hz']:.3g} Hz" if effect.form == "ringing" else ""
        return (f"cooling readings off by {size}{ring}, gone after "
                f"{p['masked_s'] * 1e6:.3g} µs")
