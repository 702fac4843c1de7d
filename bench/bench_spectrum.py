"""Speed and accuracy of NID: time-constant spectrum + structure function.

Run either way (prints the numbers)::

    .venv/bin/python bench/bench_spectrum.py [N_SEEDS]
    .venv/bin/python -m pytest -q -s -m benchmark bench/bench_spectrum.py

1. **Speed** (target < 2 s): an 8,000-point cooling transient sampled like the PyRth MOSFET
   files (1 µs steps to 1 ms, then about 1,450 log-spaced samples per decade to 100 s; the
   4-layer ladder of ``tests/test_structure.py`` scaled to Rth = 10 K/W, 0.1 % noise), timed
   stage by stage: Zth from the cooling curve (masking, √t), spectrum (Bayesian, 2000
   iterations, 40 points per decade), structure function (10 Foster stages per decade →
   exact Cauer). Median of 3 runs. The same for the two real MOSFET files.
2. **Accuracy** over ``N_SEEDS`` noise seeds (default 10) of the 4-layer ladder test, both
   methods: max |ΔΣR| at equal ΣC in % of Rth (resolved range, corners excluded within a
   factor 2, as in the test), and the relative ΣR error at the middle of each riser.
3. **Differential structure function** on five distributed layers (4 sections each): the
   layer's K = C/R read off the curve against the truth.
4. **Real data**: fit error of the spectrum's ladder from 10 µs, and the separation point.
"""

from __future__ import annotations

import statistics
import sys
import time
from pathlib import Path

import numpy as np

try:  # the same file serves as a pytest benchmark module and as a plain script
    import pytest
except ImportError:  # pragma: no cover
    pytest = None

from spicethermal.core.ladder import Cauer
from spicethermal.core.synthetic import synthetic_cooling
from spicethermal.identify.curves import ZthCurve
from spicethermal.identify.spectrum import time_constant_spectrum
from spicethermal.identify.structure import StructureFunction, separation, structure_function

DATA = Path(__file__).resolve().parents[1] / "spicethermal" / "data" / "pyrth_mosfet"
LAYERS = Cauer([0.1, 0.3, 0.5, 1.0], [0.001, 0.1, 1.0, 30.0])


def mosfet_like_times() -> np.ndarray:
    """About 8,100 sample times like the PyRth MOSFET files."""
    lin = np.arange(1, 1001) * 1e-6
    log = np.geomspace(1e-3, 100.0, 5 * 1450 + 1)[1:]
    return np.concatenate([lin, log])


def _timed(fn, *args, **kw):
    t0 = time.perf_counter()
    out = fn(*args, **kw)
    return out, time.perf_counter() - t0


def speed(repeats: int = 3) -> dict[str, float]:
    ladder = Cauer(np.asarray(LAYERS.r) * 10 / LAYERS.rth, np.asarray(LAYERS.c))
    t, tj = synthetic_cooling(ladder, 1.0, mosfet_like_times(), noise_k=0.01, seed=1,
                              transient_s=5e-5)
    rows = []
    for _ in range(repeats):
        curve, t_zth = _timed(ZthCurve.from_cooling, t, tj, 1.0, tref_steady_c=25.0)
        spec, t_spec = _timed(time_constant_spectrum, curve)
        sf, t_sf = _timed(StructureFunction.from_spectrum, spec)
        rows.append((t_zth, t_spec, t_sf))
    med = [statistics.median(x) for x in zip(*rows, strict=True)]
    print(f"speed, {t.size}-point cooling transient (median of {repeats}):")
    print(f"  Zth from cooling {med[0]:.3f} s, spectrum {med[1]:.3f} s "
          f"({spec.tau_s.size} grid points), structure function {med[2]:.3f} s "
          f"({sf.order} Cauer sections); spectrum + structure {med[1] + med[2]:.3f} s "
          f"(target < 2 s)")
    return {"zth_s": med[0], "spectrum_s": med[1], "structure_s": med[2],
            "total_s": med[1] + med[2]}


def accuracy(n_seeds: int = 10) -> dict[str, float]:
    true = LAYERS.to_foster()
    ref = StructureFunction.from_ladder(LAYERS)
    c_true, r_true = ref.c_j_per_k, ref.r_k_per_w
    t = np.logspace(-6, 3, 361)
    out = {}
    for method in ("bayes", "nnls"):
        worst, mids, zfit, times = [], [], [], []
        for seed in range(1, n_seeds + 1):
            z = true.zth(t) + np.random.default_rng(seed).normal(0, 1e-3 * true.rth, t.size)
            (spec, dt) = _timed(time_constant_spectrum, t, z, method=method)
            sf = StructureFunction.from_spectrum(spec)
            times.append(dt)
            lo, hi = sf.resolved_c_range()
            for k in range(1, LAYERS.order):
                cc = np.geomspace(max(2 * c_true[k - 1], lo), min(c_true[k] / 2, hi), 60)
                worst.append(np.max(np.abs(sf.r_at(cc) - r_true[k - 1])) / LAYERS.rth)
                mid = np.sqrt(c_true[k - 1] * c_true[k])
                mids.append(abs(float(sf.r_at(mid)) / r_true[k - 1] - 1))
            zfit.append(np.max(np.abs(spec.to_foster(10).zth(t) - true.zth(t))) / true.rth)
        print(f"accuracy, 4-layer ladder, 0.1 % noise, {n_seeds} seeds, method {method} "
              f"(resolution {spec.resolution_decades:.2f} decades, {np.median(times):.2f} s):")
        print(f"  max |ΔΣR| at equal ΣC: {100 * max(worst):.2f} % of Rth (median "
              f"{100 * np.median(worst):.2f} %); riser middles: max {100 * max(mids):.2f} % "
              f"of the local ΣR (median {100 * np.median(mids):.2f} %); "
              f"Zth reproduced within {100 * max(zfit):.3f} % of Rth")
        out[method] = max(worst)
    return out


#: Five distributed layers (R K/W, C J/K), 4 Cauer sections each: die, attach, base plate,
#: interface, heat sink. Within a uniform layer K = dΣC/dΣR = C/R (= λ cρ A²).
DISTRIBUTED = ((0.2, 0.004), (0.3, 0.002), (0.3, 0.3), (0.8, 0.1), (1.0, 30.0))


def differential(n_seeds: int = 5) -> float:
    """Layer K = C/R read off the differential structure function (median over the middle
    half of each layer, resolved part) against the truth."""
    r, c = [], []
    for big_r, big_c in DISTRIBUTED:
        r += [big_r / 4] * 4
        c += [big_c / 4] * 4
    true = Cauer(r, c).to_foster()
    edges = np.cumsum([0.0] + [x for x, _ in DISTRIBUTED])
    t = np.logspace(-6, 3, 361)
    errs = np.zeros((n_seeds, len(DISTRIBUTED)))
    for j, seed in enumerate(range(1, n_seeds + 1)):
        z = true.zth(t) + np.random.default_rng(seed).normal(0, 1e-3 * true.rth, t.size)
        sf = structure_function(time_constant_spectrum(t, z))
        rm, k = sf.differential()
        ok = sf.resolved()[1:]
        for i, (big_r, big_c) in enumerate(DISTRIBUTED):
            a, b = edges[i], edges[i + 1]
            sel = ok & (rm > a + 0.25 * (b - a)) & (rm < b - 0.25 * (b - a))
            errs[j, i] = np.median(k[sel]) / (big_c / big_r) - 1 if sel.any() else np.nan
    print(f"differential structure function, 5 distributed layers, 0.1 % noise, {n_seeds} "
          f"seeds: layer K = C/R (true " + ", ".join(f"{c / r:.3g}" for r, c in DISTRIBUTED)
          + " W²s/K²) recovered within " + ", ".join(
              f"{100 * np.nanmax(np.abs(errs[:, i])):.0f} %" for i in range(len(DISTRIBUTED))))
    return float(np.nanmax(np.abs(errs)))


def real_data() -> dict[str, float]:
    from spicethermal.identify.sources import read_source

    if not DATA.is_dir():  # pragma: no cover
        print("real data: not found")
        return {}
    sfs, out = {}, {}
    for name in ("dry", "tim"):
        (curve, t_read) = _timed(lambda p: read_source(p, calibration=DATA / "calibration.csv",
                                                       tref_c=25.0).curve(),
                                 DATA / f"MOSFET_{name}.txt")
        (spec, t_spec) = _timed(time_constant_spectrum, curve)
        (sf, t_sf) = _timed(structure_function, spec)
        keep = curve.t_s >= 1e-5
        err = spec.to_foster(10).zth(curve.t_s[keep]) - curve.zth_k_per_w[keep]
        out[name] = float(np.max(np.abs(err)) / curve.rth_k_per_w)
        sfs[name] = sf
        print(f"MOSFET_{name}: {len(curve)} points, Rth = {curve.rth_k_per_w:.3f} K/W; read + "
              f"Zth {t_read:.2f} s, spectrum {t_spec:.2f} s, structure {t_sf:.2f} s; ladder "
              f"vs Zth from 10 us: max {100 * out[name]:.2f} %, rms "
              f"{100 * np.sqrt(np.mean(err ** 2)) / curve.rth_k_per_w:.3f} % of Rth; "
              f"peaks at {', '.join(f'{x:.3g}' for x in spec.peaks_s())} s")
    sep = separation(sfs["dry"], sfs["tim"])
    print(f"  {sep}")
    out["separation_k_per_w"] = float(sep.r_k_per_w or float("nan"))
    return out


def main(n_seeds: int = 10) -> None:
    speed()
    accuracy(n_seeds)
    differential(max(1, n_seeds // 2))
    real_data()


if pytest is not None:
    @pytest.mark.benchmark
    def test_bench_spectrum():
        s = speed()
        a = accuracy(5)
        differential(3)
        r = real_data()
        assert s["total_s"] < 2.0
        assert a["bayes"] < 0.02
        assert r.get("dry", 0) < 0.01 and r.get("tim", 0) < 0.01


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 10)
