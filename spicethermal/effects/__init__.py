"""The catalogue of physical effects and measurement artefacts: typed plugins in a registry.

Every effect is one class in one module (:mod:`spicethermal.effects.base` says what it owns),
registered through the entry-point group ``spicethermal.effects``, the built-in ones in the
package's own ``pyproject.toml`` as a third-party package declares its own. *Rivals* are
plugins too: explanations outside the catalogue (a heating power other than the recorded one,
a drifting reference) that the diagnosis weighs and never names.

>>> known_names()[:2]
['electrical-transient', 'phase-change']
>>> Effect.create("tsp-nonlinearity", quad_k_per_k2=1e-4).form
'quadratic'
"""

from .base import (
    CALIBRATION,
    COOLING,
    DEVICE,
    KINDS,
    MEASUREMENT,
    PWM,
    STEADY,
    DeviceEffect,
    EffectPlugin,
    Evidence,
    MeasurementEffect,
    Observation,
    Param,
    Traits,
)
from .registry import (
    CATALOGUE,
    ENTRY_POINT_GROUP,
    Effect,
    known_names,
    plugin,
    register,
    rival_names,
)

__all__ = ["CALIBRATION", "CATALOGUE", "COOLING", "DEVICE", "ENTRY_POINT_GROUP", "KINDS",
           "MEASUREMENT", "PWM", "STEADY", "DeviceEffect", "Effect", "EffectPlugin", "Evidence",
           "MeasurementEffect", "Observation", "Param", "Traits", "known_names", "plugin",
           "register", "rival_names"]
