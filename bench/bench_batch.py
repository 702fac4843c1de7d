"""Throughput of ``spicethermal batch`` with 1 and 2 Dask workers, and the outliers it finds in
a simulated population against the defects planted in it.

Run (prints the numbers; a few minutes on two free cores)::

    .venv/bin/python bench/bench_batch.py [N_DEVICES] [--effect NAME]...

The population (:mod:`spicethermal.batch.population`, seed 0): N devices (default 200) of a
4-layer part (die, die attach, base, interface; Rth 1.5 K/W) with 5 % log-normal spread of
every layer's R and C, and 3 % of them with a voided die attach (R × 2…4). Each device is
fitted (automatic order), diagnosed (every catalogued effect, unless ``--effect`` narrows the
candidates) and exported, on a local cluster of 1, then 2, single-threaded worker processes;
the cluster's start-up is timed apart.

Reported: devices per second and the speed-up of 2 workers over 1 (target ≥ 1.7×), the median
time per device on a worker, and for the 2-worker run the outliers found against the defects
planted (target: every defect found, with a reason that puts the extra resistance beyond the
die — the path departs from the population between the die's capacitance and the end of the
die attach — and no false alarm beyond the Rth test's expected 0.05 % per device).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import tempfile
import time
from pathlib import Path

from spicethermal.batch.device import Options
from spicethermal.batch.population import LAYERS, write_population
from spicethermal.batch.runner import cluster_client, run_batch
from spicethermal.batch.summary import summarize


def timed_run(pop: Path, out: Path, workers: int, options: Options) -> dict:
    load = os.getloadavg()[0]
    t0 = time.perf_counter()
    with cluster_client(workers=workers) as client:
        t1 = time.perf_counter()
        run = run_batch([pop], out, client=client, options=options)
        t2 = time.perf_counter()
    rows = run.rows
    return {"workers": workers, "startup_s": t1 - t0, "run_s": t2 - t1,
            "per_s": len(rows) / (t2 - t1),
            "device_s": statistics.median(r["wall_s"] for r in rows),
            "errors": sum(1 for r in rows if r["error"]), "run": run,
            "load": (load, os.getloadavg()[0])}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("n", type=int, nargs="?", default=200)
    parser.add_argument("--effect", action="append")
    args = parser.parse_args()
    options = Options(effects=tuple(args.effect) if args.effect else None)
    with tempfile.TemporaryDirectory() as tmp:
        pop = Path(tmp) / "pop"
        write_population(pop, args.n, seed=0)
        truth = json.loads((pop / "population.json").read_text())
        planted = {d["name"] for d in truth["devices"] if d["defect"]}
        print(f"{args.n} simulated devices, {len(planted)} voided die attaches planted; "
              f"diagnosis candidates: {', '.join(args.effect) if args.effect else 'all'}; "
              f"{os.cpu_count()} cores", flush=True)
        runs = [timed_run(pop, Path(tmp) / f"out{w}", w, options) for w in (1, 2)]
        for r in runs:
            print(f"  {r['workers']} worker(s): {r['run_s']:7.1f} s for {args.n} devices = "
                  f"{r['per_s']:.2f} devices/s (cluster start {r['startup_s']:.1f} s), median "
                  f"{r['device_s']:.2f} s per device on a worker, {r['errors']} errors; load "
                  f"average {r['load'][0]:.1f} before, {r['load'][1]:.1f} after")
        speedup = runs[1]["per_s"] / runs[0]["per_s"]
        print(f"speed-up with 2 workers: {speedup:.2f}x (target >= 1.7x)")
        summary = summarize(runs[1]["run"].results, Path(tmp) / "out2")
        found = set(summary.outlier_names)
        c_die, c_attach = LAYERS[0][2], LAYERS[1][2]
        located = [o for o in summary.outliers if summary.names[o.index] in planted
                   and o.reason.startswith("larger outer resistance")
                   and o.departs_c_j_per_k is not None
                   and c_die / 2 <= o.departs_c_j_per_k <= c_die + c_attach]
        print(f"outliers: {len(found)} found; planted {len(planted)}: {len(found & planted)} "
              f"found ({len(located)} with the extra resistance placed in the die attach), "
              f"{len(planted - found)} missed, {len(found - planted)} false alarms")
        for o in summary.outliers:
            name = summary.names[o.index]
            print(f"  {name}{' (planted)' if name in planted else ''}: {o.reason}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
