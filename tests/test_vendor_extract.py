"""The stated rules of the network extraction (issue #44, points 1 and 2), each on a small
subcircuit written for it: what is taken, what is left, and why."""

from __future__ import annotations

import numpy as np
import pytest

from spicethermal.cli.main import main
from spicethermal.core.errors import DataFormatError
from spicethermal.core.ladder import Cauer, Foster
from spicethermal.io.vendor import import_model

LADDER = "R1 Tj n1 1\nC1 Tj 0 1m\nR2 n1 Tc 2\nC2 n1 0 3m\n"
WANT = Cauer([1.0, 2.0], [1e-3, 3e-3])


def lib(tmp_path, text, name="part.lib"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_a_power_injection_resistor_before_the_tj_pin_is_dropped(tmp_path):
    m = import_model(lib(tmp_path, f".subckt D d s Tj Tc\nG1 0 X VALUE={{V(d,s)}}\n"
                                   f"R_inj X Tj 1m\n{LADDER}.ends\n"))
    assert m.ladder == WANT
    line = m.provenance["extraction"]
    assert "R_inj: between the dissipation node x (G1) and the junction Tj, no heat storage at " \
           "x: the heat reaches Tj whole; dropped (the junction is the Tj pin)" in line
    assert m.provenance["elements"]["left"] == {
        "dead end without heat storage (carries no heat)": ["R_inj"]}


def test_without_a_tj_pin_the_series_resistor_is_kept(tmp_path):
    m = import_model(lib(tmp_path, ".subckt D d s Tc\nG1 0 X VALUE={V(d,s)}\nR_inj X Tj 1m\n"
                                   f"{LADDER}.ends\n"))
    assert m.ladder == Cauer([1e-3, 1.0, 2.0], [0.0, 1e-3, 3e-3])
    assert "R_inj: a series resistor at the junction X without heat storage: kept" in \
        m.provenance["extraction"]


def test_a_zero_volt_source_is_a_wire(tmp_path):
    m = import_model(lib(tmp_path, f".subckt D Tj Tc\nV_heat Tj tj_in DC 0\n"
                                   f"{LADDER.replace('Tj', 'tj_in')}.ends\n"))
    assert m.ladder == WANT and m.provenance["pins"] == "junction Tj, reference Tc"


def test_optional_pins_take_their_default_node(tmp_path):
    m = import_model(lib(tmp_path, ".subckt NET a OPTIONAL: b=TC\n"
                                   f"{LADDER.replace('Tj', 'a').replace('Tc', 'b')}.ends\n"
                                   ".subckt D Tj Tc\nX1 Tj NET\n.ends\n"), "D")
    assert m.ladder == WANT and m.provenance["pins"] == "junction Tj, reference Tc"


def test_a_readout_pin_is_not_the_network(tmp_path):
    """LT's DanTherm: the Tj pin is computed by a behavioural source from the real network."""
    m = import_model(lib(tmp_path, ".subckt D D S Tj Tc\nB1 0 T1 I=V(D,S)\n"
                                   f"{LADDER.replace('Tj', 'T1')}"
                                   "B3 0 Tj I=1m*(V(Tc)+V(T1,Tc))\nC13 Tj 0 20p Rpar=1k\n.ends\n"))
    assert m.ladder == WANT and m.provenance["pins"] == "junction T1, reference Tc"
    assert "Tj is left: a readout (B3 computes it from another network's temperatures)" in \
        m.provenance["extraction"]


def test_two_dies_coupled_are_two_networks_to_choose(tmp_path, capsys):
    text = (".subckt DUAL Tj1 Tc1 Tj2 Tc2\nR1 Tj1 Tc1 1\nC1 Tj1 0 1m\nR2 Tj2 Tc2 2\n"
            "C2 Tj2 0 2m\nRk Tj1 Tj2 50\n.ends\n")
    path = lib(tmp_path, text)
    assert main(["import", str(path), "-o", str(tmp_path / "m.json")]) == 2
    assert capsys.readouterr().out.splitlines() == [
        "1: from Tj1 to Tc1: R/C network, converted exactly to its Foster form, 2 stages, "
        "Rth = 0.981132 K/W",
        "2: from Tj2 to Tc2: R/C network, converted exactly to its Foster form, 2 stages, "
        "Rth = 1.92453 K/W"]
    m = import_model(path, network=2)
    assert m.rth == pytest.approx(1 / (1 / 2 + 1 / 51))
    assert "heat also leaves through Tc1, held at the reference temperature" in \
        m.provenance["extraction"]


def test_a_thevenin_source_that_leaks_much_is_kept_as_a_path(tmp_path):
    m = import_model(lib(tmp_path, ".subckt D d s Tj Tc Ta\nE1 T0 Ta VALUE={10*V(d,s)}\n"
                                   f"R0 T0 Tj 10\n{LADDER}.ends\n"))
    assert m.rth == pytest.approx(1 / (1 / 3 + 1 / 10))
    assert "R0: the resistor of the Thevenin heat source E1 leaks 30 % of Rth: kept" in \
        m.provenance["extraction"]


def test_to_takes_the_network_past_the_case(tmp_path):
    text = (f".subckt D Tj Tc Ta\n{LADDER}R3 Tc n3 5\nC3 n3 Ta 0.5\nR4 n3 Ta 7\n"
            "C4 Tc Ta 0.1\n.ends\n")
    case = import_model(lib(tmp_path, text))
    assert case.ladder == WANT and case.case_c_j_per_k == 0.1 and case.reference == "case"
    assert case.provenance["elements"]["left"] == {"past the reference Tc": ["R3", "C3", "R4"]}
    far = import_model(tmp_path / "part.lib", to="Ta")
    assert far.reference == "ambient" and far.rth == pytest.approx(15.0)
    t = np.logspace(-5, 3, 50)
    assert np.all(far.ladder.zth(t) >= case.ladder.zth(t) - 1e-12)
    with pytest.raises(DataFormatError, match="no resistive path from Tj to nowhere .--to."):
        import_model(tmp_path / "part.lib", to="nowhere")


def test_a_foster_chain_written_with_rpar_capacitors(tmp_path):
    m = import_model(lib(tmp_path, ".subckt TH Tj Tc\nC1 Tj n1 1m Rpar=1\nC2 n1 Tc 2 Rpar=2\n"
                                   ".ends\n"))
    assert m.ladder == Foster([1.0, 2.0], [1e-3, 2.0])


def test_the_choices_apply_to_spice_libraries_only(tmp_path):
    csv = lib(tmp_path, "r_k_per_w,tau_s\n1,1\n", "t.csv")
    with pytest.raises(DataFormatError, match="apply to SPICE libraries"):
        import_model(csv, to="Tc")
    out = tmp_path / "m.json"
    with pytest.raises(SystemExit) as exit_:
        main(["import", str(lib(tmp_path, f".subckt D Tj Tc\n{LADDER}.ends\n")),
              "--param", "bad", "-o", str(out)])
    assert exit_.value.code == 2 and not out.exists()
