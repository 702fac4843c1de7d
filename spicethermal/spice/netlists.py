"""The example models and test benches kept in ``netlists/`` as golden files.

``python -m spicethermal.spice.netlists`` regenerates them; the tests regenerate them in memory and
diff against the files, so any change in the export format is seen and reviewed.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from .. import __version__
from ..core.ladder import Foster
from ..data import path as data_path
from ..engines.circuit import CircuitPwm
from ..io.files import atomic_write_text
from ..io.vendor import import_model
from ..model import ThermalModel
from .electrothermal import render_electrothermal
from .lib import (
    DIALECTS,
    TOPOLOGIES,
    Pins,
    Pulse,
    environment,
    initial_conditions,
    render_bench,
    render_lib,
)

#: The vendor network of the README's "Using the model in your circuit" example.
VENDOR_EXAMPLE = ("vendor/infineon_optimos3_80v_thermal.lib", "IPB019N08N3")
#: Its heatsink (base capacity J/K, resistance to ambient K/W), ambient and drive.
HEATSINK_EXAMPLE = {"heatsink_c": 2.0, "heatsink_r": 1.0, "ambient_c": 25.0, "power_w": 20.0,
                    "on_s": 1.0, "tstop_s": 10.0, "tmax_s": 1e-3}


#: The model file of the example with device effects (kept beside the golden files it makes).
EFFECTS_EXAMPLE = Path(__file__).resolve().parents[2] / "netlists" / \
    "actuator_effects.model.json"
#: The paper-like actuator with the simulated bench's heater diode (its Vf(I, T)): the
#: electrothermal part and the bench circuit around it.
HEATER_EXAMPLE = EFFECTS_EXAMPLE.with_name("actuator_heater.model.json")
#: The bench circuit's operating point (the paper's Table 2 conditions at 1 kHz, 50 %).
CIRCUIT_EXAMPLE = {"power_w": 0.094, "freq_hz": 1e3, "duty": 0.5, "window_s": 1e-4}


def golden_models() -> dict[str, ThermalModel]:
    """The paper-like actuator (linear) and the same with device effects, read from
    ``netlists/actuator_effects.model.json``: a temperature coefficient and its cavity's
    methanol, a latent-heat band at layer 2 (so its ``.lib`` files are Cauer ladders only: a
    Foster network has no such layer)."""
    actuator = ThermalModel(Foster.from_tau([6.0, 20.0, 50.0, 70.0], [1e-4, 5e-3, 0.4, 30.0]),
                            provenance={"source": "example: paper-like actuator, Rth 146 K/W"})
    return {"actuator": actuator, "actuator_effects": ThermalModel.load(EFFECTS_EXAMPLE)}


def _lib(key: str, dialect: str, topology: str) -> Callable[[], str]:
    name = key.upper()
    return lambda: render_lib(golden_models()[key], dialect, topology, name,
                              f"{key}_{dialect}_{topology}.lib")


def _pwm_bench() -> str:
    model = golden_models()["actuator"].with_topology("cauer")
    freq, duty, power, tref = 1e3, 0.5, 0.094, 25.0
    x0 = model.pwm_initial_state(power, freq, duty)
    ic = [(n, round(v, 9)) for n, v in initial_conditions(model, x0, tref)]
    return render_bench("actuator_ngspice_cauer.lib", "ACTUATOR", power_w=power, tstop_s=3e-3,
                        tmax_s=5e-6, tref_c=tref, pulse=Pulse.of(freq, duty), ic=ic,
                        title="actuator, 1 kHz 50 % PWM from the periodic steady state",
                        description="run: ngspice actuator_pwm_1khz.cir")


def heater_model() -> ThermalModel:
    """The paper-like actuator with the simulated bench's heater diode (``electrical``)."""
    return ThermalModel.load(HEATER_EXAMPLE)


def _heater_lib(dialect: str) -> Callable[[], str]:
    return lambda: render_electrothermal(heater_model(), dialect, "cauer", "HEATER",
                                         f"actuator_heater_{dialect}.lib", temperature="rise")


def _circuit_deck() -> str:
    c = CIRCUIT_EXAMPLE
    text, _, _ = CircuitPwm(heater_model().with_topology("cauer")).netlist(
        "actuator_heater_ngspice.lib", c["power_w"], c["freq_hz"], c["duty"], c["window_s"])
    return text


def vendor_model() -> ThermalModel:
    """The README example's vendor network, imported from the shipped excerpt."""
    return import_model(data_path(VENDOR_EXAMPLE[0]), VENDOR_EXAMPLE[1])


def _vendor_lib() -> str:
    return render_lib(vendor_model(), "ngspice", "cauer", filename=f"{VENDOR_EXAMPLE[1]}.lib",
                      pins=Pins.parse("Tj,Tcase"), temperature="absolute")


def _heatsink_deck() -> str:
    return environment().get_template("bench/coupled.cir.j2").render(
        name=VENDOR_EXAMPLE[1], lib_path=f"{VENDOR_EXAMPLE[1]}.lib", pins=["Tj", "Tcase"],
        version=__version__, **HEATSINK_EXAMPLE)


GOLDEN: dict[str, Callable[[], str]] = {
    **{f"actuator_{d}_{t}.lib": _lib("actuator", d, t) for d in DIALECTS for t in TOPOLOGIES},
    **{f"actuator_effects_{d}_cauer.lib": _lib("actuator_effects", d, "cauer")
       for d in DIALECTS},
    "actuator_pwm_1khz.cir": _pwm_bench,
    f"{VENDOR_EXAMPLE[1]}.lib": _vendor_lib,
    f"{VENDOR_EXAMPLE[1]}_heatsink.cir": _heatsink_deck,
    **{f"actuator_heater_{d}.lib": _heater_lib(d) for d in DIALECTS},
    "actuator_fig3_bench.cir": _circuit_deck,
}


def write_all(directory: Path) -> list[Path]:
    directory.mkdir(parents=True, exist_ok=True)
    out = []
    for name, make in GOLDEN.items():
        path = directory / name
        atomic_write_text(path, make())
        out.append(path)
    return out


if __name__ == "__main__":  # pragma: no cover
    for p in write_all(Path(__file__).resolve().parents[2] / "netlists"):
        print(p)
