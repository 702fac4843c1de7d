"""The example models and test benches kept in ``netlists/`` as golden files.

``python -m spicethermal.netlists`` regenerates them; the tests regenerate them in memory and
diff against the files, so any change in the export format is seen and reviewed.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from .effects import Effect
from .files import atomic_write_text
from .ladder import Foster
from .model import ThermalModel
from .spice import DIALECTS, TOPOLOGIES, Pulse, initial_conditions, render_bench, render_lib


def golden_models() -> dict[str, ThermalModel]:
    """The paper-like actuator (linear) and the same with device effects."""
    actuator = ThermalModel(Foster.from_tau([6.0, 20.0, 50.0, 70.0], [1e-4, 5e-3, 0.4, 30.0]),
                            provenance={"source": "example: paper-like actuator, Rth 146 K/W"})
    effects = actuator.with_effects([
        Effect.create("temperature-coefficient", alpha_per_k=-3e-3, t0_c=25.0),
        Effect.create("phase-change", t_c=64.7, width_k=2.0, latent_j=0.05, node=2)])
    return {"actuator": actuator, "actuator_effects": effects}


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


GOLDEN: dict[str, Callable[[], str]] = {
    **{f"{k}_{d}_{t}.lib": _lib(k, d, t) for k in ("actuator", "actuator_effects")
       for d in DIALECTS for t in TOPOLOGIES},
    "actuator_pwm_1khz.cir": _pwm_bench,
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
    for p in write_all(Path(__file__).resolve().parent.parent / "netlists"):
        print(p)
