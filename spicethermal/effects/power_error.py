"""``power-error`` (rival, not catalogued): the heat delivered is not the power recorded.

A heater whose resistance, or a diode whose forward voltage, changes as it warms delivers a
power other than the nominal one recorded in the bundle; so does a supply that sags. The
rival is the simplest law of that kind, a delivered power ``P / (1 + γ P)``: every rise over
the reference scales by ``1 / (1 + γ P)`` at its own power, and the shape of each cooling
curve is the linear ladder's. The diagnosis weighs it beside the catalogued effects and never
names it: a temperature coefficient whose time warp the cooling curves do not show is told
from it only by measuring the power at the cut.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np

from .base import COOLING, PWM, STEADY, Evidence, MeasurementEffect, Observation, Param, Traits

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

    from .base import Effect


class PowerError(MeasurementEffect):
    """The delivered power departs from the recorded one in proportion to it."""

    name = "power-error"
    summary = "the power delivered departs from the power recorded (a heater that sags)"
    params = {"gamma_per_w": Param("1/W", 0.0, -1e6, 1e6, "delivered power P/(1 + γP)")}
    traits = Traits(frozenset({COOLING, STEADY, PWM}), catalogued=False,
                    confusable_with={"temperature-coefficient": "the power measured at the "
                                     "cut (a coefficient also warps the cooling in time)"})
    stage = 0.5

    def read(self, form: str, p: Mapping[str, NDArray], obs: Observation,
             values: NDArray) -> NDArray:
        if obs.kind not in (COOLING, STEADY, PWM):
            return values
        tref = obs.tref_c[None, :]
        return tref + (values - tref) / (1.0 + p["gamma_per_w"] * obs.power_w[None, :])

    def guess(self, form: str, fixed: Mapping[str, float],
              evidence: Evidence) -> Sequence[Mapping[str, float]]:
        xs, ys = [], []
        for c in evidence.cooling:
            rise = float(c.model_c[0] - c.tref_c)
            if rise:
                xs.append(c.power_w)
                ys.append(rise / float(c.reading_c[0] - c.tref_c) - 1.0)
        if len(xs) >= 2 and np.ptp(xs) > 0:
            g = float(np.polyfit(xs, ys, 1)[0])
        else:
            top = max((c.power_w for c in evidence.cooling), default=1.0)
            g = 1e-3 / max(top, 1e-30)
        return ({"gamma_per_w": g}, {"gamma_per_w": -g})

    def describe(self, effect: Effect) -> str:
        return (f"the power delivered is P/(1 + {effect.params['gamma_per_w']:.3g}/W·P) of "
                f"the power P recorded")
