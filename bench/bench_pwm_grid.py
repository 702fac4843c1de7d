"""Speed study: the paper's Table 2 grid in ngspice, from the periodic steady state vs cold start.

Run (prints the numbers)::

    .venv/bin/python bench/bench_pwm_grid.py

Model: the 4-stage actuator ladder of the tests (Rth = 146 K/W, τ from 100 µs to 30 s);
grid: 0.5, 1, 3, 5, 10, 25 kHz × duty 0.2, 0.5, 0.8 at 0.094 W, sample window 100 µs.

*Our way* (:class:`spicethermal.engines.pwmsim.SpicePwm`): each point starts at the periodic steady
state (``.ic`` from the closed form), runs 3 periods plus the sample window, and checks that
the last period repeats the first. Timed for both backends (``ngspice -b`` and PySpice), with
the worst difference from the closed form.

*Naive way*: the same subcircuit under the same PWM source from a cold start (all nodes at the
reference) until the peak is within ``TOL_K`` of the periodic steady state — the same accuracy
bar the fast runs are tested to; it needs ``k`` periods, k from the exact envelope
(:func:`spicethermal.engines.pwm.envelope`), ~ τmax · ln(A/tol) ≈ 5-6 τmax. Running that (150-170 s
of simulated time, up to four million periods) is far too long, so it is extrapolated:
time(k) = time(n1) + (k − n1) · cost per period, the cost per period from the difference of
cold starts of n1 = 50 and 250 periods at every point (start-up excluded). A lower bound
charges every period the cheapest cost measured (a long PULSE run at 1 kHz, linear regime).
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

try:  # the same file serves as a plain script and as a pytest benchmark module
    import pytest
except ImportError:  # pragma: no cover
    pytest = None

from spicethermal.core.ladder import Foster
from spicethermal.engines.pwm import envelope
from spicethermal.engines.pwmsim import SUBCKT, SpicePwm, pwm_waveform
from spicethermal.model import ThermalModel
from spicethermal.spice.lib import NgspiceBatch, Pulse, render_bench

R_K_PER_W = (6.0, 20.0, 50.0, 70.0)
TAU_S = (1e-4, 5e-3, 0.4, 30.0)
FREQS = (500.0, 1e3, 3e3, 5e3, 10e3, 25e3)
DUTIES = (0.2, 0.5, 0.8)
POWER_W = 0.094
WINDOW_S = 1e-4
TOL_K = 0.02
PERIODS_MEASURED = 200


def grid() -> list[tuple[float, float]]:
    return [(f, d) for f in FREQS for d in DUTIES]


def ours(model: ThermalModel, engine: str) -> tuple[float, float]:
    """Wall time of the whole grid and the worst |ngspice − closed form| (peak, reading)."""
    sp = SpicePwm(model, engine=engine)
    sp.state(POWER_W, 1e3, 0.5, WINDOW_S)  # warm up (library load, template compile)
    t0 = time.perf_counter()
    states = [sp.state(POWER_W, f, d, WINDOW_S) for f, d in grid()]
    wall = time.perf_counter() - t0
    worst = max(max(abs(s.peak_k - a.peak_k), abs(s.reading_k - a.reading_k))
                for s, a in ((s, model.pwm(POWER_W, f, d, WINDOW_S))
                             for s, (f, d) in zip(states, grid(), strict=True)))
    return wall, worst


def periods_needed(ladder: Foster, freq: float, duty: float, tol_k: float = TOL_K) -> int:
    """Periods a cold start needs until its peak is within ``tol_k`` of the steady one."""
    steady = envelope(ladder, POWER_W, freq, duty, [1e12])[0][0]
    lo, hi = 1, 1
    while steady - envelope(ladder, POWER_W, freq, duty, [hi])[0][0] > tol_k:
        lo, hi = hi, hi * 2
    while hi - lo > 1:  # bisection on the monotone envelope
        mid = (lo + hi) // 2
        if steady - envelope(ladder, POWER_W, freq, duty, [mid])[0][0] > tol_k:
            lo = mid
        else:
            hi = mid
    return hi


def cold_start_time(lib: Path, freq: float, duty: float, periods: int,
                    source: str = "pwl") -> float:
    """Wall time of an ngspice -b cold-start transient over ``periods`` periods: every node at
    the reference (``.ic``; without it the operating point would use the PWL's first value).

    ``source="pwl"`` is the PWL train the fast runs use; ``"pulse"`` a PULSE source
    (:meth:`Pulse.of`), cheaper per period on long runs (a PWL's corner search grows with its
    length) but at 5 kHz and above it stops ngspice ("timestep too small") or stalls at the
    first edge at t = 0 with the bench's tolerances.
    """
    period = 1 / freq
    if source == "pwl":
        pts, _ = pwm_waveform(POWER_W, freq, duty, periods)
        extra = {"pwl": pts}
    else:
        extra = {"pulse": Pulse.of(freq, duty)}
    cold = [("TJ", 25.0), *((f"X1.N{k}", 25.0) for k in range(1, len(R_K_PER_W)))]
    text = render_bench(lib, SUBCKT, power_w=POWER_W, tstop_s=periods * period,
                        tmax_s=period / 50, tref_c=25.0, title="cold start", ic=cold, **extra)
    t0 = time.perf_counter()
    NgspiceBatch(timeout_s=120).run(text, ["V(TJ)"])
    return time.perf_counter() - t0


def naive(model: ThermalModel) -> tuple[float, float, list[tuple[float, float, int, float]]]:
    """Extrapolated wall time of the naive grid, its lower bound, and per point
    (f, d, periods, seconds)."""
    sp = SpicePwm(model)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        lib = Path(tmp) / "dut.lib"
        lib.write_text(sp.lib_text)
        ns = (PERIODS_MEASURED, 5 * PERIODS_MEASURED, 25 * PERIODS_MEASURED)
        for source in ("pulse", "pwl"):
            t1, t2, t3 = (cold_start_time(lib, 1e3, 0.5, n, source) for n in ns)
            print(f"cold start at 1 kHz, duty 0.5, {source:5}: {ns[0]} / {ns[1]} / {ns[2]} periods "
                  f"in {t1:.2f} / {t2:.2f} / {t3:.2f} s; cost per period "
                  f"{(t2 - t1) / (ns[1] - ns[0]) * 1e3:.3f} ms ({ns[0]}..{ns[1]}), "
                  f"{(t3 - t2) / (ns[2] - ns[1]) * 1e3:.3f} ms ({ns[1]}..{ns[2]})")
            if source == "pulse":
                floor_per_period = (t3 - t2) / (ns[2] - ns[1])  # long, linear regime
        n1, n2 = PERIODS_MEASURED // 4, 5 * PERIODS_MEASURED // 4
        for f, d in grid():  # cost per period without the start-up (difference of two runs)
            a, b = (cold_start_time(lib, f, d, n) for n in (n1, n2))
            per_period = max(b - a, 0.0) / (n2 - n1)
            k = periods_needed(model.ladder, f, d)
            rows.append((f, d, k, a + per_period * (k - n1)))
    floor = floor_per_period * sum(r[2] for r in rows)
    return sum(r[3] for r in rows), floor, rows


def main() -> dict[str, float]:
    model = ThermalModel(Foster.from_tau(R_K_PER_W, TAU_S))
    t_batch, err_batch = ours(model, "ngspice")
    t_shared, err_shared = ours(model, "pyspice")
    t0 = time.perf_counter()
    for f, d in grid():
        model.pwm(POWER_W, f, d, WINDOW_S)
    t_analytic = time.perf_counter() - t0
    t_naive, t_floor, rows = naive(model)
    print("\nnaive cold start, per point (periods to reach the steady peak within "
          f"{TOL_K} K, extrapolated wall time):")
    print(f"{'freq (Hz)':>10} {'duty':>5} {'periods':>10} {'sim time (s)':>13} {'wall (s)':>10}")
    for f, d, k, sec in rows:
        print(f"{f:>10g} {d:>5g} {k:>10d} {k / f:>13.1f} {sec:>10.1f}")
    print(f"\n18-point grid, {POWER_W} W, window {WINDOW_S * 1e6:g} µs, Rth "
          f"{model.rth:g} K/W, τ {TAU_S[0]:g}..{TAU_S[-1]:g} s")
    print(f"  ours, ngspice -b  : {t_batch:7.2f} s   worst |Δ| vs closed form {err_batch:.1e} K")
    print(f"  ours, PySpice     : {t_shared:7.2f} s   worst |Δ| vs closed form {err_shared:.1e} K")
    print(f"  closed form       : {t_analytic * 1e3:7.2f} ms")
    print(f"  naive cold start  : {t_naive:7.0f} s  (= {t_naive / 3600:.1f} h, extrapolated "
          f"per point from PWL cold starts of {PERIODS_MEASURED // 4} and "
          f"{5 * PERIODS_MEASURED // 4} periods)")
    print(f"  naive lower bound : {t_floor:7.0f} s  (= {t_floor / 3600:.1f} h: all periods at the "
          f"cheapest measured cost, a long PULSE run at 1 kHz)")
    print(f"  speed-up          : {t_naive / t_batch:7.0f} x (ngspice -b), "
          f"{t_naive / t_shared:.0f} x (PySpice); at least {t_floor / t_batch:.0f} x and "
          f"{t_floor / t_shared:.0f} x")
    return {"ours_batch_s": t_batch, "ours_shared_s": t_shared, "naive_s": t_floor,
            "err_batch_k": err_batch, "err_shared_k": err_shared}


if pytest is not None:
    @pytest.mark.benchmark
    @pytest.mark.ngspice
    def test_pwm_grid_speed():
        numbers = main()
        assert numbers["ours_batch_s"] < 10 and numbers["err_batch_k"] < TOL_K
        assert numbers["naive_s"] > 100 * numbers["ours_batch_s"]


if __name__ == "__main__":
    main()
    sys.exit(0)
