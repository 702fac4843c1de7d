"""SPICE export: golden files, hostile names, and ngspice runs against the analytic solution."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from conftest import NETLISTS, ramp_response

from spicethermal import pwm, spice
from spicethermal.cli import main
from spicethermal.effects import Effect
from spicethermal.errors import DataFormatError
from spicethermal.ladder import Foster
from spicethermal.model import Schedule, ThermalModel
from spicethermal.netlists import GOLDEN

CASES = [(d, t) for d in spice.DIALECTS for t in spice.TOPOLOGIES]


@pytest.mark.parametrize("filename", sorted(GOLDEN))
def test_golden_netlists_regenerate_identically(filename):
    assert (NETLISTS / filename).read_text() == GOLDEN[filename](), (
        f"netlists/{filename} changed: run `python -m spicethermal.netlists` and review the diff")


@pytest.mark.parametrize("name", ["X\n.control", "1ABC", "A B", "END", "ends", "", "A" * 65,
                                  "ACT;rm", "Ü"])
def test_hostile_names_are_refused(actuator, name):
    with pytest.raises(DataFormatError, match="subcircuit name"):
        spice.render_lib(ThermalModel(actuator), name=name)


def test_comments_cannot_smuggle_directives(actuator):
    m = ThermalModel(actuator, provenance={"device": "diode\n.control\nshell touch /tmp/x\n.endc"})
    text = spice.render_lib(m, name="DUT")
    for line in filter(None, text.splitlines()):
        assert line.startswith(("*", ".SUBCKT", ".ENDS", "R", "C", "B", "G")), line
    assert "* device: diode .control shell touch /tmp/x .endc" in text


@pytest.mark.ngspice
@pytest.mark.parametrize("dialect, topology", CASES)
def test_step_response_in_ngspice_within_0p1_percent(tmp_path, actuator, dialect, topology):
    lib = spice.export(ThermalModel(actuator), tmp_path / "m.lib", dialect, topology, "ACT")
    net = spice.render_bench(lib, "ACT", power_w=1.0, tstop_s=100.0, tmax_s=1.0)
    w = spice.NgspiceBatch().run(net, ["V(TJ)"], dialect)
    sel = (w.t_s >= 1e-6) & (w.t_s <= 100.0)  # six decades and more
    assert np.log10(w.t_s[sel][-1] / w.t_s[sel][0]) >= 6
    exact = ramp_response(actuator, w.t_s[sel], 1e-5)
    err = np.max(np.abs(w["V(TJ)"][sel] - exact)) / actuator.rth
    assert err < 1e-3


@pytest.mark.ngspice
@pytest.mark.parametrize("dialect, topology", CASES)
def test_pwm_response_in_ngspice_from_periodic_state(tmp_path, actuator, dialect, topology):
    model = ThermalModel(actuator).with_topology(topology)
    freq, duty, power, tref = 1e3, 0.3, 0.094, 25.0
    x0 = model.pwm_initial_state(power, freq, duty)
    ic = spice.initial_conditions(model, x0, tref)
    lib = spice.export(model, tmp_path / "m.lib", dialect, topology, "ACT")
    pulse = spice.Pulse.of(freq, duty)
    net = spice.render_bench(lib, "ACT", power_w=power, tstop_s=3 / freq, tmax_s=1 / freq / 200,
                             tref_c=tref, pulse=pulse, ic=ic)
    w = spice.NgspiceBatch().run(net, ["V(TJ)"], dialect)
    exact = tref + pwm.at_phase(actuator, power, freq, duty, w.t_s)
    err = np.max(np.abs(w["V(TJ)"] - exact))
    assert err / actuator.rth < 1e-3
    assert err < 5e-3  # kelvin: the run starts on the periodic orbit and stays there


@pytest.mark.ngspice
def test_pyspice_backend_agrees_with_batch(tmp_path, actuator):
    lib = spice.export(ThermalModel(actuator), tmp_path / "m.lib", "ngspice", "cauer", "ACT")
    net = spice.render_bench(lib, "ACT", power_w=1.0, tstop_s=10.0, tmax_s=0.1)
    a = spice.NgspiceBatch().run(net, ["V(TJ)"])
    b = spice.NgspiceShared().run(net, ["V(TJ)"])
    np.testing.assert_allclose(b.t_s, a.t_s, rtol=1e-12)
    np.testing.assert_allclose(b["V(TJ)"], a["V(TJ)"], rtol=1e-9, atol=1e-12)


@pytest.mark.ngspice
@pytest.mark.parametrize("dialect", spice.DIALECTS)
@pytest.mark.parametrize("topology", spice.TOPOLOGIES)
def test_device_effects_in_ngspice_match_python(tmp_path, dialect, topology):
    ladder = Foster.from_tau([20.0, 80.0], [1e-3, 0.5])
    model = ThermalModel(ladder, (
        Effect.create("temperature-coefficient", alpha_per_k=-4e-3, t0_c=25.0),
        Effect.create("phase-change", t_c=40.0, width_k=2.0, latent_j=0.02, node=1),
    )).with_topology(topology)
    lib = spice.export(model, tmp_path / "m.lib", dialect, topology, "NL")
    tref, toffset = spice.reference_drive(model, 25.0)
    net = spice.render_bench(lib, "NL", power_w=0.3, tstop_s=4.0, tmax_s=4e-3, tref_c=tref,
                             toffset_c=toffset)
    w = spice.NgspiceBatch().run(net, ["V(TJ)"], dialect)
    t = w.t_s[w.t_s > 1e-3]
    rise = 4e-8  # the bench's default ramp, 1e-5 of the maximum step
    py = model.simulate(t, Schedule((0.0, rise / 2), (0.0, 0.3)), tref_c=25.0).tj_k + 25.0
    sim = w["V(TJ)"][w.t_s > 1e-3] + 25.0
    assert np.max(np.abs(sim - py)) < 0.03  # K, of a rise of about 25 K
    lin = ThermalModel(model.ladder).simulate(t, Schedule.step(0.3)).tj_k + 25.0
    assert np.max(np.abs(lin - py)) > 1.0  # the effects matter at this strength


def test_export_command_and_errors(tmp_path, actuator, capsys):
    model = tmp_path / "m.json"
    ThermalModel(actuator).save(model)
    out = tmp_path / "a.lib"
    assert main(["export", str(model), "--dialect", "pspice", "--topology", "cauer",
                 "--name", "ACT", "-o", str(out)]) == 0
    assert ".SUBCKT ACT TJ TREF" in out.read_text()
    assert main(["export", str(model), "--name", "BAD\n.end", "-o", str(tmp_path / "b.lib")]) == 2
    assert not (tmp_path / "b.lib").exists()
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "subcircuit name" in err[0]
    assert main(["export", str(tmp_path / "missing.json"), "-o", str(out)]) == 2


def test_cli_bad_input_is_one_line_without_traceback(tmp_path):
    bad = tmp_path / "m.json"
    bad.write_text("{not json")
    proc = subprocess.run([sys.executable, "-m", "spicethermal.cli", "export", str(bad), "-o",
                           str(tmp_path / "x.lib")], capture_output=True, text=True)
    assert proc.returncode == 2
    assert "Traceback" not in proc.stderr and len(proc.stderr.strip().splitlines()) == 1
    assert str(bad) in proc.stderr and not (tmp_path / "x.lib").exists()
