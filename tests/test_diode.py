"""The heater diode's law Vf(I, T): the law, its fit (forward points and TSP calibration, with
their self-heating), the model file's ``electrical`` key and the bundle's ``forward`` section."""

from __future__ import annotations

import json

import numpy as np
import pytest
from heaters import K_Q, MODEL, T0K, bench_points

from spicethermal.core.diode import DiodeLaw, linear_terms
from spicethermal.core.errors import DataFormatError
from spicethermal.fit.diode import fit_diode, fit_electrical
from spicethermal.io.bundle import Bundle, CalibrationTable, ForwardTable
from spicethermal.model import ThermalModel


def test_the_law_inverts_in_current_and_temperature():
    law = DiodeLaw(n=1.75, is_a=2.5e-9, rs_ohm=0.57, xti=2.0, eg_ev=1.15)
    i, t = np.geomspace(1e-6, 1.0, 13), np.linspace(-20.0, 150.0, 13)
    v = law.voltage(i, t)
    assert np.allclose(law.current(v, t), i, rtol=1e-12)
    assert np.allclose(law.temperature(v, i), t, atol=1e-9)
    assert np.isnan(law.temperature(5.0, 1e-3))  # no temperature gives 5 V at 1 mA
    # the linear form is the law (I >> IS)
    coef = [1.75 * K_Q, -1.75 * K_Q * np.log(2.5e-9) - 1.15 / T0K, 1.15, -2.0 * K_Q, 0.57]
    assert np.allclose(linear_terms(i[6:], t[6:]) @ coef, v[6:], atol=1e-9)


def test_a_noiseless_law_is_recovered_exactly():
    true = DiodeLaw(n=1.6, is_a=4e-9, rs_ohm=0.3, xti=2.5, eg_ev=1.12)
    t, i = (x.ravel() for x in np.meshgrid([0.0, 25.0, 50.0, 75.0, 100.0], [1e-3, 0.01, 0.1, 1]))
    fit = fit_diode(t, i, true.voltage(i, t))
    law = fit.law
    assert (law.n, law.rs_ohm, law.xti, law.eg_ev) == pytest.approx(
        (1.6, 0.3, 2.5, 1.12), rel=1e-9)
    assert law.is_a == pytest.approx(4e-9, rel=1e-8)
    assert fit.rms_v["forward"] < 1e-9 and not fit.held
    assert law.valid_i_a == (1e-3, 1.0) and law.valid_t_c == (0.0, 100.0)


def test_the_bench_points_give_the_law_and_its_uncertainty():
    law, temps, (t, i, v, tp), cal = bench_points()
    fit = fit_diode(t, i, v, t_pulse_s=tp, calibration=(temps, cal), sense_current_a=1e-3,
                    model=MODEL)
    u = fit.u
    assert abs(fit.law.n - law.n) < 3 * u["n"] and u["n"] < 0.02
    assert abs(fit.law.rs_ohm - law.rs_ohm) < 3 * u["rs_ohm"] + 1e-3
    assert fit.rms_v["forward"] == pytest.approx(0.6e-3, rel=0.3)
    assert fit.rms_v["calibration"] < 2e-5
    # the sense-current convention: the calibration reads back its own temperatures
    back = fit.law.bench_temperature(cal + fit.law.tsp_offset_v, MODEL.rth)
    assert np.max(np.abs(back - temps)) < 0.01
    text = str(fit)
    assert "N   = 1.7" in text and "calibration points" in text and "ohm" in text
    assert set(fit.law.fit) >= {"u", "rms_v", "rms_k", "points", "held"}


def test_pulse_self_heating_is_taken_from_the_thermal_model():
    """Without the pulses' own heating (0.5 K at 0.35 A) the fitted law is off at the heating
    current by more than the noise; with it, within."""
    law, temps, (t, i, v, tp), cal = bench_points(noise_v=1e-5)
    good = fit_diode(t, i, v, t_pulse_s=tp, calibration=(temps, cal), sense_current_a=1e-3,
                     model=MODEL)
    blind = fit_diode(t, i, v, calibration=(temps, cal), sense_current_a=1e-3)
    at = (0.35, 50.0 + 1e-3 * 0.55 * MODEL.rth)
    good_error = abs(good.law.voltage(*at) - law.voltage(0.35, 50.0))
    assert good_error < 2e-5 and good.rms_v["forward"] < 1.5e-5
    # unaware of it, the law explains the heating away (as little residual) and is off by far
    # more than the noise where it matters, at the heating current
    assert abs(blind.law.voltage(*at) - law.voltage(0.35, 50.0)) > 10 * good_error + 1e-4


def test_what_the_points_cannot_tell_is_held_and_said():
    true = DiodeLaw(n=1.8, is_a=3e-9, rs_ohm=0.0, xti=3.0)
    t, i = (x.ravel() for x in np.meshgrid([25.0, 75.0], [1e-3, 0.1]))
    fit = fit_diode(t, i, true.voltage(i, t))
    assert fit.law.xti == 3.0 and fit.law.rs_ohm == 0.0
    assert any("XTI = 3" in h for h in fit.held) and any("RS = 0" in h for h in fit.held)
    assert fit.law.n == pytest.approx(1.8, rel=1e-9)
    with pytest.raises(DataFormatError, match="2 currents and 2 temperatures"):
        fit_diode([25.0, 75.0], [0.1, 0.1], [0.8, 0.7])
    with pytest.raises(DataFormatError, match="forward point 2"):
        fit_diode([25.0, 75.0], [0.1, -0.1], [0.8, 0.7])
    with pytest.raises(DataFormatError, match="thermal model"):
        fit_diode(t, i, true.voltage(i, t), t_pulse_s=np.full(4, 1e-5))


def test_the_model_file_keeps_the_law_as_format_4_and_refuses_it_in_3():
    law = fit_diode(*bench_points()[2][:3]).law
    model = ThermalModel(MODEL.ladder, electrical=law)
    doc = json.loads(json.dumps(model.to_dict()))
    assert doc["format"] == "spicethermal-model/4"
    back = ThermalModel.from_dict(doc)
    assert back.electrical == law and back.electrical.fit["u"] == law.fit["u"]
    assert MODEL.to_dict()["format"] == "spicethermal-model/3"  # older readers read it
    doc["format"] = "spicethermal-model/3"
    with pytest.raises(DataFormatError, match="needs format 'spicethermal-model/4'"):
        ThermalModel.from_dict(doc, "m.json")
    doc["format"] = "spicethermal-model/4"
    doc["electrical"]["n"] = -1
    with pytest.raises(DataFormatError, match=r"m.json, key electrical: n = -1"):
        ThermalModel.from_dict(doc, "m.json")


def test_the_bundle_keeps_forward_points_as_format_3(tmp_path):
    _, temps, (t, i, v, tp), cal = bench_points()
    bundle = Bundle(calibration=CalibrationTable(temps, cal),
                    forward=ForwardTable(t, i, v, tp, sense_current_a=1e-3))
    path = bundle.write(tmp_path / "b")
    doc = json.loads((path / "bundle.json").read_text())
    assert doc["format"] == "spicethermal-bundle/3"
    assert doc["forward"] == {"file": "forward.csv", "sense_current_a": 0.001}
    back = Bundle.read(path)
    assert np.array_equal(back.forward.vf_v, v) and back.forward.sense_current_a == 1e-3
    fit = fit_electrical(back, MODEL)
    assert fit is not None and fit.calibration_residual_v.size == temps.size
    # without the section: the bundle reads as before, and there is no law to fit
    assert fit_electrical(Bundle(calibration=CalibrationTable(temps, cal))) is None
    assert Bundle(calibration=CalibrationTable(temps, cal)).manifest()["format"] == \
        "spicethermal-bundle/1"


def test_bad_forward_points_name_file_row_and_column(tmp_path):
    path = Bundle(forward=ForwardTable([25.0, 75.0], [0.1, 0.1], [0.8, 0.7])).write(
        tmp_path / "b")
    (path / "forward.csv").write_text("temp_c,i_a,vf_v\n25,0.1,0.8\n75,-0.1,0.7\n")
    with pytest.raises(DataFormatError, match=r"forward.csv, row 3, column i_a: -0.1: must be"):
        Bundle.read(path)
    (path / "forward.csv").write_text("temp_c,i_ma,vf_v\n25,100,0.8\n")
    with pytest.raises(DataFormatError, match="wrong unit"):
        Bundle.read(path)
    doc = json.loads((path / "bundle.json").read_text())
    doc["format"] = "spicethermal-bundle/2"
    (path / "bundle.json").write_text(json.dumps(doc))
    with pytest.raises(DataFormatError, match="key forward: forward-voltage points need"):
        Bundle.read(path)
