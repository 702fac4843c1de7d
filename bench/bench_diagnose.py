"""Diagnosis of the shipped data: the sample bundle (the README's step 5) and the paper's Table 2.

Plain script (not a test): ``.venv/bin/python bench/bench_diagnose.py [RUNS]``. For the sample
bundle: the verdict, the RMS staircase, and the time per diagnosis (wall and CPU, the process's
own, median of ``RUNS``, default 3), with the work counted by the diagnosis (model
evaluations), which is the same on every machine. Verdicts on physics the project was not built
from are scored by ``bench/bench_validation.py``.
"""

from __future__ import annotations

import statistics
import sys
import time

from spicethermal.analysis.diagnose import diagnose
from spicethermal.analysis.table2 import diagnose_table
from spicethermal.data import path
from spicethermal.io.bundle import Bundle


def sample(runs: int) -> dict:
    """The sample bundle's diagnosis, timed ``runs`` times."""
    bundle = Bundle.read(path("sample_bundle/bundle.json").parent)
    wall, cpu = [], []
    for _ in range(runs):
        t0, c0 = time.perf_counter(), time.process_time()
        d = diagnose(bundle)
        wall.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    return {"diagnosis": d, "wall": statistics.median(wall), "cpu": statistics.median(cpu)}


def summary(runs: int = 3) -> list[tuple[str, str, str, str]]:
    """The row of bench/README.md's table."""
    s = sample(runs)
    d = s["diagnosis"]
    return [("`diagnose` on the shipped sample bundle (README step 5): verdict, RMS staircase, "
             "CPU per diagnosis", "—",
             f"{d.verdict.cls} {', '.join(d.verdict.effects) or '(nothing)'}; "
             f"{d.staircase()}; {s['cpu']:.1f} s CPU ({d.work} model evaluations)",
             "names the calibration's bow; CPU ≤ 5 s")]


def main() -> None:
    runs = int(sys.argv[1]) if len(sys.argv) > 1 else 3
    s = sample(runs)
    d = s["diagnosis"]
    print(f"sample bundle: {d.verdict.cls} {', '.join(d.verdict.effects) or '(nothing)'}")
    print(f"  {d.verdict.reason}")
    print(f"  {d.staircase()}")
    print(f"  time per diagnosis (median of {runs}): {s['wall']:.2f} s wall, {s['cpu']:.2f} s "
          f"CPU; {d.work} model evaluations")
    t0 = time.perf_counter()
    table = diagnose_table(path("actuator_table2.csv"))
    print(f"\nthe paper's Table 2 ({time.perf_counter() - t0:.2f} s):")
    print(table)


if __name__ == "__main__":
    main()
