"""Safe fast drive on the paper-like actuator: speed-up, junction peak (exact and ngspice), runtime.

Run: ``.venv/bin/python bench/bench_drive.py`` (plain script; needs ngspice for the last
columns). For each PWM frequency and actuation node it prints the time to target of the
optimized drive and of the constant hold duty, the speed-up, the predicted (exact switched)
junction peak, the peak of the same schedule switched in ngspice, how far the averaged +
ripple limit had to be tightened (the averaging approximation), and the optimizer's runtime.
"""

from __future__ import annotations

import shutil
import time

from spicethermal.core.ladder import Foster
from spicethermal.drive.check import verify
from spicethermal.drive.optimize import optimize_drive
from spicethermal.model import ThermalModel

R = (6.0, 20.0, 50.0, 70.0)
TAU = (2e-4, 5e-3, 0.4, 12.0)
CASES = [  # (node, target °C, t_max °C, p_max W, f_pwm Hz)
    (0, 60.0, 90.0, 1.0, 1e3),
    (2, 60.0, 90.0, 1.0, 1e3),
    (2, 60.0, 90.0, 2.0, 1e3),
    (2, 60.0, 90.0, 2.0, 5e3),
    (2, 60.0, 90.0, 2.0, 25e3),
    (3, 50.0, 90.0, 2.0, 1e3),
]


def main() -> None:
    model = ThermalModel(Foster.from_tau(R, TAU))
    spice = shutil.which("ngspice") is not None
    print(f"{'node':>4} {'f (Hz)':>7} {'P (W)':>5} {'t_drive (s)':>11} {'t_const (s)':>11} "
          f"{'speed-up':>8} {'Tj peak':>8} {'ngspice':>8} {'margin K':>8} {'opt (s)':>7} "
          f"{'spice (s)':>9}")
    for node, target, t_max, p, f in CASES:
        t0 = time.perf_counter()
        r = optimize_drive(model, t_max, target, 25.0, p_max_w=p, f_pwm_hz=f, node=node)
        t_opt = time.perf_counter() - t0
        ng, t_sp = float("nan"), float("nan")
        if spice:
            t0 = time.perf_counter()
            ng = verify(r)["ngspice_peak_junction_c"]  # in parallel pieces, as drive --verify
            t_sp = time.perf_counter() - t0
        print(f"{node:4d} {f:7g} {p:5g} {r.time_to_target_s:11.4g} "
              f"{r.constant_duty_time_to_target_s:11.4g} {r.speedup:8.1f} "
              f"{r.peak_junction_c:8.3f} {ng:8.3f} {r.ripple_margin_k:8.3f} {t_opt:7.2f} "
              f"{t_sp:9.2f}")


if __name__ == "__main__":
    main()
