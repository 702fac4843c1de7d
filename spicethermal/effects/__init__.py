"""The catalogue of physical effects and measurement artefacts: a registry of plugins.

Every effect is one module: its :class:`EffectSpec` (name, kind, parameters with units and
bounds, the forms it takes, and its device physics hooks) registered with :func:`register`.
The built-in effects below register themselves on import; third-party packages register
theirs through the entry-point group ``spicethermal.effects`` (each entry point names a
module or an :class:`EffectSpec`), loaded the first time the catalogue is read.

>>> known_names()[:2]
['electrical-transient', 'phase-change']
>>> Effect.create("tsp-nonlinearity", quad_k_per_k2=1e-4).form
'quadratic'
"""

from . import (  # built-in effects register themselves on import
    electrical_transient,
    phase_change,
    sample_window,
    temperature_coefficient,
    tsp_nonlinearity,
)
from .catalogue import (
    CATALOGUE,
    DEVICE,
    ENTRY_POINT_GROUP,
    MEASUREMENT,
    Effect,
    EffectSpec,
    Param,
    known_names,
    register,
    spec,
)

__all__ = ["CATALOGUE", "DEVICE", "ENTRY_POINT_GROUP", "MEASUREMENT", "Effect", "EffectSpec",
           "Param", "electrical_transient", "known_names", "phase_change", "register",
           "sample_window", "spec", "temperature_coefficient", "tsp_nonlinearity"]
