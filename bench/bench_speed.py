"""Speed of what a user waits for: the Table 2 grid and low PWM frequencies in ngspice, compare
with a device effect, drive --verify, and 10^6-row curves (issue #18).

Run: ``.venv/bin/python bench/bench_speed.py`` (prints one line per benchmark; the commands run
as a user runs them, ``spicethermal ...`` in a fresh process, on the sample bundle shipped in
``spicethermal/data/sample_bundle``). Wall times depend on the machine and its load: they are
the best of ``REPEAT`` runs.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path
from unittest import mock

import numpy as np
from bench_conversions import best_of  # same folder: run as a script or by bench/table.py

from spicethermal.core.ladder import Foster
from spicethermal.data import path as data_path
from spicethermal.engines import pwmsim
from spicethermal.engines.pwmsim import SpicePwm
from spicethermal.model import ThermalModel

REPEAT = 2
ACTUATOR = Foster.from_tau((6.0, 20.0, 50.0, 70.0), (1e-4, 5e-3, 0.4, 30.0))
GRID = [(f, d) for f in (500.0, 1e3, 3e3, 5e3, 10e3, 25e3) for d in (0.2, 0.5, 0.8)]
CLI = [sys.executable, "-m", "spicethermal.cli.main"]


def best(fn) -> float:
    return best_of(fn, REPEAT)


def table2_grid(workers: int | None = None) -> float:
    """Wall time of the 18-point grid in ngspice (``workers=1``: one point after another)."""
    sim = SpicePwm(ThermalModel(ACTUATOR))
    f, d = zip(*GRID, strict=True)
    if workers is None:
        return best(lambda: sim.grid(0.094, f, d, 1e-4))
    with mock.patch.object(pwmsim, "workers", lambda: workers):
        return best(lambda: sim.grid(0.094, f, d, 1e-4))


def low_frequency(freq: float) -> float:
    """Wall time of one ngspice PWM point at ``freq`` (periodic, checked)."""
    sim = SpicePwm(ThermalModel(ACTUATOR))
    return best(lambda: sim.state(0.094, freq, 0.5, 1e-4))


def command(argv: list[str], cwd: Path) -> tuple[float, float]:
    """(best wall time s, peak memory MB) of ``spicethermal argv`` in a fresh process."""
    walls, peak = [], 0.0
    for _ in range(REPEAT):
        probe = ("import resource, subprocess, sys, time; t0 = time.perf_counter(); "
                 "r = subprocess.run(sys.argv[1:], stdout=subprocess.DEVNULL); "
                 "print(time.perf_counter() - t0, "
                 "resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss, r.returncode)")
        out = subprocess.run([sys.executable, "-c", probe, *CLI, *argv], cwd=cwd,
                             capture_output=True, text=True, check=True).stdout.split()
        if out[2] != "0":
            raise RuntimeError(f"spicethermal {' '.join(argv)} failed")
        walls.append(float(out[0]))
        peak = max(peak, float(out[1]) / 1024)
    return min(walls), peak


def big_bundle(where: Path, rows: int = 1_000_000) -> Path:
    """A bundle with one cooling curve of ``rows`` samples (the actuator, 10 mK noise)."""
    t = np.linspace(1e-4, 200.0, rows)
    tj = 25 + 0.094 * ACTUATOR.cooling(t) + np.random.default_rng(0).normal(0, 0.01, rows)
    where.mkdir()
    np.savetxt(where / "cooling_1.csv", np.column_stack([t, tj]), delimiter=",", fmt="%.8g",
               header="t_s,tj_c", comments="")
    (where / "bundle.json").write_text(json.dumps({
        "format": "spicethermal-bundle/1", "device": "long record", "reference": "ambient",
        "ambient_c": 25.0, "cooling": [{"file": "cooling_1.csv", "power_w": 0.094,
                                        "tj_steady_c": 25 + 0.094 * ACTUATOR.rth,
                                        "tref_steady_c": 25.0}]}))
    return where


def measure() -> dict[str, tuple[float, float]]:
    out: dict[str, tuple[float, float]] = {}
    out["grid"] = (table2_grid(), 0.0)
    out["grid serial"] = (table2_grid(workers=1), 0.0)
    for f in (1.0, 10.0):
        out[f"{f:g} Hz"] = (low_frequency(f), 0.0)
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        shutil.copytree(data_path("sample_bundle/bundle.json").parent, work / "mydiode")
        subprocess.run([*CLI, "fit", "mydiode", "-o", "model.json", "-q"], cwd=work, check=True)
        subprocess.run([*CLI, "fit", "mydiode", "--effect", "temperature-coefficient", "-o",
                        "model2.json", "-q"], cwd=work, check=True, stdout=subprocess.DEVNULL)
        out["compare effect"] = command(["compare", "model2.json", "mydiode"], work)
        out["drive verify"] = command(["drive", "model.json", "--t-max", "90", "--target", "60",
                                       "--verify"], work)
        big_bundle(work / "big")
        out["big fit"] = command(["fit", "big", "-o", "big.json", "-q"], work)
        out["big compare"] = command(["compare", "big.json", "big", "--json"], work)
        out["big spectrum"] = command(["spectrum", "big"], work)
    return out


def summary() -> list[tuple[str, str, str, str]]:
    """Rows (benchmark, before, today, target) for bench/README.md."""
    m = measure()
    grid, serial = m["grid"][0], m["grid serial"][0]

    def mem(key: str) -> str:
        return f"{m[key][0]:.1f} s, {m[key][1]:.0f} MB"

    return [
        ("Table 2: 18-point PWM grid in ngspice, from the periodic steady state",
         f"{serial:.2f} s (one point after another)", f"{grid:.2f} s ({pwmsim.workers()} at a "
         f"time)", "≤ 2 s"),
        ("one ngspice PWM point at 1 Hz / 10 Hz (duty 0.5, 100 µs window)",
         "refused: not periodic (70 mK / 8 mK drift); 2 s at 1 Hz",
         f"{m['1 Hz'][0]:.2f} s / {m['10 Hz'][0]:.2f} s, periodic", "works, ≤ 1 s"),
        ("`compare MODEL2.json BUNDLE`, temperature-coefficient model, sample bundle",
         "16 s (issue #18); 7.6 s on main at 3c460ad", f"{m['compare effect'][0]:.1f} s",
         "≥ 3× faster: ≤ 5.3 s"),
        ("`drive MODEL.json --t-max 90 --target 60 --verify`, sample bundle's model",
         "13 s (issue #18); 10.1 s on main at 3c460ad", f"{m['drive verify'][0]:.1f} s",
         "≥ 3× faster: ≤ 4.3 s"),
        ("`fit` on a 10^6-row cooling curve", "14 s (issue #18), 31 s / 461 MB on main",
         mem("big fit"), "≤ 10 s, ≤ 500 MB"),
        ("`compare --json` on a 10^6-row cooling curve", "44 s, 2.6 GB (issue #18); "
         "163 s / 2.7 GB on main", mem("big compare"), "≤ 10 s, ≤ 500 MB"),
        ("`spectrum` on a 10^6-row cooling curve", "31 s / 461 MB on main", mem("big spectrum"),
         "≤ 10 s, ≤ 500 MB"),
    ]


if __name__ == "__main__":
    for row in summary():
        print(" | ".join(row))
