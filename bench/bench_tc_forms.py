"""Speed and accuracy of the temperature-coefficient forms' cooling model (issue 14).

One cooling curve (200 points, 1 µs to the bench's last time) of each validation device with
a strong ``local``, ``power-law`` and ``quadratic`` form: the CPU time of the network
simulator's cooling curve as the fits evaluate it
(:meth:`spicethermal.engines.network.NetworkBatch.cooling`: exponential steps on the network
frozen at each step's temperatures) and its largest difference
from the independent validation network (:mod:`spicethermal.validation.network`, integrated at
tight tolerance).

Run: ``.venv/bin/python bench/bench_tc_forms.py``
"""

from __future__ import annotations

import time

import numpy as np

from spicethermal.core.ladder import Cauer
from spicethermal.effects import Effect
from spicethermal.engines.network import NetworkBatch
from spicethermal.validation.cases import DEVICES
from spicethermal.validation.network import ResistanceLaw


def measure() -> tuple[float, float]:
    """(median CPU time per curve in s, largest difference in K) over devices and forms."""
    times, errors = [], []
    for dev in DEVICES.values():
        cauer, power = Cauer(dev.r_k_per_w, dev.c_j_per_k), dev.top_power_w
        t = np.logspace(-6, np.log10(dev.bench.t_max_s), 200)
        cases = ((Effect.create("temperature-coefficient", "local", alpha_per_k=6e-3),
                  {"laws": (ResistanceLaw("linear", 6e-3),) * 4}),
                 (Effect.create("temperature-coefficient", "power-law", exponent=2.5,
                                c_slope_per_k=3e-3),
                  {"laws": (ResistanceLaw("power", exponent=2.5),) * 4,
                   "c_slope_per_k": (3e-3,) * 4}),
                 (Effect.create("temperature-coefficient", "quadratic", alpha_per_k=6e-3,
                                curvature_per_k2=-4e-5),
                  {"laws": (ResistanceLaw("quadratic", 6e-3, beta_per_k2=-4e-5),) * 4}))
        for effect, changes in cases:
            c0 = time.process_time()
            for _ in range(3):
                fast = NetworkBatch.of(cauer, (effect,)).cooling(power, 25.0, t)[0]
            times.append((time.process_time() - c0) / 3)
            net = dev.network(**changes)
            _, path = net.integrate(net.steady(power, 25.0), t[-1], 0.0, 25.0, t_eval=t,
                                    rtol=1e-10)
            errors.append(float(np.max(np.abs(fast - (path[:, 0] - 25.0)))))
    return float(np.median(times)), max(errors)


def summary() -> list[tuple[str, str, str, str]]:
    """The row of bench/README.md's table."""
    cpu, err = measure()
    return [("temperature-coefficient local/power-law/quadratic cooling curve, 200 points (CPU per "
             "curve; worst difference from the validation network)", "— (no local forms)",
             f"{cpu * 1e3:.0f} ms; {err * 1e3:.2f} mK", "≤ 100 ms; ≤ 2 mK")]


if __name__ == "__main__":
    for row in summary():
        print(" | ".join(row))
