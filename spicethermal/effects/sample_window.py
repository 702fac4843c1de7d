"""``sample-window`` (measurement): power is interrupted before each PWM temperature sample.

Form ``end``: the PWM reading is the junction temperature at the end of a power-off window of
``window_s`` that starts when an on-phase ends (``ThermalModel.pwm(window_s=)``). Form
``average``: the reading is the mean junction temperature over that window (an integrating
converter).
"""

from __future__ import annotations

from .catalogue import MEASUREMENT, EffectSpec, Param, register

SPEC = register(EffectSpec(
    "sample-window", MEASUREMENT,
    "power is interrupted for a window before each PWM temperature sample",
    {"window_s": Param("s", 1e-4, 0.0, 1.0, "length of the power-off sample window")},
    ("end", "average"), fit="spicethermal.fit.measfit:fit_sample_window"))
