"""Safe fast drive: speed-up over the constant duty, junction limit (closed form and ngspice),
agreement with a brute-force two-phase search, closed-form hold, constant-duty and release
times, device effects, and the command line."""

from __future__ import annotations

import json
import math
import shutil

import numpy as np
import pytest
from scipy.optimize import brentq

from spicethermal.cli import main as cli
from spicethermal.core.errors import DataFormatError
from spicethermal.core.ladder import Foster
from spicethermal.drive.dynamics import Dynamics, switched_peaks
from spicethermal.drive.optimize import optimize_drive
from spicethermal.effects import Effect
from spicethermal.engines.pwm import envelope, steady_state
from spicethermal.model import Schedule, ThermalModel

#: The paper-like actuator of the issue: Rth 146 K/W.
DEMO_R = (6.0, 20.0, 50.0, 70.0)
DEMO_TAU = (2e-4, 5e-3, 0.4, 12.0)
AMBIENT = 25.0


@pytest.fixture(scope="module")
def demo() -> ThermalModel:
    return ThermalModel(Foster.from_tau(DEMO_R, DEMO_TAU))


@pytest.fixture(scope="module")
def cavity_drive(demo):
    """Cauer node 2 (the cavity) to 60 °C, junction peak <= 90 °C, 2 W heater at 1 kHz."""
    return optimize_drive(demo, 90.0, 60.0, AMBIENT, p_max_w=2.0, f_pwm_hz=1000.0, node=2,
                          release_c=40.0)


# ------------------------------------------------------------------------------ the demo
def test_cavity_drive_is_fast_and_safe(cavity_drive, demo):
    r = cavity_drive
    cauer = demo.ladder.to_cauer()
    # hold duty: the steady state of Cauer node 2 is P·d·(R2 + R3 + ...)
    assert r.hold_duty == pytest.approx((60.0 - AMBIENT) / (2.0 * sum(cauer.r[2:])), rel=1e-12)
    assert r.speedup >= 3.0
    assert r.time_to_target_s < r.constant_duty_time_to_target_s / 3
    # the exact switched junction peak respects the limit and the boost uses the headroom
    assert r.peak_junction_c <= 90.0
    assert r.peak_junction_c > 90.0 - 0.05
    assert r.schedule[0][1] == 1.0 and r.schedule[-1][1] == r.hold_duty
    # the node really sits in the band from the time to target on (averaged simulation)
    t = np.linspace(r.time_to_target_s * 1.001, 200.0, 4000)
    node = r.model.simulate(t, r.power_schedule(), AMBIENT).theta_k[:, 2] + AMBIENT
    assert np.max(np.abs(node - 60.0)) <= r.tol_k + 1e-9
    before = r.model.simulate([r.time_to_target_s * 0.98], r.power_schedule(), AMBIENT)
    assert before.theta_k[0, 2] + AMBIENT < 60.0 - r.tol_k


def test_junction_drive_speedup(demo):
    r = optimize_drive(demo, 90.0, 60.0, AMBIENT, p_max_w=1.0, two_phase=False)
    assert r.hold_duty == pytest.approx(35.0 / 146.0, rel=1e-12)
    assert r.speedup >= 3.0
    assert r.peak_junction_c <= 90.0


def test_exact_switched_peaks_match_the_cold_start_envelope(demo):
    """The modal period map against pwm.envelope (independent closed form)."""
    dyn = Dynamics(demo, AMBIENT, 1.5, 2000.0)
    t, pk = switched_peaks(dyn, [(0, 300, 0.4)], 0.4, 0)
    ref, _ = envelope(demo.ladder, 1.5, 2000.0, 0.4, np.arange(1, 301))
    np.testing.assert_allclose(t, (np.arange(300) + 0.4) / 2000.0, rtol=1e-12)
    np.testing.assert_allclose(pk, ref, rtol=1e-10, atol=1e-10)


def test_constant_duty_and_release_times_closed_form(demo):
    r = optimize_drive(demo, 90.0, 60.0, AMBIENT, p_max_w=1.0, release_c=40.0,
                       two_phase=False)
    f = demo.ladder
    p_hold = r.hold_duty * r.p_max_w
    # constant duty from cold: the junction rise P·Zth(t) enters the band at target - tol
    t_c = brentq(lambda t: p_hold * float(f.zth(t)) - (35.0 - r.tol_k), 1e-6, 1e4, xtol=1e-14)
    assert r.constant_duty_time_to_target_s == pytest.approx(t_c, rel=1e-7)
    # release from the steady hold, power off: P·Σ r_i e^{-t/τ_i} falls to 15 K
    t_r = brentq(lambda t: p_hold * float(f.cooling(t)) - 15.0, 1e-6, 1e4, xtol=1e-14)
    assert r.release.time_s == pytest.approx(t_r, rel=1e-7)
    # a keep-warm duty slows the release down
    slow = optimize_drive(demo, 90.0, 60.0, AMBIENT, p_max_w=1.0, release_c=40.0,
                          keep_warm_duty=0.05, two_phase=False)
    assert slow.release.time_s > r.release.time_s


# ------------------------------------------------------------------ two-phase brute force
def _brute_two_phase(foster: Foster, p_w: float, f_hz: float, hold: float, lim_k: float,
                     tgt_k: float, tol: float) -> tuple[float, float, float]:
    """Grid search over boost length and duty with the Foster closed form (junction node).

    Constraint model of the optimizer: period-averaged junction plus the periodic ripple
    of the duty in force. Settling: last exit from the band, interpolated on a dense grid.
    Boost lengths: a log grid over [1 period, 3 s] plus every 4 ms over [0.1, 1.5] s;
    duties every 0.005.
    """
    period = 1 / f_hz
    t = np.unique(np.concatenate([np.geomspace(period / 4, 30.0, 2000),
                                  np.arange(0.1, 2.0, 2e-3)]))
    duties = np.minimum(np.arange(hold, 1.0 + 1e-9, 0.005), 1.0)
    rip = np.array([steady_state(foster, p_w, f_hz, d).peak_k - d * p_w * foster.rth
                    for d in [*duties, hold]])
    base = hold * p_w * foster.zth(t)
    lengths = np.unique(np.round(np.concatenate([np.geomspace(1, 3.0 / period, 200),
                                                 np.arange(0.1, 1.5, 4e-3) / period])))
    best = (math.inf, 0.0, 0.0)
    for n in lengths:
        tb = n * period
        step = foster.zth(t) - foster.zth(np.maximum(t - tb, 0.0)) * (t > tb)
        y = base + (duties - hold)[:, None] * p_w * step
        peak = np.maximum(np.max(np.where(t <= tb, y, -np.inf), axis=1) + rip[:-1],
                          np.max(np.where(t >= tb, y, -np.inf), axis=1) + rip[-1])
        err = np.abs(y - tgt_k) - tol
        out = err > 0
        last = y.shape[1] - 1 - np.argmax(out[:, ::-1], axis=1)
        for q in np.nonzero((peak <= lim_k) & ~out[:, -1] & out.any(axis=1))[0]:
            i = last[q]
            ts = t[i] + err[q, i] / (err[q, i] - err[q, i + 1]) * (t[i + 1] - t[i])
            if ts < best[0]:
                best = (float(ts), float(tb), float(duties[q]))
    return best


def test_two_phase_agrees_with_brute_force():
    foster = Foster.from_tau([30.0, 70.0], [0.01, 1.0])
    model = ThermalModel(foster)
    r = optimize_drive(model, 70.0, 55.0, AMBIENT, p_max_w=1.0, f_pwm_hz=1e4)
    t_bf, tb_bf, d_bf = _brute_two_phase(foster, 1.0, 1e4, r.hold_duty, 45.0, 30.0, r.tol_k)
    tp = r.two_phase
    assert tp is not None
    assert tp.time_to_target_s == pytest.approx(t_bf, rel=0.01)
    assert tp.boost_s == pytest.approx(tb_bf, rel=0.02)
    assert tp.boost_duty == pytest.approx(d_bf, abs=0.01)
    # the junction limit binds the two-phase drive, and the general profile is faster still
    assert tp.peak_junction_c == pytest.approx(70.0, abs=0.3)
    assert r.method == "profile" and r.time_to_target_s < tp.time_to_target_s / 3


# ------------------------------------------------------------------------------ effects
@pytest.fixture(scope="module")
def nonlinear_drive():
    """Temperature coefficient and a phase change at Cauer node 1; 3 W heater at 1 kHz."""
    lad = Foster.from_tau([20.0, 80.0], [5e-3, 2.0]).to_cauer()
    tc = Effect.create("temperature-coefficient", alpha_per_k=-0.003)
    pc = Effect.create("phase-change", t_c=45.0, width_k=2.0, latent_j=0.02, node=1)
    model = ThermalModel(lad, (tc, pc))
    return optimize_drive(model, 85.0, 55.0, AMBIENT, p_max_w=3.0, f_pwm_hz=1000.0, node=1,
                          two_phase=False)


def test_nonlinear_model_honours_device_effects(nonlinear_drive):
    r = nonlinear_drive
    model = r.model
    # the hold duty is the self-consistent steady state of the nonlinear network
    assert model.steady_nodes(3.0 * r.hold_duty, AMBIENT)[1] == pytest.approx(30.0, abs=1e-6)
    linear = optimize_drive(ThermalModel(model.ladder), 85.0, 55.0, AMBIENT, p_max_w=3.0,
                            node=1, two_phase=False)
    assert r.hold_duty != pytest.approx(linear.hold_duty, rel=1e-3)
    assert r.peak_method == "average + periodic ripple"
    assert 85.0 - 0.15 < r.peak_junction_c <= 85.0 - 0.05
    assert r.speedup >= 3.0
    # the node (averaged nonlinear simulation) stays in the band after the time to target
    t = np.linspace(r.time_to_target_s * 1.01, 40.0, 400)
    y = model.simulate(t, r.power_schedule(), AMBIENT).theta_k[:, 1] + AMBIENT
    assert np.max(np.abs(y - 55.0)) <= r.tol_k + 0.05


@pytest.mark.ngspice
@pytest.mark.skipif(shutil.which("ngspice") is None, reason="ngspice not installed")
def test_ngspice_nonlinear_drive_respects_t_max(nonlinear_drive):
    """Behavioural TC resistors and phase-change capacitor, switched drive in ngspice."""
    from spicethermal.spice.lib import NgspiceBatch

    r = nonlinear_drive
    wave = NgspiceBatch().run(r.spice_bench(tmax_s=r.period_s / 20), ["V(TJ)", "V(X1.N1)"])
    assert r.bench_offset_c == r.ambient_c  # TREF grounded, the ambient passed as TOFFSET
    tj = wave["V(TJ)"] + r.bench_offset_c
    assert np.max(tj) <= r.t_max_c + 0.05
    assert np.max(tj) > r.t_max_c - 0.5  # the boost really uses the headroom
    assert abs(wave["V(X1.N1)"][-1] + r.bench_offset_c - r.target_c) <= r.tol_k + 0.05


# ------------------------------------------------------------------------------ errors
@pytest.mark.parametrize(("kwargs", "match"), [
    ({"t_max_c": 60.0, "target_c": 59.0}, "not safely reachable"),
    ({"t_max_c": 400.0, "target_c": 300.0, "p_max_w": 1.0}, "not reachable"),
    ({"t_max_c": 90.0, "target_c": 60.0, "node": 4}, "node"),
    ({"t_max_c": 20.0, "target_c": 60.0}, "above the ambient"),
    ({"t_max_c": 90.0, "target_c": 95.0}, "between"),
    ({"t_max_c": 90.0, "target_c": 60.0, "f_pwm_hz": -1.0}, "freq_hz"),
    ({"t_max_c": 90.0, "target_c": 60.0, "release_c": 70.0}, "below the target"),
    ({"t_max_c": 90.0, "target_c": 60.0, "release_c": 30.0, "keep_warm_duty": 0.2},
     "not reachable"),
])
def test_bad_input_is_named(demo, kwargs, match):
    kwargs = {"p_max_w": 2.0, "two_phase": False, **kwargs}
    with pytest.raises(DataFormatError, match=match):
        optimize_drive(demo, **kwargs)


def test_default_power_is_the_safe_dc_power(demo):
    r = optimize_drive(demo, 90.0, 60.0, AMBIENT, two_phase=False)
    assert r.p_max_w == pytest.approx(65.0 / 146.0, rel=1e-12)
    assert r.peak_junction_c <= 90.0


# ------------------------------------------------------------------------------ CLI
def test_cli_json_plot_and_deck(demo, tmp_path, capsys):
    path = demo.save(tmp_path / "act.json")
    fig, deck = tmp_path / "drive.png", tmp_path / "drive.cir"
    code = cli.main(["drive", str(path), "--t-max", "90", "--target", "60", "--power", "2",
                     "--node", "2", "--json", "--plot", str(fig), "--spice", str(deck)])
    assert code == 0
    doc = json.loads(capsys.readouterr().out)
    for key in ("time_to_target_s", "constant_duty_time_to_target_s", "peak_junction_c",
                "schedule"):
        assert key in doc
    assert doc["schedule"][0] == {"t_s": 0.0, "duty": 1.0}
    assert doc["constant_duty_time_to_target_s"] / doc["time_to_target_s"] >= 3
    assert fig.stat().st_size > 10_000
    text = deck.read_text()
    assert ".SUBCKT HEATER TJ TREF" in text and "PULSE(" in text


def test_cli_errors_are_one_line(demo, tmp_path, capsys):
    path = demo.save(tmp_path / "act.json")
    assert cli.main(["drive", str(path), "--t-max", "60", "--target", "59", "--power", "2"]) == 2
    err = capsys.readouterr().err.strip()
    assert "not safely reachable" in err and len(err.splitlines()) == 1
    assert cli.main(["drive", str(tmp_path / "nope.json"), "--t-max", "90",
                     "--target", "60"]) == 2
    assert len(capsys.readouterr().err.strip().splitlines()) == 1
    with pytest.raises(SystemExit) as exc:
        cli.main(["drive", str(path), "--t-max", "90", "--target", "60", "--node", "-1"])
    assert exc.value.code == 2


# ------------------------------------------------------------------------------ ngspice
@pytest.mark.ngspice
@pytest.mark.skipif(shutil.which("ngspice") is None, reason="ngspice not installed")
def test_ngspice_switched_drive_respects_t_max(cavity_drive):
    """The exported schedule, switched at 1 kHz in ngspice over boost, ride and arrival."""
    from spicethermal.spice.lib import NgspiceBatch

    r = cavity_drive
    window = r.verification_window_s()
    assert window >= r.time_to_target_s
    wave = NgspiceBatch().run(r.spice_bench(tstop_s=window, tmax_s=r.period_s / 100),
                              ["V(TJ)", "V(X1.N2)"])
    tj = wave["V(TJ)"] + r.bench_offset_c
    assert np.max(tj) <= r.t_max_c + 0.05
    sel = r.trace.exact_t_s <= window
    assert np.max(tj) == pytest.approx(np.max(r.trace.exact_peak_c[sel]), abs=0.01)
    # the cavity arrives: within the band at the end of the window, as predicted
    node_end = wave["V(X1.N2)"][-1] + r.bench_offset_c
    assert abs(node_end - r.target_c) <= r.tol_k
    mean = r.model.simulate([wave.t_s[-1]], r.power_schedule(), AMBIENT).theta_k[0, 2]
    assert node_end == pytest.approx(mean + AMBIENT, abs=0.05)


def test_spice_sources_energy(cavity_drive):
    """Every interval's PULSE carries P·duty·periods/f of energy; the hold runs forever."""
    r = cavity_drive
    lines = r.spice_sources()
    assert len(lines) == sum(1 for _, d in r.schedule if d > 0)
    for (t, d), line in zip(r.schedule, lines, strict=True):
        args = [float(x) for x in line.split("(", 1)[1].rstrip(")").split()]
        assert args[2] == pytest.approx(t, abs=1e-15)
        rise, fall, width = args[3], args[4], args[5]
        energy = args[1] * (width + (rise + fall) / 2)
        if len(args) == 8:  # counted pulses
            k = r.schedule.index((t, d))
            length = r.schedule[k + 1][0] - t
            assert energy * args[7] == pytest.approx(r.p_max_w * d * length, rel=1e-9)
        else:
            assert (t, d) == r.schedule[-1]
            assert energy * r.f_pwm_hz == pytest.approx(r.p_max_w * d, rel=1e-9)


def test_schedule_is_whole_periods(cavity_drive):
    r = cavity_drive
    n = np.array([t for t, _ in r.schedule]) * r.f_pwm_hz
    np.testing.assert_allclose(n, np.round(n), atol=1e-6)
    assert isinstance(r.power_schedule(), Schedule)
    assert r.duty_at(0.0) == 1.0 and r.duty_at(1e6) == r.hold_duty


@pytest.mark.ngspice
@pytest.mark.skipif(shutil.which("ngspice") is None, reason="ngspice not installed")
def test_cli_verify_runs_the_deck(tmp_path, capsys):
    path = ThermalModel(Foster.from_tau([30.0, 70.0], [0.01, 1.0])).save(tmp_path / "m.json")
    code = cli.main(["drive", str(path), "--t-max", "70", "--target", "55", "--power", "1",
                     "--verify", "--json"])
    assert code == 0
    doc = json.loads(capsys.readouterr().out)
    ng = doc["ngspice"]
    assert ng["ngspice_peak_junction_c"] <= 70.05
    assert ng["ngspice_peak_junction_c"] == pytest.approx(ng["predicted_peak_junction_c"],
                                                          abs=0.01)
    assert doc["ripple_margin_k"] >= 0


def test_smoothing_keeps_energy_and_leaves_the_boost():
    from spicethermal.drive.profile import smooth

    steps = [(0, 10, 1.0), (10, 2, 0.9), (12, 2, 0.3), (14, 2, 0.8), (16, 3, 0.4), (19, 3, 0.6),
             (22, 4, 0.5)]
    out = smooth(steps, first=1)
    assert [s[:2] for s in out] == [s[:2] for s in steps]
    energy = sum(n * d for _, n, d in steps)
    assert sum(n * d for _, n, d in out) == pytest.approx(energy, rel=1e-12)
    assert out[0] == steps[0] and out[1][2] != 0.9
    d = np.array([s[2] for s in out[1:]])
    assert np.ptp(d) < np.ptp([s[2] for s in steps[1:]]) / 2


# ------------------------------------------------------------------------------ the check
def _switched(r, t_end: float) -> Schedule:
    """The drive as a rectangular train of whole periods up to ``t_end`` (ideal edges)."""
    ts, ps = [], []
    period = r.period_s
    for k in range(round(t_end / period)):
        d = r.duty_at((k + 0.5) * period)
        ts += [k * period, (k + d) * period]
        ps += [r.p_max_w, 0.0]
    keep = np.concatenate([np.diff(ts) > 0, [True]])  # a duty of 1 has no off-phase
    return Schedule(tuple(np.array(ts)[keep]), tuple(np.array(ps)[keep]))


def test_switched_state_is_the_switched_trajectory(cavity_drive):
    r = cavity_drive
    for t in (r.schedule[2][0], r.schedule[-1][0] + 7 * r.period_s):
        exact = r.model.simulate([t], _switched(r, t), AMBIENT).theta_k[0]
        np.testing.assert_allclose(r.switched_state(t), exact, rtol=1e-9, atol=1e-9)
    assert r.schedule_from(r.schedule[2][0])[0] == (0.0, r.schedule[2][1])


@pytest.mark.ngspice
@pytest.mark.skipif(shutil.which("ngspice") is None, reason="ngspice not installed")
def test_check_in_parallel_pieces_is_the_one_long_run():
    from spicethermal.drive.check import verify
    from spicethermal.spice.lib import NgspiceBatch

    r = optimize_drive(ThermalModel(Foster.from_tau([30.0, 70.0], [0.01, 1.0])), 70.0, 55.0,
                       p_max_w=1.0)
    whole = NgspiceBatch().run(r.spice_bench(), ["V(TJ)"])["V(TJ)"]  # from cold at 1/100 period
    check = verify(r, n=3)
    assert check["pieces"] == 4  # the boost at duty 1, then three switched pieces
    assert 0 < check["join_k"] < 2e-3  # each piece ends where the exact state starts the next
    assert check["ngspice_peak_junction_c"] == pytest.approx(float(whole.max()), abs=2e-3)
    assert check["ngspice_peak_junction_c"] == pytest.approx(check["predicted_peak_junction_c"],
                                                             abs=0.01)
