"""The paper's bench circuit (Fig. 3) around the electrothermal heater: Table 2 as the bench
reads it (issue #46, check 3), and its golden deck."""

from __future__ import annotations

import shutil

import numpy as np
import pytest
from conftest import NETLISTS

from spicethermal.core.errors import DataFormatError
from spicethermal.engines.circuit import CircuitPwm
from spicethermal.model import ThermalModel
from spicethermal.spice.lib import DIALECTS, NgspiceBatch
from spicethermal.spice.netlists import CIRCUIT_EXAMPLE, heater_model

#: The paper's Table 2 grid, at its 94 mW and 100 µs sample window.
FREQS = (500.0, 1e3, 3e3, 5e3, 10e3, 25e3)
DUTIES = (0.2, 0.5, 0.8)
POWER_W, WINDOW_S = 0.094, 1e-4


@pytest.mark.ngspice
@pytest.mark.parametrize("dialect", DIALECTS)
def test_table2_through_the_circuit_is_the_analytic_engine_and_the_bench_reading(dialect):
    """Issue #46, check 3: every point of Table 2 read through the circuit (the heating
    current the power loop sets, the sense current's phase, the TSP at the end of the sample
    window through the calibration) within 0.02 K of the analytic periodic steady state read
    after the same window."""
    model = heater_model()
    f, d = (x.ravel() for x in np.meshgrid(FREQS, DUTIES))
    states = CircuitPwm(model, dialect=dialect).grid(POWER_W, f, d, WINDOW_S)
    analytic = np.array([model.pwm(POWER_W, fi, di, WINDOW_S).reading_k
                         for fi, di in zip(f, d, strict=True)])
    circuit = np.array([s.reading_k for s in states])
    assert np.max(np.abs(circuit - analytic)) < 0.02
    # the junction itself (the sense current's heating taken out) is the model's too
    means = np.array([s.mean_k for s in states])
    exact = np.array([model.pwm(POWER_W, fi, di).mean_k for fi, di in zip(f, d, strict=True)])
    assert np.max(np.abs(means - exact)) < 0.01


@pytest.mark.ngspice
def test_a_run_holds_the_waveforms_and_the_power_loops_current():
    model = heater_model()
    sim = CircuitPwm(model)
    run = sim.run(POWER_W, 1e3, 0.5, WINDOW_S)
    law = model.electrical
    on = run.i_a > 0.99 * (run.i_heat_a + 1e-3)  # the on-phases, their edges left out
    assert run.i_heat_a == pytest.approx(sim.heating_current(POWER_W, 1e3, 0.5))
    # during the on-phases the heating adds P to the sense current's dissipation (within the
    # 0.1 % that Vf changes as the junction heats through an on-phase)
    added = run.vf_v[on] * run.i_a[on] - 1e-3 * law.voltage(1e-3, run.tj_c[on])
    assert np.all(np.abs(added / POWER_W - 1) < 1e-3)
    # Vf falls while the junction heats within an on-phase: the TSP at work
    assert np.ptp(run.vf_v[on]) > 5e-4 and np.corrcoef(run.vf_v[on], run.tj_c[on])[0, 1] < -0.9
    # no window: a bench with an ideal track-and-hold reads the junction at the cut
    ideal = sim.state(POWER_W, 1e3, 0.5)
    assert ideal.reading_k == pytest.approx(model.pwm(POWER_W, 1e3, 0.5).reading_k, abs=0.01)


@pytest.mark.ngspice
@pytest.mark.skipif(shutil.which("ngspice") is None, reason="no ngspice binary")
def test_the_golden_bench_deck_runs_as_written(tmp_path):
    for name in ("actuator_fig3_bench.cir", "actuator_heater_ngspice.lib"):
        shutil.copy(NETLISTS / name, tmp_path / name)
    text = (tmp_path / "actuator_fig3_bench.cir").read_text()
    text = text.replace(".include actuator_heater_ngspice.lib",
                        f".include {tmp_path / 'actuator_heater_ngspice.lib'}")
    w = NgspiceBatch().run(text, ["V(TSP)", "V(TJ)"])
    c = CIRCUIT_EXAMPLE
    t_read = (3 + c["duty"]) / c["freq_hz"] + c["window_s"]
    assert w.t_s[-1] == pytest.approx(t_read)
    law, rth = heater_model().electrical, heater_model().rth
    v = float(w["V(TSP)"][-1]) + float(law.bench_voltage(25.0, rth))
    reading = float(law.bench_temperature(v, rth)) - 25.0
    expect = heater_model().pwm(c["power_w"], c["freq_hz"], c["duty"], c["window_s"]).reading_k
    assert reading == pytest.approx(expect, abs=0.02)


def test_without_a_diode_law_the_circuit_says_what_is_missing():
    with pytest.raises(DataFormatError, match="no diode law"):
        CircuitPwm(ThermalModel(heater_model().ladder))


@pytest.fixture(scope="module")
def fast_drive():
    """A drive of a fast actuator (the heater's law on a ladder of 0.1 ms to 0.4 s): its
    cavity node (Cauer node 2) to 40 °C with the junction's peak at most 60 °C."""
    from spicethermal.core.ladder import Foster
    from spicethermal.drive.optimize import optimize_drive

    model = ThermalModel(Foster.from_tau([6.0, 20.0, 50.0, 70.0], [1e-4, 5e-3, 0.05, 0.4]),
                         electrical=heater_model().electrical)
    return optimize_drive(model, 60.0, 40.0, 25.0, p_max_w=0.5, f_pwm_hz=1000.0, node=2)


@pytest.mark.ngspice
@pytest.mark.parametrize("dialect", DIALECTS)
def test_the_drives_schedule_through_the_circuit_respects_t_max(fast_drive, dialect):
    """Issue #46, check 4: the optimizer's schedule switching the heating current through the
    circuit, from cold: the junction (the sense current's heating included) stays under
    t_max; the current source's power falls as the diode warms, so it stays under the drive's
    own prediction too, and not far from it."""
    from spicethermal.drive.circuit import verify_circuit

    check = verify_circuit(fast_drive, dialect=dialect)
    predicted = float(np.max(fast_drive.trace.exact_peak_c))
    assert predicted > 55.0  # the boost drives the junction close to its limit
    assert check["circuit_peak_junction_c"] <= fast_drive.t_max_c
    assert predicted - 2.0 < check["circuit_peak_junction_c"] < predicted + 0.1
    assert check["window_s"] == pytest.approx(fast_drive.verification_window_s())


@pytest.mark.ngspice
def test_the_pwm_command_runs_table2_through_the_circuit(tmp_path):
    import json
    import subprocess
    import sys

    heater_model().save(tmp_path / "h.json")
    cli = [sys.executable, "-m", "spicethermal.cli.main", "pwm", str(tmp_path / "h.json"),
           "--power", "94m", "--window", "100u"]
    grid = subprocess.run([*cli, "--freq", "500,25k", "--duty", "0.2,0.8", "--engine",
                           "ngspice", "--circuit", "--dialect", "pspice", "--json"],
                          capture_output=True, text=True)
    assert grid.returncode == 0, grid.stderr
    points = json.loads(grid.stdout)["points"]
    assert [(p["freq_hz"], p["duty"]) for p in points] == [(500, 0.2), (25e3, 0.2),
                                                           (500, 0.8), (25e3, 0.8)]
    table = subprocess.run([*cli, "--freq", "500,25k", "--duty", "0.2,0.8", "--engine",
                            "ngspice", "--circuit"], capture_output=True, text=True)
    assert "D=20%" in table.stdout and "bench circuit (ngspice)" in table.stdout
    plot = subprocess.run([*cli, "--freq", "1k", "--duty", "0.5", "--engine", "ngspice",
                           "--circuit", "--plot", str(tmp_path / "c.png")],
                          capture_output=True, text=True)
    assert plot.returncode == 0 and (tmp_path / "c.png").stat().st_size > 10000
    for args, words in ((["--circuit"], "--engine ngspice or pyspice"),
                        (["--plot", str(tmp_path / "x.png")], "--plot")):
        bad = subprocess.run([*cli, "--freq", "1k", "--duty", "0.5", *args],
                             capture_output=True, text=True)
        assert bad.returncode == 2 and words in bad.stderr and "Traceback" not in bad.stderr
    assert not (tmp_path / "x.png").exists()
