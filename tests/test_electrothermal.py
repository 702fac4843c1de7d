"""The heater as an electrothermal part (issue #46): ``export --electrothermal``, its
convergence in the three dialects, and the checks it answers to: at constant current it
reproduces the thermal model's Zth, at the sense current its Vf reproduces the calibration."""

from __future__ import annotations

import json
import subprocess
import sys
from dataclasses import replace

import numpy as np
import pytest
from conftest import NETLISTS
from heaters import MODEL, bench_points

from spicethermal.core.errors import DataFormatError
from spicethermal.effects import Effect
from spicethermal.fit.diode import fit_diode
from spicethermal.model import ThermalModel
from spicethermal.spice.electrothermal import render_electrothermal
from spicethermal.spice.lib import DIALECTS, NgspiceBatch, render_lib
from spicethermal.spice.netlists import heater_model
from spicethermal.spice.pins import Pins

CLI = [sys.executable, "-m", "spicethermal.cli.main"]


def deck(lib: str, body: str, temperature: str = "rise", tref: float = 0.0) -> str:
    x = "X1 A 0 TJ TREF HEATER" + (" PARAMS: TOFFSET=25" if temperature == "rise" else "")
    return f"* electrothermal test\n.include {lib}\n{x}\nVREF TREF 0 DC {tref}\n{body}\n.end\n"


def write(tmp_path, model, dialect, temperature="rise", name="h.lib", topology="cauer"):
    path = tmp_path / name
    path.write_text(render_electrothermal(model, dialect, topology, "HEATER", name,
                                          temperature=temperature))
    return path


def test_the_part_writes_the_law_and_reuses_the_ladders_writer():
    model = heater_model()
    text = render_electrothermal(model, "ngspice", "cauer", "HEATER", temperature="rise")
    assert ".SUBCKT HEATER A K TJ TREF PARAMS: TOFFSET=25" in text
    assert "limit(" not in text.lower()  # a random Monte-Carlo function in ngspice
    assert "ngspice dialect" in text and "N = 1.75" in text and ".model DHEATER D(" in text
    # the ladder is the thermal writer's, element for element
    thermal = render_lib(model, "ngspice", "cauer", "HEATER", temperature="rise")
    ladder = [ln for ln in thermal.splitlines() if ln[:1] in "RC" and ln[1:2].isdigit()]
    assert ladder and all(ln in text.splitlines() for ln in ladder)
    assert "GPD 0 TJ VALUE={MAX(V(DI)*V(A,K),0)}" in render_electrothermal(model, "pspice")
    pins = Pins.parse("anode=P,cathode=N,junction=Tj,case=Tc", electrical=True)
    assert ".SUBCKT HEATER P N Tj Tc" in render_electrothermal(model, name="HEATER", pins=pins)
    with pytest.raises(DataFormatError, match="electrothermal"):
        render_lib(model, pins=pins)
    with pytest.raises(DataFormatError, match="no diode law"):
        render_electrothermal(replace(model, electrical=None))


DRIVES = {
    "pwm from cold": "ISENSE 0 A DC 1m\nIHEAT 0 A PULSE(0 0.105 0 1u 1u 0.5m 1m)",
    "hot start, then off": "ISENSE 0 A DC 1m\nIHEAT 0 A PULSE(0.35 0 0.5m 1u 1u 0.5m 1m)",
    "voltage through a resistor, reverse bias": "VS S 0 PULSE(-5 5 0 1u 1u 0.5m 1m)\nRL S A 20",
}
#: Device effects the part's heat feeds: a temperature coefficient, and a latent-heat band the
#: drives below do not reach (one crossed under the electrothermal drive stalls ngspice's time
#: step, as the band's rendering does in other nonlinear decks: see the report of issue #46).
EFFECTS = (Effect.create("temperature-coefficient", alpha_per_k=-3e-3, t0_c=25.0),
           Effect.create("phase-change", t_c=90.0, latent_j=0.05, node=2, width_k=2.0))


@pytest.mark.ngspice
@pytest.mark.parametrize("dialect", DIALECTS)
@pytest.mark.parametrize("effects", [False, True], ids=["linear", "device effects"])
def test_it_converges_from_a_cold_start_and_across_edges(tmp_path, dialect, effects):
    """Every drive from the DC operating point, 20 ms with edges of 1 µs; the law holds
    throughout (V(A) = V(I, T(TJ)) + RS·I at the pulse's top)."""
    model = heater_model().with_topology("cauer")
    if effects:
        model = model.with_effects(EFFECTS)
    lib = write(tmp_path, model, dialect)
    law = model.electrical
    for name, body in DRIVES.items():
        w = NgspiceBatch(timeout_s=60).run(deck(lib, body + "\n.tran 1u 20m"),
                                           ["V(A)", "V(TJ)", "V(X1.DI)"], dialect)
        assert w.t_s[-1] == pytest.approx(0.02), name
        assert np.all(np.isfinite(w["V(A)"])) and np.max(w["V(TJ)"]) < 60, name
        on = w["V(X1.DI)"] > 0.05
        expect = law.voltage(w["V(X1.DI)"][on], 25.0 + w["V(TJ)"][on])
        assert np.max(np.abs(w["V(A)"][on] - expect)) < 1e-4, name


@pytest.mark.ngspice
@pytest.mark.parametrize("dialect", DIALECTS)
def test_absolute_temperatures_and_a_three_pin_ladder(tmp_path, dialect):
    path = tmp_path / "h.lib"
    path.write_text(render_electrothermal(heater_model(), dialect, "cauer", "HEATER",
                                          pins=Pins.parse("TJ,TREF,TAMB", electrical=True),
                                          temperature="absolute"))
    text = (f"* three pins\n.include {path}\nX1 A 0 TJ TREF TAMB HEATER\nVREF TREF 0 DC 25\n"
            f"VAMB TAMB 0 DC 25\n{DRIVES['pwm from cold']}\n.tran 1u 20m\n.end\n")
    w = NgspiceBatch(timeout_s=60).run(text, ["V(A)", "V(TJ)"], dialect)
    assert w["V(TJ)"][0] == pytest.approx(25.0 + 1e-3 * 0.6 * 146, abs=2e-3)  # sense current
    assert 26.0 < w["V(TJ)"][-1] < 28.0


@pytest.mark.ngspice
@pytest.mark.parametrize("dialect", DIALECTS)
def test_at_constant_current_it_reproduces_the_thermal_models_zth(tmp_path, dialect):
    """Issue #46, check 1: a current step (the sense current on before it); the junction's
    rise against the thermal model's response to the power the part dissipates (I·V falls 2 %
    as it heats), from 10 µs to 150 s, within 0.5 % of the rise."""
    model = heater_model().with_topology("cauer")
    lib = write(tmp_path, model, dialect)
    # the project's bench tolerances (with ngspice's defaults, reltol 1e-3: 0.39 %)
    body = ("ISENSE 0 A DC 1m\nIHEAT 0 A PWL(0 0 1u 0.105)\n"
            ".options reltol=1e-4 trtol=0.5\n.tran 1e-6 150 0 1.5")
    w = NgspiceBatch(timeout_s=120).run(deck(lib, body), ["V(A)", "V(TJ)", "V(X1.DI)"],
                                        dialect)
    t = w.t_s
    power = w["V(A)"] * w["V(X1.DI)"]
    rise = w["V(TJ)"] - w["V(TJ)"][0]
    zth = model.ladder.zth
    # superposition of the power's steps at the simulated instants (exact for a linear ladder)
    steps = np.diff(power, prepend=power[0] if t[0] > 0 else w["V(A)"][0] * 1e-3)
    sel = np.flatnonzero(t >= 1e-5)
    predicted = np.array([np.sum(steps[:k + 1] * zth(np.maximum(t[k] - t[:k + 1], 0.0)))
                          for k in sel])
    final = rise[-1]
    assert final > 10.0 and np.log10(t[sel][-1] / t[sel][0]) > 6.9
    assert np.max(np.abs(rise[sel] - predicted)) < 0.005 * final


@pytest.mark.ngspice
@pytest.mark.parametrize("dialect", DIALECTS)
def test_at_the_sense_current_its_vf_reproduces_the_calibration(tmp_path, dialect):
    """Issue #46, check 2: the law fitted to the bench's points, exported; the part under the
    sense current alone, its reference at each calibration temperature (a DC sweep): V(A) less
    the calibration's offset (the reference diode's voltage) is the calibration within its
    noise."""
    _, temps, (t, i, v, tp), cal = bench_points(cal_noise_v=1e-5)
    fit = fit_diode(t, i, v, t_pulse_s=tp, calibration=(temps, cal), sense_current_a=1e-3,
                    model=MODEL)
    model = ThermalModel(MODEL.ladder, electrical=fit.law)
    lib = write(tmp_path, model, dialect, temperature="absolute", topology="foster")
    w = NgspiceBatch(timeout_s=60).run(
        deck(lib, "ISENSE 0 A DC 1m\n.dc VREF 25 75 10", "absolute", 25.0), ["V(A)"], dialect)
    assert np.allclose(w.t_s, temps)
    error = w["V(A)"] - fit.law.tsp_offset_v - cal
    noise = fit.rms_v["calibration"]
    assert np.sqrt(np.mean(error ** 2)) < 1.5 * noise and np.max(np.abs(error)) < 3 * 1e-5


def test_export_electrothermal_and_what_an_older_model_lacks(tmp_path):
    model = heater_model()
    model.save(tmp_path / "heater.json")
    ok = subprocess.run([*CLI, "export", str(tmp_path / "heater.json"), "--electrothermal",
                         "--dialect", "ltspice", "-o", str(tmp_path / "heater.lib")],
                        capture_output=True, text=True)
    assert ok.returncode == 0, ok.stderr
    assert "A K TJ TREF, electrothermal part" in ok.stdout
    assert ".SUBCKT" in (tmp_path / "heater.lib").read_text()
    old = json.loads((NETLISTS / "actuator_effects.model.json").read_text())
    (tmp_path / "old.json").write_text(json.dumps(old))
    bad = subprocess.run([*CLI, "export", str(tmp_path / "old.json"), "--electrothermal",
                          "-o", str(tmp_path / "old.lib")], capture_output=True, text=True)
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1
    assert "has no diode law Vf(I, T)" in bad.stderr and "Traceback" not in bad.stderr
    assert not (tmp_path / "old.lib").exists()
    thermal = subprocess.run([*CLI, "export", str(tmp_path / "old.json"), "-o",
                              str(tmp_path / "old.lib")], capture_output=True, text=True)
    assert thermal.returncode == 0 and (tmp_path / "old.lib").exists()
    pins = subprocess.run([*CLI, "export", str(tmp_path / "heater.json"), "--pins", "A,K,TJ",
                           "--electrothermal", "-o", str(tmp_path / "p.lib")],
                          capture_output=True, text=True)
    assert pins.returncode == 2 and "--pins" in pins.stderr


def test_an_older_bundle_still_fits_and_exports_and_says_what_is_missing(tmp_path):
    """The shipped sample bundle (spicethermal-bundle/1, firmware 1.0: no forward points):
    `fit` writes the thermal model as before (format /3), `export` writes its .lib, and
    `export --electrothermal` says in one line what is missing, writing nothing."""
    from conftest import DATA

    def cli(*args):
        return subprocess.run([*CLI, *map(str, args)], capture_output=True, text=True)

    fit = cli("fit", DATA / "sample_bundle", "-o", tmp_path / "m.json")
    assert fit.returncode == 0 and "diode law" not in fit.stdout
    assert json.loads((tmp_path / "m.json").read_text())["format"] == "spicethermal-model/3"
    assert cli("export", tmp_path / "m.json", "-o", tmp_path / "m.lib").returncode == 0
    bad = cli("export", tmp_path / "m.json", "--electrothermal", "-o", tmp_path / "e.lib")
    assert bad.returncode == 2 and len(bad.stderr.strip().splitlines()) == 1
    assert "no diode law Vf(I, T)" in bad.stderr and "forward-voltage points" in bad.stderr
    assert not (tmp_path / "e.lib").exists()
