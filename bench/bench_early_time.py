"""Accuracy study of the early-time correction
(:meth:`spicethermal.identify.curves.ZthCurve.from_cooling`).

Run either way (prints the numbers)::

    .venv/bin/python bench/bench_early_time.py
    .venv/bin/python -m pytest -q -s -m benchmark bench/bench_early_time.py

Cases: the MUR880E-like ladder (:func:`spicethermal.core.synthetic.mur880e_foster`, 10 W), sampled
every 1 us to 1 ms then 400 log-spaced samples to 30 s, the junction temperature at the cut
*not* given (extrapolated T0), an electrical transient of length 0, 30, 100, 300 us
(:func:`~spicethermal.core.synthetic.synthetic_cooling`), white noise 0, 5, 20 mK, 10 seeds each.

Reported per setting (worst over seeds): whether the transient was detected, the masked span,
the Rth error, the error of r(t) at 10 us and 100 us (the paper's worst rows of Table 1:
11 % and 13 %), and the largest error over the masked span in % of Rth.
Targets: transients >= 30 us always detected, none detected without one; for transients up to
100 us, Rth within 0.5 % and masked points within 0.5 % of Rth. (A 300 us transient pushes the
√t window to 0.35..1.4 ms, where this device is no longer √t-like: ~2 % of Rth, reported only.)

Measured (10 seeds): detection 10/10 for 30, 100, 300 us and 0/10 without a transient; with
100 us and 5 mK: Rth within 0.14 %, r(10 us) within 6 % (the paper: 11 %), r(100 us) within
0.6 % (the paper: 13 %), masked points within 0.12 % of Rth. Without a transient and with Tj at
the cut unknown, T0 comes from the first 10 samples (1..10 us): 20 mK of noise then costs up to
38 % at 10 us — measure tj_steady_c or give fit_window_s in that case.
"""

from __future__ import annotations

import sys

import numpy as np

try:  # the same file serves as a pytest benchmark module and as a plain script
    import pytest
except ImportError:  # pragma: no cover
    pytest = None

from spicethermal.core.synthetic import mur880e_foster, synthetic_cooling
from spicethermal.identify.curves import ZthCurve

T = np.unique(np.concatenate([np.arange(1, 1000) * 1e-6, np.geomspace(1e-3, 30, 400)]))


def study(seeds: int = 10) -> list[dict]:
    f, p = mur880e_foster(), 10.0
    rows = []
    for transient in (0.0, 3e-5, 1e-4, 3e-4):
        for noise in (0.0, 0.005, 0.02):
            worst = {"transient_s": transient, "noise_k": noise, "detected": 0,
                     "mask_max_s": 0.0, "rth_err_pct": 0.0, "r10us_err_pct": 0.0,
                     "r100us_err_pct": 0.0, "masked_err_pct_rth": 0.0}
            for seed in range(seeds):
                _, tj = synthetic_cooling(f, p, T, noise_k=noise, seed=seed,
                                          transient_s=transient)
                z = ZthCurve.from_cooling(T, tj, p, tref_steady_c=25.0)
                e = z.early
                worst["detected"] += int(e.detected)
                worst["mask_max_s"] = max(worst["mask_max_s"], e.masked_s[1])
                worst["rth_err_pct"] = max(worst["rth_err_pct"],
                                           abs(z.rth_k_per_w / f.rth - 1) * 100)
                for key, tq in (("r10us_err_pct", 1e-5), ("r100us_err_pct", 1e-4)):
                    err = abs(float(z.r_at(tq)) / float(f.r_norm(tq)) - 1) * 100
                    worst[key] = max(worst[key], err)
                masked = z.t_s < e.masked_s[1]
                if masked.any():
                    dev = np.max(np.abs(z.zth_k_per_w[masked] - f.zth(z.t_s[masked])))
                    worst["masked_err_pct_rth"] = max(worst["masked_err_pct_rth"],
                                                      dev / f.rth * 100)
            worst["detected"] = f"{worst['detected']}/{seeds}"
            rows.append(worst)
    return rows


def report(rows: list[dict]) -> str:
    head = ("transient", "noise", "detected", "mask<=", "Rth err", "r(10us) err",
            "r(100us) err", "masked err")
    lines = ["  ".join(f"{h:>12}" for h in head)]
    for r in rows:
        lines.append("  ".join(f"{x:>12}" for x in (
            f"{r['transient_s'] * 1e6:.0f} us", f"{r['noise_k'] * 1e3:.0f} mK", r["detected"],
            f"{r['mask_max_s'] * 1e6:.0f} us", f"{r['rth_err_pct']:.2f} %",
            f"{r['r10us_err_pct']:.1f} %", f"{r['r100us_err_pct']:.1f} %",
            f"{r['masked_err_pct_rth']:.2f} %Rth")))
    return "\n".join(lines)


if pytest is not None:
    @pytest.mark.benchmark
    def test_early_time_correction_accuracy() -> None:
        rows = study()
        print("\n" + report(rows))
        for r in rows:
            n = int(r["detected"].split("/")[0])
            if r["transient_s"] == 0:
                assert n == 0
            else:
                assert r["detected"] == "10/10"
            if r["transient_s"] <= 1e-4:
                assert r["rth_err_pct"] < (0.5 if r["transient_s"] else 1.0)
                assert r["masked_err_pct_rth"] < 0.5


if __name__ == "__main__":
    print(report(study(int(sys.argv[1]) if len(sys.argv) > 1 else 10)))
