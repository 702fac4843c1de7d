"""Diagnosis study: time per bundle, verdicts over many seeds, noise sensitivity, Table 2.

Plain script (not a test): ``.venv/bin/python bench/bench_diagnose.py [SEEDS] [NOISE_SEEDS]``.
Times are wall-clock and CPU (the process's own: what a busy shared machine does not inflate).
The independent validation set (other forms, devices, pairs, uncatalogued effects) is scored by
``bench/bench_validation.py``.
Bundles come from :mod:`spicethermal.analysis.scenarios` with ``exact=True``: the device effects are
simulated by the :class:`~spicethermal.model.ThermalModel` integration (Radau, shooting), not
by the fast solutions the fits use, so the study is not an inverse crime.
"""

from __future__ import annotations

import statistics
import sys
import time
from pathlib import Path

from spicethermal.analysis.scenarios import SCENARIOS, expected_effect, scenario_bundle

from spicethermal.analysis.diagnose import diagnose, diagnose_table

ROOT = Path(__file__).resolve().parent.parent
TABLE2 = ROOT / "spicethermal" / "data" / "actuator_table2.csv"


def study(seeds: range, noise_k: float) -> dict[str, dict]:
    out = {}
    for name in SCENARIOS:
        ok, times, cpu, impr, found = 0, [], [], [], []
        for seed in seeds:
            b = scenario_bundle(name, seed=seed, noise_k=noise_k, exact=True)
            t0, c0 = time.perf_counter(), time.process_time()
            d = diagnose(b)
            times.append(time.perf_counter() - t0)
            cpu.append(time.process_time() - c0)
            want = expected_effect(name)
            ok += d.verdict_effect == want
            found.append(d.verdict_effect)
            if want is not None:
                impr.append(next(c.improvement for c in d.candidates if c.effect.name == want))
        out[name] = {"ok": ok, "n": len(seeds), "times": times, "cpu": cpu, "impr": impr,
                     "found": found}
    return out


def report(title: str, res: dict[str, dict]) -> None:
    print(f"\n{title}")
    print(f"{'scenario':24s} {'correct':>8s} {'time s (median/max)':>20s} "
          f"{'improvement of the true effect (min/median)':>44s}")
    for name, r in res.items():
        imp = (f"{min(r['impr']):8.1f}× / {statistics.median(r['impr']):6.1f}×"
               if r["impr"] else "-")
        wrong = {str(f) for f in r["found"] if f != expected_effect(name)}
        print(f"{name:24s} {r['ok']:3d}/{r['n']:<4d} {statistics.median(r['times']):9.2f} / "
              f"{max(r['times']):5.2f} {imp:>44s}" + (f"   wrong: {', '.join(wrong)}"
                                                      if wrong else ""))


def main() -> None:
    seeds = int(sys.argv[1]) if len(sys.argv) > 1 else 6
    noise_seeds = int(sys.argv[2]) if len(sys.argv) > 2 else 4
    t0 = time.perf_counter()
    for name in SCENARIOS:  # noise-free truth, generated once per scenario (cached)
        scenario_bundle(name, exact=True)
    print(f"exact truth for {len(SCENARIOS)} scenarios generated in "
          f"{time.perf_counter() - t0:.1f} s (Radau cooling curves, shooting PWM)")
    base = study(range(seeds), 0.02)
    report(f"verdicts, noise 0.02 K, {seeds} seeds per scenario", base)
    all_times = [t for r in base.values() for t in r["times"]]
    all_cpu = [t for r in base.values() for t in r["cpu"]]
    print(f"diagnose time per full bundle (197 points, 5 candidates): median "
          f"{statistics.median(all_times):.2f} s, max {max(all_times):.2f} s wall; CPU median "
          f"{statistics.median(all_cpu):.2f} s, max {max(all_cpu):.2f} s (target: median <= 5 s)")
    for noise in (0.05, 0.1):
        report(f"verdicts, noise {noise} K, {noise_seeds} seeds per scenario",
               study(range(100, 100 + noise_seeds), noise))
    if TABLE2.exists():
        t0 = time.perf_counter()
        d = diagnose_table(TABLE2)
        print(f"\nthe paper's Table 2 ({time.perf_counter() - t0:.2f} s):")
        print(d)


if __name__ == "__main__":
    main()
