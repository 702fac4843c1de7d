"""spicethermal: thermal measurements of heated devices to RC ladder models for SPICE.

The objects and functions a user calls are listed in ``__all__`` and loaded lazily:
``import spicethermal`` stays light (numpy only); plotting, SPICE, serial and templates are
imported when first used.

Examples
--------
>>> import spicethermal as st
>>> ladder = st.Foster.from_tau([6.0, 20.0, 50.0, 70.0], [1e-4, 5e-3, 0.4, 30.0])
>>> round(ladder.rth, 6)
146.0
>>> round(st.steady_state(ladder, 0.094, 1e3, 0.5).mean_k, 3)   # 94 mW, 1 kHz, 50 %
6.862
"""

from __future__ import annotations

import importlib
from typing import Any

__version__ = "0.1.0"

#: public name -> module that defines it (relative to the package)
_API: dict[str, str] = {
    # curves and ladders
    "ZthCurve": "identify.curves",
    "Foster": "core.ladder",
    "Cauer": "core.ladder",
    # models and simulation
    "ThermalModel": "model",
    "Schedule": "model",
    "steady_state": "engines.pwm",
    "pwm_state": "engines.pwmsim",
    "simulator": "spice.lib",
    # measurements
    "Bundle": "io.bundle",
    "Calibration": "identify.calibration",
    "read_pyrth": "identify.records",
    "read_t3ster": "identify.records",
    "read_zth_points": "identify.datasheet",
    "read_foster_table": "io.datasheet",
    "read_source": "identify.sources",
    "import_model": "io.vendor",
    "read_library": "io.vendor",
    "PowerProfile": "predict",
    "predict": "predict",
    # fitting, comparison, diagnosis
    "fit_foster": "fit.ladder",
    "fit_model": "fit.ladder",
    "FitResult": "fit.ladder",
    "compare": "analysis.compare",
    "Comparison": "analysis.compare",
    "diagnose": "analysis.diagnose",
    "diagnose_table": "analysis.table2",
    "Diagnosis": "analysis.diagnosis",
    "fit_with_effects": "analysis.diagnose",
    "DiodeLaw": "core.diode",
    "fit_diode": "fit.diode",
    "table1": "identify.datasheet",
    "time_constant_spectrum": "identify.spectrum",
    "structure_function": "identify.structure",
    # SPICE
    "render_lib": "spice.lib",
    "export": "spice.lib",
    "render_electrothermal": "spice.electrothermal",
    "CircuitPwm": "engines.circuit",
    # effects
    "Effect": "effects",
    "DeviceEffect": "effects",
    "MeasurementEffect": "effects",
    "Param": "effects",
    "Traits": "effects",
    "register_effect": "effects",
    "known_effects": "effects",
    # many devices
    "run_batch": "batch.runner",
    # drive
    "optimize_drive": "drive.optimize",
    # errors
    "SpiceThermalError": "core.errors",
    "DataFormatError": "core.errors",
    "FitError": "core.errors",
    "InstrumentError": "core.errors",
    "SimulationError": "core.errors",
}

#: names whose attribute in the defining module differs from the public name
_ALIASES: dict[str, str] = {"known_effects": "known_names", "register_effect": "register"}

__all__ = sorted(_API) + ["__version__"]


def __getattr__(name: str) -> Any:
    """Load a public object on first use (PEP 562)."""
    module = _API.get(name)
    if module is None:
        raise AttributeError(f"module 'spicethermal' has no attribute {name!r}")
    value = getattr(importlib.import_module(f".{module}", __name__), _ALIASES.get(name, name))
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
