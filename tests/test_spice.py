"""SPICE export: golden files, hostile names, and ngspice runs against the analytic solution."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from conftest import NETLISTS, ramp_response

from spicethermal.cli.main import main
from spicethermal.core.errors import DataFormatError
from spicethermal.core.ladder import Cauer, Foster
from spicethermal.effects import Effect
from spicethermal.engines import pwm
from spicethermal.model import Schedule, ThermalModel
from spicethermal.spice import lib as spice
from spicethermal.spice.netlists import GOLDEN

CASES = [(d, t) for d in spice.DIALECTS for t in spice.TOPOLOGIES]


@pytest.mark.parametrize("filename", sorted(GOLDEN))
def test_golden_netlists_regenerate_identically(filename):
    assert (NETLISTS / filename).read_text() == GOLDEN[filename](), (
        f"netlists/{filename} changed: run `python -m spicethermal.spice.netlists` and review "
        f"the diff")


@pytest.mark.parametrize("name", ["X\n.control", "-ABC", ".end", "A B", "END", "ends", "", "A" * 65,
                                  "ACT;rm", "Ü", "A/B", "A(1)", "X{Y}", "A=B"])
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
@pytest.mark.parametrize("temperature", spice.TEMPERATURES)
@pytest.mark.parametrize("dialect", spice.DIALECTS)
@pytest.mark.parametrize("topology", spice.TOPOLOGIES)
def test_device_effects_in_ngspice_match_python(tmp_path, dialect, topology, temperature):
    ladder = Foster.from_tau([20.0, 80.0], [1e-3, 0.5])
    # a band one layer out needs the Cauer form's physical nodes: a Foster .lib has it at the
    # junction
    node = 1 if topology == "cauer" else 0
    model = ThermalModel(ladder, (
        Effect.create("temperature-coefficient", alpha_per_k=-4e-3, t0_c=25.0),
        Effect.create("phase-change", t_c=40.0, width_k=2.0, latent_j=0.02, node=node),
    )).with_topology(topology)
    lib = spice.export(model, tmp_path / "m.lib", dialect, topology, "NL",
                       temperature=temperature)
    # rise: TREF grounded, the ambient as TOFFSET; absolute: TREF at 25 V, no offset anywhere
    tref, toffset = spice.reference_drive(model, 25.0) if temperature == "rise" else (25.0, None)
    net = spice.render_bench(lib, "NL", power_w=0.3, tstop_s=4.0, tmax_s=4e-3, tref_c=tref,
                             toffset_c=toffset)
    w = spice.NgspiceBatch().run(net, ["V(TJ)"], dialect)
    t = w.t_s[w.t_s > 1e-3]
    rise = 4e-8  # the bench's default ramp, 1e-5 of the maximum step
    py = model.simulate(t, Schedule((0.0, rise / 2), (0.0, 0.3)), tref_c=25.0).tj_k + 25.0
    sim = w["V(TJ)"][w.t_s > 1e-3] + 25.0 - tref
    assert np.max(np.abs(sim - py)) < 0.03  # K, of a rise of about 25 K
    lin = ThermalModel(model.ladder).simulate(t, Schedule.step(0.3)).tj_k + 25.0
    assert np.max(np.abs(lin - py)) > 1.0  # the effects matter at this strength


@pytest.mark.ngspice
@pytest.mark.parametrize("dialect", spice.DIALECTS)
def test_a_quadratic_law_on_inner_layers_in_ngspice_matches_python(tmp_path, dialect):
    """The resistance of the two inner layers peaks 40 K above the reference (a negative
    curvature): the exported Cauer .lib heats as the one network simulator does."""
    model = ThermalModel(Cauer((20.0, 30.0, 50.0), (2e-4, 3e-3, 0.2)), (
        Effect.create("temperature-coefficient", "quadratic", alpha_per_k=8e-3,
                      curvature_per_k2=-1e-4, t0_c=25.0, last_layer=1),))
    lib = spice.export(model, tmp_path / "q.lib", dialect, "cauer", "Q")
    tref, toffset = spice.reference_drive(model, 25.0)
    net = spice.render_bench(lib, "Q", power_w=0.6, tstop_s=2.0, tmax_s=2e-3, tref_c=tref,
                             toffset_c=toffset)
    w = spice.NgspiceBatch().run(net, ["V(TJ)"], dialect)
    t = w.t_s[w.t_s > 1e-3]
    py = model.simulate(t, Schedule((0.0, 2e-8), (0.0, 0.6)), tref_c=25.0).tj_k + 25.0
    sim = w["V(TJ)"][w.t_s > 1e-3] + 25.0 - tref
    assert np.max(np.abs(sim - py)) < 0.03  # K, of a rise of about 60 K
    lin = ThermalModel(model.ladder).simulate(t, Schedule.step(0.6)).tj_k + 25.0
    assert np.max(np.abs(lin - py)) > 1.0  # the law matters at this strength


def test_a_band_one_layer_out_is_exported_on_the_cauer_form(tmp_path, actuator, capsys):
    model = ThermalModel(actuator, (Effect.create("phase-change", t_c=40.0, width_k=2.0,
                                                  latent_j=0.02, node=1),))
    text = spice.export(model, tmp_path / "m.lib", name="PC").read_text()
    assert "(cauer ladder, 4 stages)" in text.splitlines()[0]
    with pytest.raises(DataFormatError, match="phase-change .*needs physical node"):
        spice.export(model, tmp_path / "f.lib", topology="foster", name="PC")
    assert not (tmp_path / "f.lib").exists()
    # the command says what it wrote: the Cauer ladder, not the model file's Foster one
    model.save(tmp_path / "m.json")
    assert main(["export", str(tmp_path / "m.json"), "-o", str(tmp_path / "c.lib")]) == 0
    assert "cauer ladder of 4 stages" in capsys.readouterr().out


def test_export_command_and_errors(tmp_path, actuator, capsys):
    model = tmp_path / "m.json"
    ThermalModel(actuator).save(model)
    out = tmp_path / "a.lib"
    assert main(["export", str(model), "--dialect", "pspice", "--topology", "cauer",
                 "--name", "ACT", "-o", str(out)]) == 0
    assert ".SUBCKT ACT TJ TREF" in out.read_text()
    assert main(["export", str(model), "--pins", "case=TC,junction=TJ", "-o",
                 str(tmp_path / "SPD22N08S2L-50.lib")]) == 0
    assert ".SUBCKT SPD22N08S2L-50 TC TJ\n" in (tmp_path / "SPD22N08S2L-50.lib").read_text()
    for bad in (["--pins", "TJ"], ["--pins", "TJ,0"], ["--pins", "TJ,tj"], ["--pins", "TJ,N1"],
                ["--pins", "TJ,TC,TA", "--topology", "foster"], ["--pins", "x=TJ,TC"]):
        assert main(["export", str(model), *bad, "-o", str(tmp_path / "c.lib")]) == 2
        assert not (tmp_path / "c.lib").exists()
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "pin" in err[0], (bad, err)
    assert main(["export", str(model), "--name", "BAD\n.end", "-o", str(tmp_path / "b.lib")]) == 2
    assert not (tmp_path / "b.lib").exists()
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "subcircuit name" in err[0]
    assert main(["export", str(tmp_path / "missing.json"), "-o", str(out)]) == 2


def test_cli_bad_input_is_one_line_without_traceback(tmp_path):
    bad = tmp_path / "m.json"
    bad.write_text("{not json")
    proc = subprocess.run([sys.executable, "-m", "spicethermal.cli.main", "export", str(bad), "-o",
                           str(tmp_path / "x.lib")], capture_output=True, text=True)
    assert proc.returncode == 2
    assert "Traceback" not in proc.stderr and len(proc.stderr.strip().splitlines()) == 1
    assert str(bad) in proc.stderr and not (tmp_path / "x.lib").exists()


# ------------------------------------------------------------------ names, pins, conventions
@pytest.mark.ngspice
@pytest.mark.parametrize("dialect", spice.DIALECTS)
@pytest.mark.parametrize("name", ["SPD22N08S2L-50", "IPB019N08N3", "2N7002", "C3M0065090D",
                                  "GS66508B", "FDMS86181.TH", "irf540n_thermal"])
def test_vendor_part_names_are_accepted_and_run(tmp_path, name, dialect):
    model = ThermalModel(Foster.from_tau([1.0, 2.0], [1e-3, 1.0]))
    lib = spice.export(model, tmp_path / "m.lib", dialect, "cauer", name)
    w = spice.NgspiceBatch().run(spice.render_bench(lib, name, power_w=1.0, tstop_s=5.0,
                                                    tmax_s=0.05), ["V(TJ)"], dialect)
    assert abs(w["V(TJ)"][-1] - model.ladder.zth(5.0)) < 1e-3 * model.rth


def test_default_name_comes_from_the_device_or_the_file(tmp_path, actuator, capsys):
    model = tmp_path / "m.json"
    ThermalModel(actuator, provenance={"device": "BSC047N08NS3 G"}).save(model)
    assert main(["export", str(model), "-o", str(tmp_path / "a.lib")]) == 0
    assert ".SUBCKT BSC047N08NS3_G TJ TREF" in (tmp_path / "a.lib").read_text()
    ThermalModel(actuator).save(model)
    assert main(["export", str(model), "-o", str(tmp_path / "MUR880E.lib")]) == 0
    assert ".SUBCKT MUR880E TJ TREF" in (tmp_path / "MUR880E.lib").read_text()


def _elements(text: str) -> list[list[str]]:
    body = text[text.index(".SUBCKT"):].splitlines()[1:-1]
    return [line.split() for line in body if line and not line.startswith("*")]


@pytest.mark.parametrize("pins, ground", [("TJ,TCASE", "0"), ("Tj,Tcase,Tamb", "Tamb")])
def test_cauer_capacitors_connect_to_the_thermal_ground(actuator, pins, ground):
    model = ThermalModel(actuator, reference="case", case_c_j_per_k=0.5)
    text = spice.render_lib(model, "ngspice", "cauer", "DUT", pins=spice.Pins.parse(pins))
    caps = [e for e in _elements(text) if e[0].startswith("C")]
    assert len(caps) == actuator.order + 1 and all(e[2] == ground for e in caps)
    assert caps[-1][:2] == ["CCASE", spice.Pins.parse(pins).reference]
    assert "junction-to-case" in text and "Foster" not in text
    foster = spice.render_lib(model, "ngspice", "foster", "DUT")
    assert "valid ONLY with an ideal reference" in foster and "CCASE" not in foster


def test_temperature_conventions_differ_only_for_device_effects(actuator):
    lin = ThermalModel(actuator)
    a = spice.render_lib(lin, "ngspice", "cauer", "D", temperature="absolute")
    r = spice.render_lib(lin, "ngspice", "cauer", "D", temperature="rise")
    assert _elements(a) == _elements(r) and "temperatures in degC" in a and "rises in K" in r
    nl = lin.with_effects([Effect.create("temperature-coefficient", alpha_per_k=-3e-3,
                                         t0_c=25.0)])
    a = spice.render_lib(nl, "ngspice", "cauer", "D", temperature="absolute")
    r = spice.render_lib(nl, "ngspice", "cauer", "D", temperature="rise")
    assert "TOFFSET" not in a and ".SUBCKT D TJ TREF\n" in a
    assert ".SUBCKT D TJ TREF PARAMS: TOFFSET=25" in r and "V(TJ)+TOFFSET" in r


def test_negligible_stages_are_merged_and_said_in_the_header():
    # an exact conversion of a vendor network produced R = 2.4e-22 K/W, C = 8e15 J/K
    bad = Foster([0.3, 2.4e-22, 0.5], [1e-3, 8e15, 1.0])
    lad, notes = spice.simulator_ready(bad)
    assert lad.order == 2 and lad.rth == pytest.approx(bad.rth, rel=1e-15)
    t = np.logspace(-7, 2, 50)
    assert np.max(np.abs(lad.zth(t) - bad.zth(t))) < 1e-20
    text = spice.render_lib(ThermalModel(bad), "ngspice", "foster", "D")
    assert "* Export: 1 stage with R < 1e-09 Rth merged" in text and "8e+15" not in text
    cauer, notes = spice.simulator_ready(Cauer([0.1, 1e-15, 0.2], [1e-3, 2e-3, 1.0]))
    assert cauer.r == (0.1, 0.2) and cauer.c == pytest.approx((1e-3, 1.002)) and notes
    assert spice.simulator_ready(Foster([1.0], [1.0]))[1] == []


@pytest.mark.ngspice
def test_merged_export_runs_where_the_exact_stages_would_not(tmp_path):
    bad = ThermalModel(Foster([0.3, 2.4e-22, 0.5], [1e-3, 8e15, 1.0]))
    lib = spice.export(bad, tmp_path / "m.lib", "ngspice", "foster", "D")
    w = spice.NgspiceBatch().run(spice.render_bench(lib, "D", power_w=1.0, tstop_s=10.0,
                                                    tmax_s=0.01), ["V(TJ)"])
    assert abs(w["V(TJ)"][-1] - bad.ladder.zth(10.0)) < 1e-3 * bad.rth


def test_header_states_reference_source_fit_error_and_time_range(actuator):
    prov = {"source": "zth.csv", "device": "D1", "valid_t_s": [1e-5, 10.0],
            "fit": {"rms_k_per_w": 0.0146, "n_points": 60}}
    text = spice.render_lib(ThermalModel(actuator, reference="case", provenance=prov),
                            "ltspice", "cauer")
    for want in (".SUBCKT D1 TJ TREF", "Rth = 146 K/W, junction-to-case", "* source: zth.csv",
                 "Fit error: rms 0.0146 K/W (0.01 % of Rth) over 60 points",
                 "Valid from 1e-05 s to 10 s"):
        assert want in text, want


# ------------------------------------------------------------------ coupled to a heatsink
def nodal(resistors, capacitors, held=("TA",)):
    """G and C of a thermal network: ``resistors`` as (a, b, R), ``capacitors`` as (a, C) to
    the thermal ground; nodes in ``held`` are ideal sources (rises 0)."""
    nodes = sorted({n for a, b, _ in resistors for n in (a, b)} - set(held))
    idx = {n: i for i, n in enumerate(nodes)}
    g, c = np.zeros((len(nodes),) * 2), np.zeros(len(nodes))
    for a, b, r in resistors:
        for x, y in ((a, b), (b, a)):
            if x in idx:
                g[idx[x], idx[x]] += 1 / r
                if y in idx:
                    g[idx[x], idx[y]] -= 1 / r
    for a, cap in capacitors:
        c[idx[a]] += cap
    return nodes, g, c


def exact_rise(resistors, capacitors, node, t, segments):
    """Rise of ``node`` under piecewise-constant power ``segments`` ((t0, t1, W) into the
    junction "J"), by the modal solution of the full network (scipy, independent of
    spicethermal)."""
    from scipy.linalg import eigh

    nodes, g, c = nodal(resistors, capacitors)
    lam, v = eigh(g, np.diag(c))
    inj, out = v[nodes.index("J")], v[nodes.index(node)]
    z, rise = np.zeros(lam.size), np.full(t.size, np.nan)
    for t0, t1, p in segments:
        sel = (t >= t0) & (t < t1)
        dt = (t[sel] - t0)[:, None]
        rise[sel] = (z * np.exp(-lam * dt) + p * inj / lam * -np.expm1(-lam * dt)) @ out
        z = z * np.exp(-lam * (t1 - t0)) + p * inj / lam * -np.expm1(-lam * (t1 - t0))
    return rise


def ladder_branches(cauer_r, cauer_c, case="TC"):
    """A Cauer ladder from "J" to ``case`` as branch lists for :func:`nodal`."""
    names = ["J", *[f"n{k}" for k in range(1, len(cauer_r))], case]
    return ([(names[k], names[k + 1], r) for k, r in enumerate(cauer_r)],
            [(names[k], c) for k, c in enumerate(cauer_c) if c > 0])


#: Heatsinks from the case TC to the ambient TA: base capacity at TC, resistance to TA.
HEATSINKS = {"slow": (1.0, 100.0), "among": (0.2, 0.05)}
#: Tolerances of the issue: % of the peak junction rise over the whole transient.
COUPLED_TOLERANCE = {"slow": 0.02, "among": 0.05}


PWM_PERIOD_S = 0.01


def drive_segments(drive, power, tstop):
    if drive == "step":
        return [(0.0, np.inf, power)], f"IP 0 TJ PWL(0 0 1n {power})"
    period = PWM_PERIOD_S
    segs = [seg for k in range(int(tstop / period) + 2) for seg in
            ((k * period, (k + 0.5) * period, power), ((k + 0.5) * period, (k + 1) * period, 0))]
    return segs, f"IP 0 TJ PULSE(0 {power} 0 1n 1n {period / 2} {period})"


def coupled_error(lib, name, pins, resistors, capacitors, heatsink, drive, dialect="ngspice",
                  power=20.0, ambient_c=25.0, options="reltol=1e-4"):
    """Junction temperature in ngspice, the .lib's case coupled to ``heatsink``, against the
    exact solution of the reference network with the same heatsink: max |Δ| / peak rise."""
    r_hs, c_hs = HEATSINKS[heatsink]
    tstop = 5 * r_hs * c_hs if heatsink == "among" else (20.0 if drive == "step" else 2.0)
    segs, source = drive_segments(drive, power, tstop)
    tmax = tstop / 2000 if drive == "step" else min(tstop / 2000, PWM_PERIOD_S / 100)
    nodes = {"junction": "TJ", "reference": "TC", "ambient": "TA"}
    inst = " ".join(nodes[role] for role in pins.order)
    net = (f"* coupled\n.include {lib}\nX1 {inst} {name}\nCHS TC 0 {c_hs}\nRHS TC TA {r_hs}\n"
           f"VA TA 0 DC {ambient_c}\n{source}\n.options {options}\n"
           f".tran {tmax} {tstop} 0 {tmax}\n.end\n")
    w = spice.NgspiceBatch().run(net, ["V(TJ)"], dialect)
    rs = [*resistors, ("TC", "TA", r_hs)]
    cs = [*capacitors, ("TC", c_hs)]
    exact = ambient_c + exact_rise(rs, cs, "J", w.t_s, segs)
    sel = w.t_s > 1e-6
    return float(np.max(np.abs(w["V(TJ)"][sel] - exact[sel])) / np.max(exact - ambient_c))


@pytest.fixture(scope="module")
def distributed():
    """A reference heat path as a fine 24-section line (τ from ns to 75 ms, Rth 0.3 K/W), and
    the ladder a user fits to its case-held Zth(t) sampled 1 µs ... 10 s with 0.2 % noise."""
    from types import SimpleNamespace

    from spicethermal.fit.ladder import fit_model

    n = 24
    w = np.geomspace(0.01, 1, n)
    ref = Cauer(0.3 * w / w.sum(), np.geomspace(1e-5, 0.3, n))
    t = np.logspace(-6, 1, 71)
    noise = 1 + 2e-3 * np.random.default_rng(1).standard_normal(t.size)
    model, _ = fit_model(SimpleNamespace(t_s=t, zth_k_per_w=ref.zth(t) * noise,
                                         rth_k_per_w=ref.rth), reference="case")
    return ref, model


@pytest.mark.ngspice
@pytest.mark.parametrize("heatsink", sorted(HEATSINKS))
@pytest.mark.parametrize("drive", ["step", "pwm"])
def test_fitted_cauer_coupled_to_a_heatsink_matches_the_reference_network(
        tmp_path, distributed, heatsink, drive):
    ref, model = distributed
    pins = spice.Pins("TJ", "TC")
    lib = spice.export(model, tmp_path / "d.lib", "ngspice", "cauer", "DEV", pins=pins,
                       temperature="absolute")
    rs, cs = ladder_branches(ref.r, ref.c)
    err = coupled_error(lib, "DEV", pins, rs, cs, heatsink, drive)
    assert err < COUPLED_TOLERANCE[heatsink], f"{100 * err:.2f} % of the peak rise"


@pytest.mark.ngspice
def test_foster_coupled_to_a_heatsink_is_wrong_as_its_header_says(tmp_path, distributed):
    ref, model = distributed
    pins = spice.Pins("TJ", "TC")
    lib = spice.export(model, tmp_path / "d.lib", "ngspice", "foster", "DEV", pins=pins)
    rs, cs = ladder_branches(ref.r, ref.c)
    assert coupled_error(lib, "DEV", pins, rs, cs, "among", "step") > 0.3


@pytest.mark.ngspice
@pytest.mark.parametrize("temperature, ambient_c", [("absolute", 25.0), ("rise", 0.0)])
def test_three_pin_form_and_both_temperature_conventions(tmp_path, distributed, temperature,
                                                         ambient_c):
    ref, model = distributed
    pins = spice.Pins.parse("reference=TC,junction=TJ,ambient=TA")
    lib = spice.export(model, tmp_path / "d.lib", "pspice", "cauer", "DEV", pins=pins,
                       temperature=temperature)
    rs, cs = ladder_branches(ref.r, ref.c)
    # capacitors to an ambient pin at 25 V: ngspice's default tolerances (the header says so)
    err = coupled_error(lib, "DEV", pins, rs, cs, "among", "step", "pspice",
                        ambient_c=ambient_c, options="")
    assert err < COUPLED_TOLERANCE["among"]


@pytest.mark.ngspice
def test_absolute_temperatures_next_to_an_electrothermal_vendor_expression(tmp_path, actuator):
    """A vendor-style electrothermal expression reads V(Tj) in degC (Rds(on) ∝ (T/298 K)^2.5,
    as Infineon's level-3 models): with --temperature absolute it gets the junction
    temperature, and the self-consistent steady state matches the closed loop solved here."""
    from scipy.optimize import brentq

    ladder = Foster.from_tau([2.0, 6.0], [1e-3, 0.05])  # Rth 8 K/W
    i_a, r0, amb = 3.0, 0.5, 25.0

    def power(tj_c):
        return i_a**2 * r0 * ((tj_c + 273.15) / 298.15) ** 2.5

    tj = brentq(lambda x: x - amb - ladder.rth * power(x), amb, 500.0)
    pins = spice.Pins.parse("Tj,Tcase")
    lib = spice.export(ThermalModel(ladder, reference="case"), tmp_path / "d.lib", "ngspice",
                       "cauer", "DEV", pins=pins, temperature="absolute")
    net = (f"* self-heating\n.include {lib}\nX1 TJ TC DEV\nVC TC 0 DC {amb}\n"
           f"BPD 0 TJ I={i_a}**2*{r0}*pwr((V(TJ)+273.15)/298.15,2.5)\n"
           ".tran 1m 1 0 1m\n.end\n")
    w = spice.NgspiceBatch().run(net, ["V(TJ)"])
    assert abs(w["V(TJ)"][-1] - tj) < 1e-3 * (tj - amb)
    as_rise = brentq(lambda x: x - ladder.rth * power(x), 0.0, 500.0) + amb
    assert abs(as_rise - tj) > 0.05 * (tj - amb)  # reading a rise as degC would be wrong
