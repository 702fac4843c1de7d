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
#: A ringing's starts come from a scan of the first readings' residual: masked spans on a
#: log grid of this many points a decade ...
SCAN_PER_DECADE = 8
#: ... and frequencies of these many cycles over the masked span (a ringing may go through
#: many cycles before it dies; fewer than a quarter is no ringing) ...
SCAN_CYCLES = (0.25, 50.0)
#: ... on a log grid this fine (a thirtieth of a cycle of phase at the span's end at the top);
SCAN_STEP = 1.03
#: the best few distinct frequencies are the starts.
SCAN_STARTS = 3


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
        if form == "ringing":
            return _ringing_starts(curves, 2 * float(t[0]), 0.3 * float(t[-1]))
        starts = []
        for m in (masked, 3 * masked):
            amp = r0 * math.exp(min(RATE * float(t[0]) / m, 50.0))
            if form == "power":
                starts.append({"masked_s": m, "k_per_w": amp / max(worst.power_w, 1e-30)})
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


def _ringing_starts(curves: Sequence, lo: float, hi: float) -> list[dict[str, float]]:
    """Starts of a ringing: every masked span (log grid from ``lo`` to ``hi``) and frequency
    (:data:`SCAN_CYCLES` over the span) scanned at once, the amplitude of each by least
    squares on every curve's readings within its span; the best point of each of the
    :data:`SCAN_STARTS` best frequencies (at least a tenth apart) is a start. The first
    readings of a ringing are far too sparse for a guess from zero crossings.

    Parameters
    ----------
    curves : sequence of CurveEvidence
    lo, hi : float
        The range of masked spans (s).

    Returns
    -------
    list of dict
    """
    t = np.concatenate([c.t_s for c in curves])
    r = np.concatenate([c.residual_k for c in curves])
    if hi <= lo:
        hi = 2.0 * lo
    spans = np.geomspace(lo, hi, max(2, int(SCAN_PER_DECADE * math.log10(hi / lo)) + 1))
    cycles = np.exp(np.arange(math.log(SCAN_CYCLES[0]), math.log(SCAN_CYCLES[1]),
                              math.log(SCAN_STEP)))
    best: list[tuple[float, float, float, float]] = []  # gain, span, frequency, amplitude
    for m in spans:
        near = t <= m
        if np.count_nonzero(near) < 3:
            continue
        tt, rr = t[near], r[near]
        f = cycles[:, None] / m
        basis = np.exp(-RATE * tt / m)[None, :] * np.cos(2 * math.pi * f * tt[None, :])
        bb = np.einsum("ij,ij->i", basis, basis)
        rb = basis @ rr
        gain = np.where(bb > 0, rb * rb / np.maximum(bb, 1e-300), 0.0)
        best += [(float(g), float(m), float(fi), float(a)) for g, fi, a in
                 zip(gain, f[:, 0], rb / np.maximum(bb, 1e-300), strict=True)]
    starts: list[dict[str, float]] = []
    for _g, m, f, a in sorted(best, key=lambda x: -x[0]):
        if any(abs(f / s["ring_hz"] - 1.0) < 0.1 for s in starts):
            continue
        starts.append({"masked_s": m, "amplitude_k": a, "ring_hz": f})
        if len(starts) == SCAN_STARTS:
            break
    return starts
