"""``electrical-transient`` (measurement): the first readings after the cut are wrong.

A cooling reading at ``t`` after the cut is off by

* form ``fixed``: ``amplitude_k · exp(−5 t / masked_s)``;
* form ``power``: ``k_per_w · P · exp(−5 t / masked_s)``, proportional to the power ``P``
  before the cut (an artefact of the current switched off);
* form ``ringing``: ``amplitude_k · exp(−5 t / masked_s) · cos(2π ring_hz t)``, a damped
  ringing.

``masked_s`` is the span after which the error has fallen below 1 % (e⁻⁵); the fix is masking
and √t extrapolation (:mod:`spicethermal.identify.curves`).
"""

from __future__ import annotations

from .catalogue import MEASUREMENT, EffectSpec, Param, register

SPEC = register(EffectSpec(
    "electrical-transient", MEASUREMENT,
    "the electrical transient after power cut-off masks the first part of a cooling curve",
    {"masked_s": Param("s", 1e-4, 0.0, 1.0, "span after the cut during which readings are wrong"),
     "amplitude_k": Param("K", 0.0, -1e3, 1e3, "error of the reading at the cut, decaying over"
                          " the masked span (forms fixed, ringing)"),
     "k_per_w": Param("K/W", 0.0, -1e4, 1e4, "error at the cut per watt cut off (form power)"),
     "ring_hz": Param("Hz", 0.0, 0.0, 1e9, "ringing frequency (form ringing)")},
    ("fixed", "power", "ringing"), fit="spicethermal.fit.measfit:fit_electrical_transient"))
