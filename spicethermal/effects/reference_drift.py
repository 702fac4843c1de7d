"""``reference-drift`` (rival, not catalogued): the reference warms during each cooling curve.

An ambient, a cold plate or a heatsink that drifts while a curve is recorded, without a
``tref_c`` column that records it, adds ``rate · t`` to the readings at ``t`` after the cut.
The diagnosis weighs it beside the catalogued effects and never names it; recording the
reference's temperature with each reading tells it apart.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np

from .base import COOLING, Evidence, MeasurementEffect, Observation, Param, Traits

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

    from .base import Effect


class ReferenceDrift(MeasurementEffect):
    """An unrecorded drift of the reference during the cooling curves."""

    name = "reference-drift"
    summary = "the reference drifts during the cooling curves, unrecorded"
    params = {"rate_k_per_s": Param("K/s", 0.0, -1e6, 1e6, "drift of the reference")}
    traits = Traits(frozenset({COOLING}), catalogued=False,
                    confusable_with={"phase-change": "the reference's temperature recorded "
                                     "with every reading (a tref_c column)"})
    stage = 2

    def read(self, form: str, p: Mapping[str, NDArray], obs: Observation,
             values: NDArray) -> NDArray:
        return values + p["rate_k_per_s"] * obs.x[None, :] if obs.kind == COOLING else values

    def guess(self, form: str, fixed: Mapping[str, float],
              evidence: Evidence) -> Sequence[Mapping[str, float]]:
        t = np.concatenate([c.t_s for c in evidence.cooling] or [np.zeros(0)])
        r = np.concatenate([c.residual_k for c in evidence.cooling] or [np.zeros(0)])
        if t.size < 2 or not np.any(t):
            return ()
        return ({"rate_k_per_s": float(np.dot(t, r) / np.dot(t, t))},)

    def describe(self, effect: Effect) -> str:
        return f"the reference drifts {effect.params['rate_k_per_s']:.3g} K/s during the curves"
