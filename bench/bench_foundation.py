"""Foundation benchmark: exactness of Foster<->Cauer, ngspice accuracy per dialect/topology,
analytic PWM against brute force, and their speed. Run: .venv/bin/python bench/bench_foundation.py
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))

from conftest import ACTUATOR_R, ACTUATOR_TAU, ramp_response  # noqa: E402
from test_pwm import brute_force  # noqa: E402

from spicethermal.core.ladder import Foster  # noqa: E402
from spicethermal.engines import pwm
from spicethermal.model import ThermalModel  # noqa: E402
from spicethermal.spice import lib as spice  # noqa: E402


def round_trip(cases_per_order: int = 5) -> None:
    print("Foster -> Cauer -> Foster, time constants over 8 decades")
    print(f"{'order':>5} {'max rel err R':>14} {'max rel err tau':>16} {'F->C s':>8} {'C->F s':>8}")
    for order in range(1, 21):
        er = et = 0.0
        tfc = tcf = 0.0
        for k in range(cases_per_order):
            rng = np.random.default_rng(1000 * order + k)
            tau = (np.logspace(-5, 3, order) * rng.uniform(0.7, 1.3, order)
                   if order > 1 else np.array([1e-2]))
            f = Foster.from_tau(rng.uniform(0.05, 20.0, order), tau)
            t0 = time.perf_counter()
            c = f.to_cauer()
            t1 = time.perf_counter()
            b = Foster.from_cauer(type(c)(c.r, c.c))  # fresh object: no cached Foster form
            t2 = time.perf_counter()
            er = max(er, np.max(np.abs(np.subtract(b.r, f.r)) / f.r))
            et = max(et, np.max(np.abs(np.subtract(b.tau, f.tau)) / f.tau))
            tfc, tcf = tfc + t1 - t0, tcf + t2 - t1
        print(f"{order:>5} {er:>14.2e} {et:>16.2e} {tfc / cases_per_order:>8.3f} "
              f"{tcf / cases_per_order:>8.3f}")


def ngspice_accuracy() -> None:
    f = Foster.from_tau(ACTUATOR_R, ACTUATOR_TAU)
    model = ThermalModel(f)
    print("\nngspice step (1e-6..100 s) and 1 kHz/30 % PWM vs analytic, error in % of Rth")
    with tempfile.TemporaryDirectory() as tmp:
        for dialect in spice.DIALECTS:
            for topology in spice.TOPOLOGIES:
                m = model.with_topology(topology)
                lib = spice.export(m, Path(tmp) / "m.lib", dialect, topology, "ACT")
                t0 = time.perf_counter()
                w = spice.NgspiceBatch().run(
                    spice.render_bench(lib, "ACT", power_w=1.0, tstop_s=100.0, tmax_s=1.0),
                    ["V(TJ)"], dialect)
                dt = time.perf_counter() - t0
                sel = w.t_s >= 1e-6
                step = np.max(np.abs(w["V(TJ)"][sel] - ramp_response(f, w.t_s[sel], 1e-5)))
                x0 = m.pwm_initial_state(0.094, 1e3, 0.3)
                net = spice.render_bench(lib, "ACT", power_w=0.094, tstop_s=3e-3, tmax_s=5e-6,
                                         tref_c=25.0, pulse=spice.Pulse.of(1e3, 0.3),
                                         ic=spice.initial_conditions(m, x0, 25.0))
                w2 = spice.NgspiceBatch().run(net, ["V(TJ)"], dialect)
                pw = np.max(np.abs(w2["V(TJ)"] - 25.0 - pwm.at_phase(f, 0.094, 1e3, 0.3, w2.t_s)))
                print(f"  {dialect:8} {topology:7} step {100 * step / f.rth:.4f} %  "
                      f"pwm {100 * pw / f.rth:.5f} % ({pw * 1e3:.3f} mK)  step run {dt:.2f} s")


def pwm_vs_brute_force() -> None:
    f = Foster.from_tau([6.0, 20.0, 50.0], [1e-4, 5e-3, 0.05])
    worst = 0.0
    for freq in (200.0, 2e3, 1e4):
        for duty in (0.2, 0.5, 0.8):
            s = pwm.steady_state(f, 0.094, freq, duty, 1e-4)
            peak, valley, reading = brute_force(f, 0.094, freq, duty, 1e-4)
            worst = max(worst, abs(s.peak_k / peak - 1), abs(s.valley_k / valley - 1),
                        abs(s.reading_k / reading - 1))
    t0 = time.perf_counter()
    for _ in range(1000):
        pwm.steady_state(f, 0.094, 1e3, 0.5, 1e-4)
    per = (time.perf_counter() - t0) / 1000
    print(f"\nanalytic PWM vs brute-force stepping: worst relative difference {worst:.1e}; "
          f"{per * 1e6:.0f} µs per steady state")


if __name__ == "__main__":
    round_trip()
    ngspice_accuracy()
    pwm_vs_brute_force()
