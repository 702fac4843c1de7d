"""Tactile display (issue #47): a Braille cell measured, fitted, exported, and a line of text.

Run: ``.venv/bin/python bench/bench_array.py [CELLS]`` (plain script; needs ngspice). On the
simulated 2 x 4 actuator array (``sim://array``, an eight-dot Braille cell at 2.5 mm pitch) it
measures heat one, read all through the firmware, fits the N-port model (order by BIC),
checks the N-port ``.lib`` in ngspice in the three dialects, and refreshes a 40-character
line of text with the crosstalk-aware drive, the naive lone drives and the constant hold,
every distinct cell checked in ngspice (seed 47 of the simulated bench). It prints the
figures ``bench/README.md`` records.
"""

from __future__ import annotations

import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from spicethermal.array.check import verify_line
from spicethermal.array.data import coupling_from_bundle
from spicethermal.array.drive import Limits
from spicethermal.array.fit import fit_array
from spicethermal.array.refresh import drive_text
from spicethermal.array.result import line_document, summary
from spicethermal.bench.array_devices import ArrayGeometry
from spicethermal.bench.session import run_bench
from spicethermal.io.bundle import Bundle
from spicethermal.spice.array_lib import check_array_lib

URL = "sim://array?seed=47"
#: 40 characters of text (six-dot Braille; dots 7 and 8 stay down)
LINE = "the quick brown fox jumps over a lazy do"
LIMITS = Limits(ambient_c=25.0, t_max_c=85.0, target_c=70.0, tol_k=1.0, actuation_c=64.7,
                margin_k=1.0, p_max_w=1.5, f_pwm_hz=1000.0)


def main(cells: int = 40) -> None:
    work = Path(tempfile.mkdtemp(prefix="bench-array-"))
    try:
        t0 = time.perf_counter()
        bundle = work / "cell"
        run_bench(URL, bundle, actions=["calibrate"], calibration_c=(25.0, 45.0, 65.0),
                  calibration_settle_s=120.0)
        run_bench(URL, bundle, actions=["coupling"])
        t_bench = time.perf_counter() - t0
        data = coupling_from_bundle(Bundle.read(bundle))
        final = data.final()
        ratio = final / np.diag(final)[:, None]
        off = ratio[~np.eye(len(final), dtype=bool)]
        print(f"measured (simulated bench, {t_bench:.1f} s wall): {len(data.elements)} elements, "
              f"mutual/self at the end of the record {100 * off.min():.1f}-"
              f"{100 * off.max():.1f} %")
        t0 = time.perf_counter()
        fit = fit_array(data)
        print(f"fit ({time.perf_counter() - t0:.1f} s): {fit}")
        print(fit.table())
        print(f"(a) worst |Z_ij fit - measured| {100 * fit.max_error:.2f} % of Z_ii final "
              f"(target <= 2 %)")
        truth = ArrayGeometry().model()
        t = np.geomspace(1e-4, 300, 200)
        dev = np.max(np.abs(fit.model.zth(t) - truth.zth(t)), axis=0) / np.diag(
            truth.modes.dc())[:, None]
        print(f"fit against the simulator's true network: worst element {100 * dev.max():.2f} % "
              f"of Z_ii")
        for dialect in ("ngspice", "pspice", "ltspice"):
            t0 = time.perf_counter()
            check = check_array_lib(fit.model, dialect)
            print(f"(b) .lib in ngspice ({dialect}, {check['runs']} runs, "
                  f"{time.perf_counter() - t0:.1f} s): worst pin {100 * check['max_error']:.3f} "
                  f"% of Z_ii from the fitted model")
        text = LINE[:cells]
        t0 = time.perf_counter()
        line = drive_text(fit.model, [text], LIMITS, cells=cells)
        t_plan = time.perf_counter() - t0
        checks = None
        if shutil.which("ngspice"):
            t0 = time.perf_counter()
            checks = verify_line(line, "ngspice")
            t_spice = time.perf_counter() - t0
        doc = line_document(line, checks)
        print(f"line of {cells} cells planned in {t_plan:.1f} s"
              + (f", checked in ngspice in {t_spice:.1f} s" if checks else ""))
        print(summary(doc))
        ours, naive = doc["refresh_s"]["ours"][0], doc["raised_s"]["naive"][0]
        if ours is not None and naive is not None:
            print(f"(c) refresh {1e3 * ours:.1f} ms ({1 / ours:.1f} lines/s); the naive drive "
                  f"has every dot up after {1e3 * naive:.1f} ms but "
                  f"{'never settles' if doc['refresh_s']['naive'][0] is None else 'settles'}, "
                  f"with {doc['violations']['naive']['t_max']} t_max and "
                  f"{doc['violations']['naive']['actuation']} actuation violations")
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 40)
