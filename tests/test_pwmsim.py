"""PWM in ngspice from the periodic steady state, against the closed form and shooting."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest

from spicethermal.cli.main import main
from spicethermal.core.errors import DataFormatError, SimulationError
from spicethermal.effects import Effect
from spicethermal.engines.pwm import PwmState
from spicethermal.engines.pwmsim import SpicePwm, pwm_state, pwm_waveform, resolve_engine
from spicethermal.model import ThermalModel

FREQS = (500.0, 1e3, 3e3, 5e3, 10e3, 25e3)
DUTIES = (0.2, 0.5, 0.8)
POWER_W = 0.094
WINDOW_S = 1e-4
TOL_K = 0.02  # the acceptance bound; runs are typically within 2e-4 K

needs_ngspice = pytest.mark.skipif(shutil.which("ngspice") is None, reason="no ngspice binary")


def _grid():
    return [(f, d) for f in FREQS for d in DUTIES]


def _close(a: PwmState, b: PwmState, tol: float = TOL_K) -> float:
    worst = max(abs(a.peak_k - b.peak_k), abs(a.reading_k - b.reading_k),
                abs(a.valley_k - b.valley_k), abs(a.mean_k - b.mean_k))
    assert worst < tol, (a, b)
    return worst


# ------------------------------------------------------------------------------ waveform
@pytest.mark.parametrize("freq, duty, window", [(1e3, 0.5, 0.0), (25e3, 0.2, 1e-4),
                                                (500.0, 0.8, 1e-4), (1e3, 1.0, 1e-4),
                                                (1e3, 0.3, 1e-9)])
def test_waveform_energy_timing_and_corners(freq, duty, window):
    periods = 3
    pts, t_read = pwm_waveform(2.0, freq, duty, periods, window)
    t, p = np.array(pts).T
    period = 1 / freq
    assert np.all(np.diff(t) > 0)
    assert t[0] == 0 and t[-1] == pytest.approx(t_read, rel=1e-15)
    assert t_read == pytest.approx((periods + duty) * period + window, rel=1e-14)
    for k in range(periods):  # every whole period carries exactly P·D·T
        grid = np.union1d(t, [k * period, (k + 1) * period])
        grid = grid[(grid >= k * period) & (grid <= (k + 1) * period)]
        energy = np.trapezoid(np.interp(grid, t, p), grid)
        assert energy == pytest.approx(2.0 * duty * period, rel=1e-12)
    # power is off during the window (after the last falling ramp)
    if window > 1e-4 * period:
        assert p[-1] == 0 and p[-2] == 0


def test_waveform_zero_duty_and_bad_input():
    pts, t_read = pwm_waveform(1.0, 1e3, 0.0, 2, 1e-4)
    assert [p for _, p in pts] == [0.0, 0.0] and t_read == pytest.approx(2e-3 + 1e-4)
    with pytest.raises(DataFormatError, match="duty"):
        pwm_waveform(1.0, 1e3, 1.5, 2)
    with pytest.raises(DataFormatError, match="periods"):
        pwm_waveform(1.0, 1e3, 0.5, 0)


def test_engine_choice_and_validation(actuator):
    linear = ThermalModel(actuator)
    tc = linear.with_effects([Effect.create("temperature-coefficient", alpha_per_k=-3e-3)])
    assert resolve_engine("auto", linear) == "analytic"
    assert resolve_engine("auto", tc) == "ngspice"
    pc = tc.with_effects([*tc.effects, Effect.create("phase-change", t_c=40.0, latent_j=0.01)])
    assert resolve_engine("auto", pc) == "ngspice"
    assert resolve_engine("pyspice", pc) == "pyspice"
    assert pwm_state(linear, POWER_W, 1e3, 0.5, WINDOW_S) == \
        linear.pwm(POWER_W, 1e3, 0.5, WINDOW_S)
    with pytest.raises(DataFormatError, match="engine"):
        resolve_engine("spectre", linear)
    for kw, word in [({"engine": "xyce"}, "engine"), ({"periods": 1}, "periods"),
                     ({"dialect": "hspice"}, "dialect"), ({"topology": "pi"}, "topology"),
                     ({"tol_k": 0.0}, "tol_k")]:
        with pytest.raises(DataFormatError, match=word):
            SpicePwm(linear, **kw)


def test_initial_conditions_are_the_nodal_rises(actuator):
    """.ic values are tref + θ of the model's network; the junction's is the closed-form valley."""
    m = ThermalModel(actuator)
    ic = SpicePwm(m, tref_c=20.0).initial_conditions(POWER_W, 1e3, 0.5)
    assert [n for n, _ in ic] == ["TJ", "X1.N1", "X1.N2", "X1.N3"]
    valley = m.pwm(POWER_W, 1e3, 0.5).valley_k
    assert ic[0][1] - 20.0 == pytest.approx(valley, abs=1e-9)
    # Foster inner nodes hold the sums of the stage rises below them: decreasing to TREF
    assert all(a[1] > b[1] > 20.0 for a, b in zip(ic, ic[1:], strict=False))


# ------------------------------------------------------------------------------ ngspice
@pytest.mark.ngspice
@needs_ngspice
def test_grid_batch_matches_closed_form(actuator):
    """All 18 points of Table 2's grid: ngspice -b within 0.02 K of the closed form."""
    m = ThermalModel(actuator)
    sp = SpicePwm(m, engine="ngspice")
    worst = 0.0
    for f, d in _grid():
        run = sp.run(POWER_W, f, d, WINDOW_S)
        assert run.drift_k <= sp.tol_k
        worst = max(worst, _close(run.state, m.pwm(POWER_W, f, d, WINDOW_S)))
    assert worst < 2e-3  # what the runs actually reach (1e-4 K typical)


@pytest.mark.ngspice
@needs_ngspice
def test_grid_runs_in_parallel_in_order(actuator):
    """The pool keeps the order of the points, with power and window per point."""
    m = ThermalModel(actuator)
    freqs, duties = (25e3, 500.0, 3e3), (0.2, 0.8, 0.5)
    states = SpicePwm(m).grid([0.05, 0.094, 0.2], freqs, duties, window_s=[1e-4, 0.0, 1e-4])
    for s, f, d, p, w in zip(states, freqs, duties, [0.05, 0.094, 0.2], [1e-4, 0.0, 1e-4],
                             strict=True):
        assert (s.freq_hz, s.duty, s.power_w, s.window_s) == (f, d, p, w)
        _close(s, m.pwm(p, f, d, w), 2e-3)


@pytest.mark.ngspice
@needs_ngspice
@pytest.mark.parametrize("freq", [1.0, 10.0, 100.0])
def test_low_frequencies_are_periodic_and_exact(actuator, freq):
    """Down to 1 Hz (edges shortened below the fastest τ; ripple of kelvins): periodic, and
    within 2 mK of the closed form."""
    m = ThermalModel(actuator)
    for d in (0.2, 0.8):
        run = SpicePwm(m).run(POWER_W, freq, d, WINDOW_S)
        assert run.drift_k < 1e-3
        _close(run.state, m.pwm(POWER_W, freq, d, WINDOW_S), 2e-3)


@pytest.mark.ngspice
def test_grid_pyspice_matches_closed_form(actuator):
    m = ThermalModel(actuator)
    states = SpicePwm(m, engine="pyspice").grid(POWER_W, *zip(*_grid(), strict=True),
                                                window_s=WINDOW_S)
    for s, (f, d) in zip(states, _grid(), strict=True):
        assert (s.freq_hz, s.duty, s.window_s) == (f, d, WINDOW_S)
        _close(s, m.pwm(POWER_W, f, d, WINDOW_S))


@pytest.mark.ngspice
@needs_ngspice
@pytest.mark.parametrize("dialect", ["ngspice", "pspice", "ltspice"])
@pytest.mark.parametrize("topology", ["foster", "cauer"])
def test_dialects_and_topologies(actuator, dialect, topology):
    m = ThermalModel(actuator)
    sp = SpicePwm(m, dialect=dialect, topology=topology)
    for f, d, w in [(25e3, 0.2, WINDOW_S), (500.0, 0.8, WINDOW_S), (3e3, 0.5, 0.0)]:
        _close(sp.state(POWER_W, f, d, w), m.pwm(POWER_W, f, d, w))


@pytest.mark.ngspice
@needs_ngspice
def test_nonlinear_model_matches_shooting(actuator):
    """Temperature coefficient (behavioural resistors in SPICE) vs ThermalModel.pwm shooting."""
    m = ThermalModel(actuator, (Effect.create("temperature-coefficient", alpha_per_k=-3e-3),))
    linear = ThermalModel(actuator)
    for f, d in [(500.0, 0.8), (25e3, 0.2)]:
        ref = m.pwm(POWER_W, f, d, WINDOW_S, tref_c=25.0)
        got = pwm_state(m, POWER_W, f, d, WINDOW_S, engine="auto", tref_c=25.0)
        _close(got, ref)
        # the effect is there: Rth falls as the junction heats, R = R0 (1 + α ΔT) at the mean
        lin = linear.pwm(POWER_W, f, d).mean_k
        assert got.mean_k == pytest.approx(lin * (1 - 3e-3 * got.mean_k), rel=1e-3)
        assert got.mean_k < lin - 0.02


@pytest.mark.ngspice
def test_wrong_start_is_caught(actuator, monkeypatch):
    """A start away from the periodic steady state drifts: the run must refuse it."""
    m = ThermalModel(actuator)
    monkeypatch.setattr(SpicePwm, "initial_conditions",
                        lambda self, *a: [("TJ", 25.0), ("X1.N1", 25.0), ("X1.N2", 25.0),
                                          ("X1.N3", 25.0)])
    with pytest.raises(SimulationError, match="not periodic"):
        SpicePwm(m, engine="pyspice").state(POWER_W, 1e3, 0.5, WINDOW_S)


# ------------------------------------------------------------------------------ command
def _model_file(tmp_path, actuator, effects=()):
    return str(ThermalModel(actuator, effects).save(tmp_path / "m.json"))


def test_pwm_command_json_analytic(tmp_path, actuator, capsys):
    path = _model_file(tmp_path, actuator)
    assert main(["pwm", path, "--freq", "25e3", "--duty", "0.2", "--power", "0.094",
                 "--window", "1e-4", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert set(doc) == {"peak_k", "mean_k", "valley_k", "reading_k"}
    ref = ThermalModel(actuator).pwm(0.094, 25e3, 0.2, 1e-4)
    assert doc == ref.as_json()


@pytest.mark.ngspice
@needs_ngspice
def test_pwm_command_ngspice_text(tmp_path, actuator, capsys):
    path = _model_file(tmp_path, actuator)
    assert main(["pwm", path, "--freq", "1000", "--duty", "0.5", "--power", "0.094",
                 "--engine", "ngspice"]) == 0
    out = capsys.readouterr().out
    assert "reading" in out and "ngspice" in out
    ref = ThermalModel(actuator).pwm(0.094, 1e3, 0.5)
    line = next(x for x in out.splitlines() if x.startswith("peak"))
    assert float(line.split()[1]) == pytest.approx(ref.peak_k, abs=TOL_K)


@pytest.mark.parametrize("argv, word", [
    (["--freq", "0", "--duty", "0.5", "--power", "0.1"], "freq"),
    (["--freq", "1e3", "--duty", "2", "--power", "0.1"], "duty"),
    (["--freq", "1e3", "--duty", "0.5", "--power", "abc"], "power"),
    (["--freq", "1e3", "--duty", "0.5", "--power", "0.1", "--engine", "xyce"], "engine"),
    (["--freq", "1e3", "--duty", "0.5", "--power", "0.1", "--window", "-1"], "window"),
    (["--duty", "0.5", "--power", "0.1"], "freq"),
])
def test_pwm_command_bad_input(tmp_path, actuator, capsys, argv, word):
    path = _model_file(tmp_path, actuator)
    with pytest.raises(SystemExit) as exc:
        main(["pwm", path, *argv])
    assert exc.value.code == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and word in err


def test_pwm_command_bad_model(tmp_path, capsys):
    bad = tmp_path / "bad.json"
    bad.write_text("{\"format\": \"nope\"}")
    assert main(["pwm", str(bad), "--freq", "1e3", "--duty", "0.5", "--power", "0.1"]) == 2
    assert main(["pwm", str(tmp_path / "none.json"), "--freq", "1e3", "--duty", "0.5",
                 "--power", "0.1"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 2 and "format" in err[0] and "no such file" in err[1]


# ------------------------------------------------------------------------------ Fig. 8
def test_fig8_curves(actuator):
    from spicethermal.engines.pwm import r_duty_eq3, r_duty_exact
    from spicethermal.viz.plots import FIG8_DUTIES, plot_r_duty

    ax = plot_r_duty(actuator)
    lines = ax.get_lines()
    assert len(lines) == 2 * len(FIG8_DUTIES)
    for k, d in enumerate(FIG8_DUTIES):
        solid, dashed = lines[2 * k], lines[2 * k + 1]
        t = solid.get_xdata()
        assert solid.get_linestyle() == "-" and dashed.get_linestyle() == "--"
        assert np.array_equal(solid.get_ydata(), actuator.rth * r_duty_exact(actuator, t, d))
        assert np.array_equal(dashed.get_ydata(), actuator.rth * r_duty_eq3(actuator, t, d))
        assert np.all(solid.get_ydata() <= dashed.get_ydata() + 1e-12)  # eq. 3 is conservative
    assert t[0] < min(actuator.tau) and t[-1] > max(actuator.tau)
    assert ax.get_ylabel().endswith("(K/W)")  # the family in K/W per duty


def test_curves_command(tmp_path, actuator, capsys):
    path = _model_file(tmp_path, actuator)
    out = tmp_path / "fig8.png"
    table = out.with_suffix(".csv")
    assert main(["curves", path, "--plot", str(out), "-o", str(table)]) == 0
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and out.stat().st_size > 10000
    lines = capsys.readouterr().out.splitlines()  # says what it wrote
    assert lines[0].startswith(f"wrote figure {out}: r_D(t) for duty 0, 0.1,")
    assert lines[1].startswith(f"wrote table {table}: peak Zth in K/W for duty 0, 0.1,")
    assert main(["curves", path, "--plot", str(out), "--duty", "0.5", "--duty", "0"]) == 0
    with pytest.raises(SystemExit) as exc:
        main(["curves", path, "--plot", str(out), "--duty", "1.5"])
    assert exc.value.code == 2
    assert main(["curves", str(tmp_path / "none.json"), "--plot", str(out)]) == 2
    assert main(["curves", path]) == 2  # nothing to write
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 3 and "duty" in err[0] and "none.json" in err[1]
    assert "--plot FIG.png" in err[2] and "-o TABLE.csv" in err[2]


@pytest.mark.ngspice
@pytest.mark.parametrize("topology", ["foster", "cauer"])
def test_phase_change_in_ngspice_matches_shooting(actuator, topology):
    # the band sits where the periodic orbit of node 1 lives: the element works hardest here
    model = ThermalModel(actuator, (Effect.create("phase-change", t_c=33.0, width_k=2.0,
                                                  latent_j=0.02, node=1),)).with_topology(topology)
    spice_state = SpicePwm(model, topology=topology).state(POWER_W, 1e3, 0.5, WINDOW_S)
    exact = model.pwm(POWER_W, 1e3, 0.5, WINDOW_S)
    assert spice_state.peak_k == pytest.approx(exact.peak_k, abs=0.02)
    assert spice_state.reading_k == pytest.approx(exact.reading_k, abs=0.02)
