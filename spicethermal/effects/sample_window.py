"""``sample-window`` (measurement): power is interrupted before each PWM temperature sample.

Form ``end``: the PWM reading is the junction temperature at the end of a power-off window of
``window_s`` that starts when an on-phase ends. Form ``average``: the reading is the mean
junction temperature over that window (an integrating converter). The bundle declares the
window it used (``sample_window_s``); the effect is a window other than the declared one.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np

from .base import PWM, Evidence, MeasurementEffect, Observation, Param, Traits

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

    from .base import Effect

#: The window's mean is Gauss–Legendre on these sub-spans (fractions of the window, log
#: spaced: the fast stages decay at its start), 4 nodes each.
SPANS = (0.0, 1e-3, 1e-2, 1e-1, 1.0)
_NODES, _WEIGHTS = np.polynomial.legendre.leggauss(4)


class SampleWindow(MeasurementEffect):
    """The PWM readings are taken after (or over) a power-off window."""

    name = "sample-window"
    summary = "power is interrupted for a window before each PWM temperature sample"
    forms = ("end", "average")
    params = {"window_s": Param("s", 1e-4, 0.0, 1.0, "length of the power-off sample window",
                                log=True)}
    traits = Traits(frozenset({PWM}), cost=1.0,
                    confusable_with={
                        "temperature-coefficient": "a PWM grid at two powers",
                        # a transient decays like a fast stage: a ladder whose fast stages
                        # fit the PWM readings, with a transient hiding them in the cooling
                        # curves, reads like a wrong window
                        "electrical-transient": "the steady reading just before each cut "
                        "(a transient makes the first cooling readings jump from it, a window "
                        "does not), or the PWM sample window measured at the bench"})
    stage = 0

    def read(self, form: str, p: Mapping[str, NDArray], obs: Observation,
             values: NDArray) -> NDArray:
        if obs.kind != PWM or obs.after_off is None:
            return values
        w = p["window_s"]
        if form == "end":
            return obs.after_off(w)
        total = 0.0
        for a, b in zip(SPANS[:-1], SPANS[1:], strict=True):
            for x, wt in zip(_NODES, _WEIGHTS, strict=True):
                at = w * (a + 0.5 * (b - a) * (x + 1))
                total = total + 0.5 * (b - a) * wt * obs.after_off(at)
        return total

    def guess(self, form: str, fixed: Mapping[str, float],
              evidence: Evidence) -> Sequence[Mapping[str, float]]:
        if evidence.pwm is None:
            return ()
        freq = evidence.pwm[0]
        w0 = evidence.declared_window_s
        if w0 <= 0:
            w0 = max(min(evidence.tau_s, default=1e-5), 1e-9)
        top = 0.5 / float(np.max(freq))
        return tuple({"window_s": float(w)} for w in sorted({w0 * 3, w0 / 3, max(top, w0)}))

    def describe(self, effect: Effect) -> str:
        w = effect.params["window_s"]
        how = "at the end of" if effect.form == "end" else "averaged over"
        return f"PWM readings taken {how} a {w * 1e6:.3g} µs power-off window"
