"""Wall-clock time of a full simulated bench run (target: < 30 s).

Run: .venv/bin/python bench/bench_bench_run.py   (or with pytest -m benchmark bench/)
A full run is calibration at six temperatures, Rth at 99.9 % duty, two cooling curves and the
18-point PWM grid: about an hour of bench time, simulated.
"""

from __future__ import annotations

import json
import tempfile
import time
from pathlib import Path

import pytest


def run_once(url: str) -> tuple[float, dict]:
    from spicethermal.bench.session import run_bench

    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        out = run_bench(url, Path(tmp) / "bundle")
        wall = time.perf_counter() - t0
        manifest = json.loads((out / "bundle.json").read_text())
    return wall, manifest


@pytest.mark.benchmark
@pytest.mark.parametrize("url", ["sim://actuator?seed=1", "sim://mur880e?seed=1",
                                 "sim://actuator?seed=1&faults=1e-3&stall=20"])
def test_full_simulated_run_is_fast(url):
    wall, manifest = run_once(url)
    link = manifest["bench"]["link"]
    print(f"\n{url}: {wall:.2f} s wall, {link['frames']} frames, {link['corrupt']} corrupt, "
          f"{link['naks']} NAKs")
    assert wall < 30.0


if __name__ == "__main__":
    for url in ("sim://actuator?seed=1", "sim://mur880e?seed=1",
                "sim://actuator?seed=1&faults=1e-3&stall=20"):
        wall, manifest = run_once(url)
        link = manifest["bench"]["link"]
        print(f"{url:45s} {wall:6.2f} s wall  {link['frames']:5d} frames  "
              f"{link['corrupt']:3d} corrupt  {link['naks']:3d} NAKs")
