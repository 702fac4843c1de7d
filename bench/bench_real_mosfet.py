"""The real MOSFET transients (PyRth, MIT) end to end through bundles with a K-factor
calibration, against PyRth's numbers, and the command line's speed.

Run either way (prints the numbers)::

    .venv/bin/python bench/bench_real_mosfet.py
    .venv/bin/python -m pytest -q -s -m benchmark bench/bench_real_mosfet.py

1. **Totals and separation**: ``spicethermal structure dry tim --json`` on the two bundles,
   with the default √t window and with PyRth's (samples 450..1100, 0.46..1.35 ms). Targets:
   totals within 1 % of PyRth's 13.667 and 5.977 K/W, separation between 2.1 and 2.8 K/W
   (PyRth 2.42).
2. **Speed**: that command for both files, a fresh process each time, median of 3: CPU time
   (target <= 1.5 s) and wall time (the same on an idle machine; on a shared one it also
   counts the waiting).
"""

from __future__ import annotations

import json
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

try:  # the same file serves as a pytest benchmark module and as a plain script
    import pytest
except ImportError:  # pragma: no cover
    pytest = None

from spicethermal.data import path
from spicethermal.identify.records import read_pyrth
from spicethermal.io.importers import PYRTH_MOSFET_CALIBRATION

PYRTH_RTH = {"dry": 13.667, "tim": 5.977}
PYRTH_WINDOW = "4.6e-4,1.35e-3"


def _bundles(root: Path) -> list[str]:
    return [str(read_pyrth(path(f"pyrth_mosfet/MOSFET_{n}.txt"), PYRTH_MOSFET_CALIBRATION,
                           tref_c=25.0).write(root / n)) for n in ("dry", "tim")]


def _structure(bundles: list[str], *extra: str) -> tuple[list[dict], float, float]:
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "spicethermal.cli.main", "structure", *bundles,
                           "--json", *extra], capture_output=True, text=True, check=True)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return json.loads(proc.stdout), wall, cpu


def main() -> dict[str, float]:
    out: dict[str, float] = {}
    with tempfile.TemporaryDirectory() as tmp:
        bundles = _bundles(Path(tmp))
        for window, extra in (("default", ()), ("pyrth", ("--early-window", PYRTH_WINDOW))):
            docs, _, _ = _structure(bundles, *extra)
            for name, doc in zip(("dry", "tim"), docs, strict=True):
                total = doc["cumulative"]["r_k_per_w"][-1]
                out[f"{window}_{name}_error"] = total / PYRTH_RTH[name] - 1
                print(f"{window:7s} window: {name} total {total:.4f} K/W (PyRth "
                      f"{PYRTH_RTH[name]}, {100 * (total / PYRTH_RTH[name] - 1):+.2f} %)")
            sep = docs[0]["separation"]["r_k_per_w"]
            out[f"{window}_separation"] = sep
            print(f"{window:7s} window: separation at {sep:.3f} K/W (PyRth 2.42)")
        runs = [_structure(bundles)[1:] for _ in range(3)]
        out["wall_s"] = statistics.median(w for w, _ in runs)
        out["cpu_s"] = statistics.median(c for _, c in runs)
        print(f"structure dry tim: wall {out['wall_s']:.2f} s, CPU {out['cpu_s']:.2f} s "
              f"(median of 3, fresh processes)")
    return out


if pytest is not None:
    @pytest.mark.benchmark
    def test_bench_real_mosfet():
        r = main()
        assert abs(r["pyrth_dry_error"]) < 0.01 and abs(r["pyrth_tim_error"]) < 0.01
        assert 2.1 <= r["pyrth_separation"] <= 2.8 and 2.1 <= r["default_separation"] <= 2.8
        assert r["cpu_s"] <= 1.5


if __name__ == "__main__":
    main()
