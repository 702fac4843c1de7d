"""Speed and exactness of Foster <-> Cauer at 20 to 1000 stages, time constants over 8 decades.

Run: ``.venv/bin/python bench/bench_conversions.py`` (in-process, warm; each figure the best of
three). Targets (issue #18): 200 stages in <= 0.3 s and 1000 stages in <= 5 s both ways, and a
round trip Foster -> Cauer -> Foster exact to 1e-9 relative in every R and τ. Before the bidiagonal
conversions (mpmath eigenvalues): Cauer -> Foster 0.33 s at 20 stages, 7.9 s at 50, 98 s at 100;
Foster -> Cauer 0.48 s at 100 and more than 15 minutes at 1000.
"""

from __future__ import annotations

import time

import numpy as np

from spicethermal.core.ladder import Cauer, Foster, round_trip_error

ORDERS = (20, 50, 100, 200, 1000)


def ladder(order: int, seed: int = 0) -> Foster:
    """Random stage resistances 0.05-20 K/W, time constants log-spaced 10 µs-1000 s ± 30 %."""
    rng = np.random.default_rng(1000 * order + seed)
    tau = np.logspace(-5, 3, order) * rng.uniform(0.7, 1.3, order)
    return Foster.from_tau(rng.uniform(0.05, 20.0, order), tau)


def best_of(fn, repeat: int = 3) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def measure(order: int) -> tuple[float, float, float]:
    """(Foster -> Cauer s, Cauer -> Foster s, round-trip relative error) at ``order`` stages."""
    f = ladder(order)
    c = f.to_cauer()
    t_fc = best_of(f.to_cauer)
    t_cf = best_of(lambda: Cauer(c.r, c.c).to_foster())  # fresh object: no cached Foster form
    return t_fc, t_cf, round_trip_error(f, Cauer(c.r, c.c))


def summary() -> list[tuple[str, str, str, str]]:
    """Rows (benchmark, before, today, target) for bench/README.md."""
    rows = []
    before = {200: "C→F over 98 s (100 stages: 98 s); F→C ~2 s", 1000: "F→C over 15 min"}
    for order, target in ((200, "≤ 0.3 s"), (1000, "≤ 5 s")):
        t_fc, t_cf, err = measure(order)
        rows.append((f"Foster→Cauer / Cauer→Foster, {order} stages, τ over 8 decades",
                     before[order], f"{t_fc:.3f} s / {t_cf:.3f} s", target + " each way"))
    worst = max(measure(n)[2] for n in ORDERS)
    rows.append(("round trip F→C→F, 20-1000 stages, worst relative error in any R, τ",
                 "1e-15 up to 20 stages; beyond: minutes", f"{worst:.1e}", "≤ 1e-9"))
    return rows


if __name__ == "__main__":
    print(f"{'order':>6} {'F->C s':>8} {'C->F s':>8} {'round trip':>11}")
    for n in ORDERS:
        t_fc, t_cf, err = measure(n)
        print(f"{n:>6} {t_fc:>8.4f} {t_cf:>8.4f} {err:>11.1e}")
