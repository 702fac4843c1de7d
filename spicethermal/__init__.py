"""spicethermal: thermal measurements of heated devices to RC ladder models for SPICE.

``import spicethermal`` stays light: numpy only. Plotting, SPICE, serial and templates are
imported when used.
"""

from __future__ import annotations

__version__ = "0.1.0"

from .errors import (  # noqa: E402
    DataFormatError,
    FitError,
    InstrumentError,
    SimulationError,
    SpiceThermalError,
)
from .ladder import Cauer, Foster  # noqa: E402

__all__ = [
    "Cauer",
    "DataFormatError",
    "FitError",
    "Foster",
    "InstrumentError",
    "SimulationError",
    "SpiceThermalError",
    "__version__",
]
