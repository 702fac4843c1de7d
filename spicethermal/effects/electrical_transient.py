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

from .base import COOLING, CurveEvidence, Evidence, MeasurementEffect, Observation, Param, Traits

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

    from .base import Effect

#: The error decays as ``exp(−RATE · t / masked_s)``: 1 % is left after ``masked_s``.
RATE = 5.0
#: Starts come from a scan of the first readings' residual: masked spans on a log grid of
#: this many points a decade ...
SCAN_PER_DECADE = 8
#: ... each fitted over the readings up to twice the span, and at least this many of each
#: curve, beside an offset of its own (what the ladder so far misses there, about level
#: over a transient's span) ...
SCAN_READINGS = 6
#: ... and for a ringing, frequencies of these many cycles over the masked span (a ringing
#: may go through many cycles before it dies; fewer than a quarter is no ringing) ...
SCAN_CYCLES = (0.25, 50.0)
#: ... on a log grid this fine (a thirtieth of a cycle of phase at the span's end at the top).
SCAN_STEP = 1.03
#: The best distinct points are the starts: two spans at least this factor apart, or for a
#: ringing ...
SCAN_APART = 2.0
#: ... this many frequencies a tenth apart.
SCAN_STARTS = 3
#: A transient of the reading is over before the junction has given up this share of its rise
#: after the cut. Its fix, masking and a √t extrapolation of the readings after the mask back
#: to the cut (JESD51-14), holds only while the heat still spreads in the die, early in the
#: cooling; a fitted "transient" masking more hides the readings a Zth curve is built from,
#: where the device's own cooling (the ladder, or a device effect) can take its place.
MAX_MASKED_SHARE = 0.25


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
                                     "(a transient leaves it alone)"},
                    shown_alone_by="a cut from a small heating power (the switching "
                    "transient with little cooling)")
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
        t0 = min(float(c.t_s[0]) for c in curves)
        t1 = max(float(c.t_s[-1]) for c in curves)
        ringing = form == "ringing"
        cycles = (np.exp(np.arange(math.log(SCAN_CYCLES[0]), math.log(SCAN_CYCLES[1]),
                                   math.log(SCAN_STEP))) if ringing else np.zeros(1))
        weights = [c.power_w if form == "power" else 1.0 for c in curves]
        starts: list[dict[str, float]] = []
        hi = min(0.3 * t1, _longest_shown(curves))  # no start the data could not show
        for _gain, m, f, a in _scan(curves, weights, 2.0 * t0, hi, cycles):
            if ringing and any(abs(f / s["ring_hz"] - 1.0) < 0.1 for s in starts):
                continue
            if not ringing and any(max(m / s["masked_s"], s["masked_s"] / m) < SCAN_APART
                                   for s in starts):
                continue
            key = "k_per_w" if form == "power" else "amplitude_k"
            starts.append({"masked_s": m, key: a, **({"ring_hz": f} if ringing else {})})
            if len(starts) == (SCAN_STARTS if ringing else 2):
                break
        return starts

    def unshown(self, effect: Effect, evidence: Evidence) -> str:
        """A transient is shown only while the junction has given up less than
        :data:`MAX_MASKED_SHARE` of its rise (the largest share over the curves, from the
        model's junction temperature at the end of the masked span)."""
        masked = float(effect.params["masked_s"])
        share = max((_share_cooled(c, masked) for c in evidence.cooling), default=0.0)
        if not share > MAX_MASKED_SHARE:
            return ""
        return (f"it masks the first {masked * 1e6:.3g} µs after the cut, over which the "
                f"junction gives up {100 * share:.0f} % of its rise: the device's own cooling, "
                "not a transient of the reading that masking and √t extrapolation remove")

    def describe(self, effect: Effect) -> str:
        p = effect.params
        size = (f"{p['k_per_w']:.3g} K per watt cut off" if effect.form == "power" else
                f"{p['amplitude_k']:+.3g} K at the cut")
        ring = "" if effect.form != "ringing" else (
            f", ringing at {p['ring_hz']:.3g} Hz" if p["ring_hz"] * p["masked_s"]
            >= SCAN_CYCLES[0] else ", too slow to ring before it dies (under a quarter cycle)")
        return (f"cooling readings off by {size}{ring}, gone after "
                f"{p['masked_s'] * 1e6:.3g} µs")


def _shares(curve: CurveEvidence) -> NDArray | None:
    """The share of its rise above the reference that the model's junction has given up at
    each reading of ``curve`` (None without the model's path)."""
    rise = float(curve.nodes_c[0]) - curve.tref_c
    if curve.node_paths_c is None or curve.t_s.size == 0 or not rise > 0:
        return None
    return np.maximum(float(curve.nodes_c[0]) - curve.node_paths_c[:, 0], 0.0) / rise


def _share_cooled(curve: CurveEvidence, t_s: float) -> float:
    """:func:`_shares` ``t_s`` after the cut (0 without the path; before the first reading,
    that reading's share scaled as √t, the die's early cooling)."""
    shares = _shares(curve)
    if shares is None:
        return 0.0
    if t_s <= curve.t_s[0]:
        return float(shares[0]) * math.sqrt(t_s / curve.t_s[0])
    return float(np.interp(math.log(t_s), np.log(curve.t_s), shares))


def _longest_shown(curves: Sequence[CurveEvidence]) -> float:
    """The longest span a transient is shown over (:meth:`ElectricalTransient.unshown`): the
    first time after which some curve's junction has given up more than
    :data:`MAX_MASKED_SHARE` of its rise, read from its path as :func:`_share_cooled` reads it
    (infinite without the model's paths)."""
    ends = []
    for c in curves:
        s = _shares(c)
        if s is None or not np.any(s > MAX_MASKED_SHARE):
            continue
        i = int(np.argmax(s > MAX_MASKED_SHARE))
        if i == 0:  # before the first reading, its share scaled as √t
            ends.append(float(c.t_s[0]) * (MAX_MASKED_SHARE / float(s[0])) ** 2)
            continue
        lo, hi = np.log(c.t_s[i - 1:i + 1])
        ends.append(math.exp(lo + (MAX_MASKED_SHARE - s[i - 1]) / (s[i] - s[i - 1]) * (hi - lo)))
    return min(ends, default=math.inf)


def _scan(curves: Sequence, weights: Sequence[float], lo: float, hi: float,
          cycles: NDArray) -> list[tuple[float, float, float, float]]:
    """Every masked span ``m`` (log grid from ``lo`` to ``hi``) and frequency (``cycles``
    over the span; 0: no ringing) scanned at once: on each curve's readings up to
    ``2 m`` (at least :data:`SCAN_READINGS`), the error ``w_c · a · exp(−5t/m) cos(2πft)``
    (``w_c`` the curve's weight: 1, or its power for an error per watt) fitted by least squares
    beside an offset of each curve's own. Points are ranked by the t² of the amplitude (its
    fall of the sum of squares over what is left per degree of freedom): a long span that takes
    some of what the ladder misses over many readings is not a transient that leaves the
    readings after it at their noise.

    Returns
    -------
    list of (score, span, frequency, amplitude)
        Best first.
    """
    if hi <= lo:
        hi = 2.0 * lo
    spans = np.geomspace(lo, hi, max(2, int(SCAN_PER_DECADE * math.log10(hi / lo)) + 1))
    out: list[tuple[float, float, float, float]] = []
    for m in spans:
        freq = cycles / m
        num, den = np.zeros(freq.size), np.zeros(freq.size)
        sse, dof = 0.0, -1
        for c, w in zip(curves, weights, strict=True):
            n = max(int(np.searchsorted(c.t_s, 2.0 * m, side="right")), SCAN_READINGS)
            t, r = c.t_s[:n], c.residual_k[:n]
            g = np.exp(-RATE * t / m)[None, :] * np.cos(2 * math.pi * freq[:, None] * t)
            g = g - g.mean(axis=1, keepdims=True)  # what the offset cannot take
            r = r - r.mean()
            num += w * (g @ r)
            den += w * w * np.einsum("ij,ij->i", g, g)
            sse, dof = sse + float(r @ r), dof + t.size - 1
        if dof < 1:
            continue
        ok = den > 0
        gain = np.where(ok, num * num / np.where(ok, den, 1.0), 0.0)
        score = gain / np.maximum((sse - gain) / dof, 1e-12 * max(sse, 1e-300) / dof)
        amp = np.where(ok, num / np.where(ok, den, 1.0), 0.0)
        out += [(float(x), float(m), float(f), float(a)) for x, a, f
                in zip(score, amp, freq, strict=True)]
    return sorted(out, key=lambda x: -x[0])
