"""Accuracy and speed study of the automatic ladder fit
(:func:`spicethermal.fit.ladder.fit_foster`).

Run either way (prints the numbers)::

    .venv/bin/python bench/bench_fit.py [N_CASES]
    .venv/bin/python -m pytest -q -s -m benchmark bench/bench_fit.py

Synthetic cases (:func:`make_case`, deterministic in the seed):

* order m uniform in 2..6; the fastest time constant log-uniform in [3e-4, 3e-3] s, each next one
  a log-uniform factor 4..12 slower (so time constants are at least 4x apart);
* data: 10 points per decade from 100 us; the last point at t_max = 5 τ_max · (log-uniform 1..10),
  so every τ lies in [3e-4, t_max/5];
* stage resistances: each at least 3 % of Rth (r_i = Rth · (0.03 + (1 - 0.03 m) · Dirichlet(1..1)));
  Rth log-uniform in [1, 200] K/W;
* noise: white Gaussian, σ = 0.1 % of Rth, added to Zth(t); the fit is not told σ or Rth.

Also reported: how often the true r_i and τ_i lie within 1 and 2 reported standard
uncertainties (ideal: 68 % and 95 %), the same study with Rth given, and noise-free recovery.

Acceptance (per case): automatic order == true order; |ΣR - Rth| ≤ 0.2 % Rth;
max |Zfit(t) - Ztrue(t)| ≤ 0.5 % Rth over the data window (400 log-spaced points).
Targets: order right in ≥ 95 % of cases, no failures; a 46-point fit < 0.1 s, 10,000 points < 2 s.
"""

from __future__ import annotations

import statistics
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

try:  # the same file serves as a pytest benchmark module and as a plain script
    import pytest
except ImportError:  # pragma: no cover
    pytest = None

from spicethermal.core.ladder import Foster
from spicethermal.fit.ladder import fit_foster

NOISE_OF_RTH = 1e-3
MIN_STAGE_OF_RTH = 0.03


@dataclass(frozen=True)
class Case:
    seed: int
    truth: Foster
    t_s: np.ndarray
    zth_k_per_w: np.ndarray
    sigma_k_per_w: float


def make_case(seed: int, points_per_decade: int = 10, noise_of_rth: float = NOISE_OF_RTH) -> Case:
    """One synthetic Zth curve from a random 2..6-stage ladder (see the module docstring)."""
    rng = np.random.default_rng(seed)
    m = int(rng.integers(2, 7))
    tau = [10 ** rng.uniform(np.log10(3e-4), np.log10(3e-3))]
    for _ in range(m - 1):
        tau.append(tau[-1] * 10 ** rng.uniform(np.log10(4), np.log10(12)))
    t_max = 5 * tau[-1] * 10 ** rng.uniform(0, 1)
    rth = 10 ** rng.uniform(0, np.log10(200))
    r = rth * (MIN_STAGE_OF_RTH + (1 - MIN_STAGE_OF_RTH * m) * rng.dirichlet(np.ones(m)))
    truth = Foster.from_tau(r, tau)
    n_dec = np.log10(t_max) + 4
    t = np.logspace(-4, np.log10(t_max), int(np.ceil(n_dec * points_per_decade)) + 1)
    sigma = noise_of_rth * truth.rth
    z = truth.zth(t) + rng.normal(0.0, sigma, t.size)
    return Case(seed, truth, t, z, sigma)


def errors(case: Case, fitted: Foster) -> tuple[float, float, float]:
    """(|ΔRth|/Rth, max |ΔZth|/Rth, max |ΔZth|/Zth) over the data window."""
    tt = np.logspace(np.log10(case.t_s[0]), np.log10(case.t_s[-1]), 400)
    zt = case.truth.zth(tt)
    dz = np.abs(fitted.zth(tt) - zt)
    rth = case.truth.rth
    return abs(fitted.rth - rth) / rth, float(dz.max() / rth), float((dz / zt).max())


def study(n_cases: int = 200, first_seed: int = 0, hold_rth: bool = False,
          noise_of_rth: float = NOISE_OF_RTH) -> dict:
    """Fit ``n_cases`` synthetic curves; return the counts and worst errors.

    ``hold_rth`` tells the fit the true Rth (ΣR = Rth held); ``noise_of_rth`` = 0 gives
    noise-free data (then ``worst_param_error`` is the largest relative error of any r or τ).
    """
    ok_order = ok_rth = ok_zth = 0
    worst_rth = worst_zth = worst_rel = worst_param = 0.0
    wrong: list[tuple[int, int, int]] = []
    times: list[float] = []
    z_scores: list[float] = []
    for seed in range(first_seed, first_seed + n_cases):
        case = make_case(seed, noise_of_rth=noise_of_rth)
        t0 = time.perf_counter()
        res = fit_foster(case.t_s, case.zth_k_per_w,
                         rth_k_per_w=case.truth.rth if hold_rth else None)
        times.append(time.perf_counter() - t0)
        e_rth, e_z, e_rel = errors(case, res.foster)
        ok_order += res.order == case.truth.order
        if res.order != case.truth.order:
            wrong.append((seed, case.truth.order, res.order))
        else:
            est = np.r_[res.foster.r, res.foster.tau]
            true = np.r_[case.truth.r, case.truth.tau]
            worst_param = max(worst_param, float(np.max(np.abs(est / true - 1))))
            if noise_of_rth > 0:
                z_scores.extend((est - true) / np.r_[res.u_r_k_per_w, res.u_tau_s])
        ok_rth += e_rth <= 2e-3
        ok_zth += e_z <= 5e-3
        worst_rth, worst_zth, worst_rel = max(worst_rth, e_rth), max(worst_zth, e_z), max(
            worst_rel, e_rel)
    return {"cases": n_cases, "order_right": ok_order, "rth_within_0.2%": ok_rth,
            "zth_within_0.5%_of_rth": ok_zth, "worst_rth_error": worst_rth,
            "worst_zth_error_of_rth": worst_zth, "worst_zth_error_relative": worst_rel,
            "worst_param_error": worst_param,
            "params_within_1u": float(np.mean(np.abs(z_scores) < 1)) if z_scores else None,
            "params_within_2u": float(np.mean(np.abs(z_scores) < 2)) if z_scores else None,
            "wrong_orders(seed,true,fit)": wrong, "median_fit_s": statistics.median(times),
            "max_fit_s": max(times)}


def timing(n_points: int, repeats: int = 7) -> float:
    """Median wall time (s) of an automatic fit of an ``n_points`` curve (a 4-stage ladder)."""
    truth = Foster.from_tau([10.0, 30.0, 60.0, 46.0], [2e-4, 3e-3, 4e-2, 0.6])
    rng = np.random.default_rng(1)
    if n_points <= 100:
        t = np.logspace(-4, np.log10(3.0), n_points)  # log-spaced, like the paper's 46 points
    else:
        t = np.linspace(3.0 / n_points, 3.0, n_points)  # sampled at a fixed rate
    z = truth.zth(t) + rng.normal(0, 1e-3 * truth.rth, t.size)
    fit_foster(t, z)  # warm up imports
    runs = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fit_foster(t, z)
        runs.append(time.perf_counter() - t0)
    return statistics.median(runs)


def report(n_cases: int = 200) -> dict:
    out = study(n_cases)
    held = study(n_cases, hold_rth=True)
    exact = study(n_cases, noise_of_rth=0.0)
    out["median_time_46_points_s"] = timing(46)
    out["median_time_10000_points_s"] = timing(10_000, repeats=3)
    print(f"{n_cases} random ladders, 0.1 % noise, Rth not given:")
    for k, v in out.items():
        print(f"  {k:32s} {v}")
    print("same cases, Rth given (ΣR = Rth held):")
    for k in ("order_right", "zth_within_0.5%_of_rth", "worst_zth_error_of_rth",
              "wrong_orders(seed,true,fit)"):
        print(f"  {k:32s} {held[k]}")
    print("same ladders, noise-free:")
    for k in ("order_right", "worst_param_error", "wrong_orders(seed,true,fit)"):
        print(f"  {k:32s} {exact[k]}")
    out["held"], out["noise_free"] = held, exact
    return out


if pytest is not None:

    @pytest.mark.benchmark
    def test_fit_study() -> None:
        out = report(200)
        assert out["order_right"] >= 0.95 * out["cases"]
        assert out["rth_within_0.2%"] == out["cases"]
        assert out["zth_within_0.5%_of_rth"] == out["cases"]
        assert out["median_time_46_points_s"] < 0.1
        assert out["median_time_10000_points_s"] < 2.0
        assert out["held"]["order_right"] >= 0.95 * out["cases"]
        assert out["noise_free"]["order_right"] == out["cases"]
        assert out["noise_free"]["worst_param_error"] < 1e-6


if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
    report(int(sys.argv[1]) if len(sys.argv) > 1 else 200)
