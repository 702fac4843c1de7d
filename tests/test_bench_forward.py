"""The bench measures the heater's forward voltage Vf(I, T) (issue #46): the firmware's FORWARD
procedure on the simulated plant, the bundle's forward section, the law fitted to it."""

from __future__ import annotations

import json

import numpy as np
import pytest

from spicethermal.bench import client as bc
from spicethermal.bench import protocol as p
from spicethermal.bench import session
from spicethermal.bench.devices import CURVED_TSP, preset
from spicethermal.bench.plant import Frontend
from spicethermal.bench.session import run_bench
from spicethermal.core.errors import DataFormatError, InstrumentError
from spicethermal.fit.diode import fit_electrical
from spicethermal.io.bundle import Bundle
from spicethermal.model import ThermalModel

FAST = {"calibration_c": (25.0, 40.0, 55.0, 70.0), "calibration_settle_s": 200.0}


@pytest.fixture(scope="module")
def measured(tmp_path_factory):
    return run_bench("sim://actuator?seed=4", tmp_path_factory.mktemp("b") / "heater",
                     actions=["calibrate"], **FAST)


def test_the_calibration_run_adds_forward_points(measured):
    doc = json.loads((measured / "bundle.json").read_text())
    assert doc["format"] == "spicethermal-bundle/3"
    assert doc["forward"]["sense_current_a"] == 1e-3
    assert doc["forward"]["raw"].startswith("raw/")  # the frames behind them, saved first
    fwd = Bundle.read(measured).forward
    currents = (1e-3, *session.PLANS["actuator"].forward_currents_a)
    assert fwd.temp_c.size == 4 * len(currents)
    # each current's mean reading is near the current asked for (the DAC's and ADC's steps)
    for k, i in enumerate(currents):
        assert np.allclose(fwd.i_a[k::len(currents)], i, rtol=0.1, atol=5e-4)
    assert set(fwd.t_pulse_s) == {0.0, 2e-5}
    # the plant's diode, read through 10-bit ADCs
    plant = Frontend(preset("actuator"), [CURVED_TSP], 0.0, np.random.default_rng(0))
    truth = [plant.v_diode(i, t) for i, t in zip(fwd.i_a, fwd.temp_c, strict=True)]
    assert np.max(np.abs(fwd.vf_v - truth)) < 5e-3


def test_the_law_fitted_to_them_is_the_plants_diode(measured):
    bundle = Bundle.read(measured)
    model = ThermalModel(preset("actuator").foster)
    fit = fit_electrical(bundle, model)
    assert fit.law.n == pytest.approx(preset("actuator").diode.n, abs=4 * fit.u["n"] + 0.01)
    assert fit.law.rs_ohm == pytest.approx(preset("actuator").diode.rs_ohm, rel=0.05)
    plant = Frontend(preset("actuator"), [CURVED_TSP], 0.0, np.random.default_rng(0))
    # at the heating current (94 mW, about 0.11 A) within a fraction of a millivolt, and at
    # the sense current within the calibration's noise, the sense current's heating apart
    sense_k = 1e-3 * 0.6 * model.rth
    for i, t in ((0.11, 30.0), (0.11, 65.0), (0.3, 50.0)):
        assert abs(fit.law.voltage(i, t + sense_k) - plant.v_diode(i, t)) < 3e-4
    assert fit.rms_k["calibration"] < 0.02


def test_the_client_checks_the_forward_command(measured):
    with bc.BenchClient("sim://actuator?seed=1") as bench:
        assert bench.info.proto >= 3 and bench.info.i_sense_ua == 1000
        with pytest.raises(DataFormatError, match="1 to 8 currents"):
            bench.forward(25.0, 1.0, 4e-5, 1, 0.02, ())
        with pytest.raises(InstrumentError, match="refused forward: bad parameter"):
            bench.forward(25.0, 1.0, 4e-5, 1, 0.02, (1.0,))  # above the board's 0.5 A
        run = bench.forward(25.0, 1.0, 4e-5, 2, 0.02, (0.05, 0.1))
        assert [s.kind for s in run.samples] == [p.KIND_FORWARD] * 4


def test_firmware_without_the_procedure_gives_a_bundle_without_the_section(tmp_path,
                                                                          monkeypatch, capsys):
    # as a protocol-2 device answers: the device's protocol below the procedure's
    monkeypatch.setattr(session, "FORWARD_PROTOCOL", p.PROTOCOL_VERSION + 1)
    out = run_bench("sim://actuator?seed=1", tmp_path / "old", actions=["calibrate"], **FAST)
    assert Bundle.read(out).forward is None
    assert "no forward-voltage procedure" in capsys.readouterr().err
    assert json.loads((out / "bundle.json").read_text())["format"] == "spicethermal-bundle/1"


@pytest.mark.ngspice
@pytest.mark.parametrize("dialect", ("ngspice", "pspice", "ltspice"))
def test_the_exported_part_reproduces_the_benchs_calibration(measured, dialect, tmp_path):
    """Issue #46, check 2, on the simulated bench's own readings: the part exported from the
    law fitted to them, under the sense current alone with its reference swept through the
    calibration's temperatures, gives the calibration's TSP (plus the reference diode's
    offset) within the calibration's noise."""
    from spicethermal.spice.electrothermal import render_electrothermal
    from spicethermal.spice.lib import NgspiceBatch

    bundle = Bundle.read(measured)
    fit = fit_electrical(bundle, ThermalModel(preset("actuator").foster))
    model = ThermalModel(preset("actuator").foster, electrical=fit.law)
    lib = tmp_path / "h.lib"
    lib.write_text(render_electrothermal(model, dialect, "foster", "HEATER",
                                         temperature="absolute"))
    deck = (f"* calibration\n.include {lib}\nX1 A 0 TJ TREF HEATER\nVREF TREF 0 DC 25\n"
            "ISENSE 0 A DC 1m\n.dc VREF 24 71 0.01\n.end\n")
    w = NgspiceBatch(timeout_s=60).run(deck, ["V(A)"], dialect)
    cal = bundle.calibration
    error = np.interp(cal.temp_c, w.t_s, w["V(A)"]) - fit.law.tsp_offset_v - cal.v_tsp_v
    noise = fit.rms_v["calibration"]
    assert np.sqrt(np.mean(error ** 2)) < 1.5 * noise and np.max(np.abs(error)) < 3 * noise
