"""Vendors' libraries as shipped (issue #44): each library of ``tests/data/vendor/`` imports
with only ``--subckt`` (plus ``--param``, ``--network`` or ``--to`` where the library holds a
real choice), and its Zth(t) matches the network cut out by hand.

The libraries are synthetic copies of real vendors' files (their structure kept, their values
changed; the sources are in ``tests/data/vendor/README.md``). The hand-cut networks below are
typed again from the files, element by element, and solved here by an independent method
(scipy's generalized symmetric eigenproblem, nodes without capacity eliminated first), not by
spicethermal.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pytest
from test_vendor import validate

from spicethermal.cli.main import main
from spicethermal.core.errors import DataFormatError
from spicethermal.io.vendor import import_model

CORPUS = Path(__file__).parent / "data" / "vendor"
#: The issue's bound: imported Zth within 0.5 % of Rth of the hand-cut network's.
TOLERANCE = 5e-3


@dataclass
class Cut:
    """A network cut by hand: resistors and capacitors ``(a, b, value)``, the junction ``J``,
    the held nodes, the case capacitance, the reference label."""

    resistors: list[tuple[str, str, float]]
    capacitors: list[tuple[str, str, float]]
    held: set[str]
    reference: str = "case"
    case_c: float = 0.0
    choices: dict = field(default_factory=dict)

    @property
    def rth(self) -> float:
        return float(hand_zth(self, np.array([1e12]))[0])


def chain(nodes, rs, cs, ground="0"):
    """A Cauer ladder by hand: ``rs`` between consecutive ``nodes``, ``cs`` from them to
    ``ground`` (None: no capacitor)."""
    return ([(a, b, r) for a, b, r in zip(nodes, nodes[1:], rs, strict=False)],
            [(n, ground, c) for n, c in zip(nodes, cs, strict=False) if c is not None])


def hand_zth(cut: Cut, t: np.ndarray) -> np.ndarray:
    """Rise of J per watt into J, the held nodes at 0 (scipy, independent of spicethermal)."""
    from scipy.linalg import eigh, solve

    names = sorted({n for a, b, _ in cut.resistors + cut.capacitors for n in (a, b)} - cut.held)
    names.remove("J")
    names.insert(0, "J")
    idx = {n: i for i, n in enumerate(names)}
    n = len(names)
    g, c = np.zeros((n, n)), np.zeros((n, n))
    for matrix, branches, inv in ((g, cut.resistors, True), (c, cut.capacitors, False)):
        for a, b, v in branches:
            y = 1 / v if inv else v
            for p, q in ((a, b), (b, a)):
                if p in idx:
                    matrix[idx[p], idx[p]] += y
                    if q in idx:
                        matrix[idx[p], idx[q]] -= y
    z = [i for i in range(n) if not np.any(c[i])]
    k = [i for i in range(n) if np.any(c[i])]
    e = np.zeros(n)
    e[0] = 1.0
    gzz, gzk = g[np.ix_(z, z)], g[np.ix_(z, k)]
    red = g[np.ix_(k, k)] - (gzk.T @ solve(gzz, gzk) if z else 0)
    b = e[k] - (gzk.T @ solve(gzz, e[z]) if z else 0)
    lam, v = eigh(red, c[np.ix_(k, k)])
    w = v.T @ b
    xk = (v * (w / lam)) @ (-np.expm1(-np.outer(lam, t)))
    if 0 in k:
        return xk[k.index(0)]
    xz = solve(gzz, e[z][:, None] - gzk @ xk)
    return xz[z.index(0)]


T = np.logspace(-7, 4, 111)
_J = "J"

CUTS: dict[tuple[str, str, str], Cut] = {}


def _optimos(zthtype: int) -> Cut:
    d = [1.2e-3, 11.4e-3, 39.7e-3, 150.3e-3, 270.1e-3]
    r = [v + zthtype * dv for v, dv in zip([3.1e-3, 30.5e-3, 118.2e-3, 140.6e-3, 250.9e-3], d,
                                           strict=True)]
    rs, cs = chain([_J, "t1", "t2", "t3", "t4", "Tcase"], r,
                   [125.5e-6, 380.2e-6, 2.61e-3, 2.05e-3, 40.7e-3])
    return Cut(rs + [("Tb", _J, 6.1)], cs + [("Tb", "0", 4.2e-3)], {"0", "Tcase"},
               case_c=185e-3, choices={"params": {"Zthtype": str(zthtype)}} if zthtype else {})


CUTS[("infineon_optimos_n_l3.lib", "XMPL66N08", "typical")] = _optimos(0)
CUTS[("infineon_optimos_n_l3.lib", "XMPL66N08", "Zthtype=1")] = _optimos(1)

_COOL_R = [105.3e-3, 160.2e-3, 880.6e-3, 610.4e-3, 512.8e-3]
_COOL_C = [15.1e-6, 90.2e-6, 118.7e-6, 690.4e-6, 1.1e-3]
CUTS[("infineon_coolmos_l3.lib", "XMPL04N50", "junction-to-case")] = Cut(
    *chain([_J, "1", "2", "3", "4", "Tcase"], _COOL_R, _COOL_C), {"0", "Tcase"}, case_c=40e-3)
CUTS[("infineon_coolmos_l3.lib", "XMPL04N50", "--to 7")] = Cut(
    *chain([_J, "1", "2", "3", "4", "Tcase", "6", "7"], [*_COOL_R, 450e-3, 45.0],
           [*_COOL_C, 40e-3, 62e-3]), {"0", "7"}, case_c=95e-3, choices={"to": "7"})
CUTS[("infineon_profet.lib", "XMPL550P/INF", "")] = Cut(
    *chain([_J, "a", "b", "c", "d", "e", "Tcase"], [0.0019, 0.0041, 0.024, 0.040, 0.063, 0.035],
           [6.1e-4, 6.3e-4, 1.7e-3, 0.011, 0.033, 0.40], "Tamb"), {"Tamb", "Tcase"})
CUTS[("infineon_hitfet.lib", "XMPL78", "")] = Cut(
    *chain([_J, "1", "2", "3", "4", "5", "6", "Tsp"],
           [0.045, 0.070, 0.150, 0.210, 0.095, 4.9, 5.2],
           [2.2e-4, 2.0e-4, 4.5e-4, 1.3e-3, 2.9e-3, 2.5e-3, 0.6e-3], "Tamb"), {"Tamb", "Tsp"})
CUTS[("wolfspeed_c3m.lib", "XMPL0016120D", "")] = Cut(
    *chain([_J, "N1", "N2", "N3", "Tc"], [175.2e-3, 392.7e-3, 248.1e-3, 210.4e-3],
           [702.1e-6, 3.51e-3, 16.2e-3, 150.9e-3]), {"0", "Tc"}, case_c=1e-12)
CUTS[("wolfspeed_module.lib", "XMPL021M12FM3", "Thermals=2, die Q2")] = Cut(
    *chain([_J, "1", "2", "TcQ2"], [1.71e-3, 15.2e-3, 84.4e-3], [1.69e-3, 52.3e-3, 341.2e-3]),
    {"0", "TcQ2"}, choices={"params": {"Thermals": "2"}, "network": "TjQ2"})
CUTS[("cree_c2m_packaged.lib", "XMPL0025120D", "")] = Cut(
    *chain([_J, *[f"N{k}" for k in range(1, 14)], "Tc"],
           [4.6e-3, 4.2e-3, 18.7e-3, 20.1e-3, 27.9e-3, 26.0e-3, 17.1e-3, 18.9e-3, 24.8e-3,
            35.2e-3, 26.1e-3, 10.4e-3, 2.75e-3, 0.19e-3],
           [1.28e-3, 1.15e-3, 4.9e-3, 9.1e-3, 7.8e-3, 10.4e-3, 22.5e-3, 46.1e-3, 66.7e-3,
            70.2e-3, 87.5e-3, 0.30, 5.6, 1.3e3], "Tc"), {"Tc"})
CUTS[("gansystems_gs665_l3.lib", "XMPL508T_L3V2", "")] = Cut(
    *chain([_J, "T11", "T22", "T33", "TC"], [0.012, 0.226, 0.241, 0.023],
           [4.1e-5, 3.05e-3, 6.4e-4, 1.1e-3]), {"0", "TC"})
CUTS[("gansystems_gs665_l3v4.lib", "XMPL516T_L3V4P1", "")] = Cut(
    *chain([_J, "T11", "T22", "T33", "TC"], [0.011, 0.135, 0.146, 0.012],
           [1.35e-4, 1.3e-3, 10.1e-3, 3.4e-3]), {"0", "TC"})
CUTS[("rohm_sct3_thermal.lib", "XMPL3022AL_T_LT", "")] = Cut(
    *chain([_J, "T2", "T3", "Tc"], [4.9e-3, 170.4e-3, 166.8e-3], [1.45e-3, 11.1e-3, 61.3e-3],
           "Ta"), {"Ta", "Tc"})
_IR_R = [0.0071, 0.058, 0.91, 0.29, 0.262]
_IR_C = [None, 660e-6, 6.4e-3, 128e-3, 14.1e-3]
CUTS[("ir_ips10xx.lib", "XMPL1011", "junction-to-case")] = Cut(
    *chain([_J, "n2", "n3", "n4", "n5", "Tcase"], _IR_R, _IR_C, "Tambiant"),
    {"Tambiant", "Tcase"}, case_c=820e-3)
CUTS[("ir_ips10xx.lib", "XMPL1011", "--to Tambiant")] = Cut(
    *chain([_J, "n2", "n3", "n4", "n5", "Tcase", "n13", "Tambiant"], [*_IR_R, 24.0, 26.0],
           [*_IR_C, 820e-3, 7.5], "Tambiant"), {"Tambiant"}, reference="ambient",
    choices={"to": "Tambiant"})
_FAIR = list(zip([_J, "c2", "c3", "c4", "c5", "c6", "c7", "c8"],
                 ["c2", "c3", "c4", "c5", "c6", "c7", "c8", "TA"], strict=True))
CUTS[("fairchild_fdm36xx.lib", "XMPL3622_JA", "")] = Cut(
    [(a, b, r) for (a, b), r in zip(_FAIR, [0.022, 0.12, 0.21, 1.05, 3.4, 6.5, 12.8, 26],
                                    strict=True)],
    [(a, b, c) for (a, b), c in zip(_FAIR, [1.2e-4, 1.1e-4, 3.2e-4, 2.1e-3, 6.0e-3, 3.4e-2,
                                            2.7e-1, 3.2], strict=True)],
    {"TA"}, reference="ambient")
CUTS[("lt_soatherm_nmos.lib", "XMPL009NE2LS", "")] = Cut(
    *chain([_J, "N001", "N002", "N003", "N004", "N005", "Tc"],
           [3.3e-2, 1.05e-1, 2.6e-1, 8.7e-1, 7.1e-2, 1.1e-3],
           [1.7e-4, 2.9e-4, 1.55e-3, 9.1e-3, 3.4e-3, 1.75e-3]), {"0", "Tc"})
_VISHAY = {
    1: ([(_J, "F1", 1.21), ("F1", "F2", 6.35), ("F2", "0", 27.9)],
        [(_J, "F1", 1.52e-3), ("F1", "F2", 23.7e-3), ("F2", "0", 0.611)]),
    2: chain([_J, "T1", "T2", "0"], [1.05, 5.9, 28.5], [1.12e-3, 19.4e-3, 0.702]),
    3: ([(_J, "F4", 0.43), ("F4", "0", 2.11)], [(_J, "F4", 2.04e-3), ("F4", "0", 41.8e-3)]),
    4: chain([_J, "T4", "T5", "0"], [0.38, 1.22, 0.94], [1.67e-3, 12.9e-3, 115.1624e-6]),
}
for _k, (_rs, _cs) in _VISHAY.items():
    CUTS[("vishay_four_networks.lib", "XMPL7xxDP_THERMAL", f"--network {_k}")] = Cut(
        _rs, _cs, {"0"}, reference="ambient", choices={"network": _k})

#: The libraries gathered from vendors (the Vishay-like file reproduces the issue's report).
GATHERED = sorted({k[0] for k in CUTS} - {"vishay_four_networks.lib"})


def test_the_corpus_covers_twelve_libraries_of_seven_vendors():
    vendors = {name.split("_")[0] for name in GATHERED}
    assert len(GATHERED) >= 12 and len(vendors) >= 7, (GATHERED, vendors)
    readme = (CORPUS / "README.md").read_text()
    for path in sorted(CORPUS.iterdir()):
        if path.name != "README.md":
            assert f"`{path.name}`" in readme, f"{path.name}: no provenance in README.md"


@pytest.mark.parametrize("key", CUTS, ids=[f"{k[1]}{' ' + k[2] if k[2] else ''}" for k in CUTS])
def test_each_library_imports_as_shipped_and_matches_the_hand_cut_network(key):
    name, subckt, _ = key
    cut = CUTS[key]
    m = import_model(CORPUS / name, subckt, **cut.choices)
    validate(m.to_dict())
    exact = hand_zth(cut, T)
    rth = cut.rth
    assert m.rth == pytest.approx(rth, rel=1e-9)
    err = float(np.max(np.abs(m.ladder.zth(T) - exact))) / rth
    assert err < TOLERANCE, f"{100 * err:.3g} % of Rth"
    assert err < 1e-8  # in fact exact to rounding
    assert m.case_c_j_per_k == pytest.approx(cut.case_c, rel=1e-12, abs=1e-15)
    assert m.reference == cut.reference
    line = m.provenance["extraction"]
    assert line.startswith("took ") and "\n" not in line


def test_choices_are_required_where_the_library_holds_them(tmp_path, capsys):
    lib = CORPUS / "vishay_four_networks.lib"
    out = tmp_path / "m.json"
    assert main(["import", str(lib), "-o", str(out)]) == 2 and not out.exists()
    captured = capsys.readouterr()
    assert captured.out.splitlines() == [
        "1: from TJA_FOSTER to 0: Foster chain as written, 3 stages, Rth = 35.46 K/W",
        "2: from TJA_CAUER to 0: Cauer ladder as written, 3 stages, Rth = 35.45 K/W",
        "3: from TJF_FOSTER to 0: Foster chain as written, 2 stages, Rth = 2.54 K/W",
        "4: from TJF_CAUER to 0: Cauer ladder as written, 3 stages, Rth = 2.54 K/W"]
    assert captured.err.count("\n") == 1 and "choose one with --network N" in captured.err
    assert main(["import", str(lib), "--network", "tjf_cauer", "-o", str(out)]) == 0
    doc = json.loads(out.read_text())
    assert doc["provenance"]["network"].startswith("4 of 4: from TJF_CAUER to 0")
    assert doc["topology"] == "cauer" and doc["reference"] == "ambient"
    assert main(["import", str(lib), "--network", "5", "-o", str(out)]) == 2
    assert "--network 5: expected 1 to 4 or a junction node" in capsys.readouterr().err


def test_a_parameter_changes_the_network_and_is_kept_in_the_provenance(tmp_path):
    lib = CORPUS / "infineon_optimos_n_l3.lib"
    typical = import_model(lib, "XMPL66N08")
    worst = import_model(lib, "XMPL66N08", params={"ZTHTYPE": "1"})
    assert worst.rth == pytest.approx(typical.rth + 0.4727, rel=1e-12)
    assert worst.provenance["params"] == {"ZTHTYPE": "1"}
    with pytest.raises(DataFormatError, match="--param zth: no such parameter in .SUBCKT "
                                              "XMPL66N08 .*zthtype"):
        import_model(lib, "XMPL66N08", params={"zth": "1"})


@pytest.mark.parametrize("name, subckt, words", [
    ("onsemi_sic_encrypted.txt", "XMPL080N120SC1_5p",
     "onsemi_sic_encrypted.txt, line 1: the library is encrypted; an encrypted model cannot be "
     "read"),
    ("infineon_igbt_l2.lib", "XMPL15N120H3_L2",
     "(line 5): no thermal network: no pin named like Tj"),
    ("infineon_optimos_n_l3.lib", "XMPL66N08_L1", "(line 89): no thermal network"),
    ("infineon_coolmos_l3.lib", "cool_x_n_var", "no thermal network at Tj: no R or C element"),
    ("fairchild_fdm36xx.lib", "XMPL3622", "(line 5): no thermal network"),
    ("wolfspeed_module.lib", "XMPL021M12FM3", "the network from TjQ1 to "
     "X1.XDie_Thermal_Q1.Tj1 has no capacitance (a temperature held through a resistor"),
])
def test_libraries_without_a_network_say_so_in_one_line(tmp_path, capsys, name, subckt, words):
    out = tmp_path / "m.json"
    assert main(["import", str(CORPUS / name), "--subckt", subckt, "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and words in err and not out.exists(), err


@pytest.mark.parametrize("content, words", [
    (b"", "empty file, no subcircuit to read"),
    (b"  \n* only a comment\n\n", "no subcircuit"),
    (b"\x7fELF\x02\x01\x01\x00\x00\x00" + bytes(range(256)), "a binary file (it holds NUL bytes)"),
])
def test_empty_and_binary_files_are_one_line(tmp_path, capsys, content, words):
    lib = tmp_path / "part.lib"
    lib.write_bytes(content)
    out = tmp_path / "m.json"
    assert main(["import", str(lib), "--subckt", "X", "-o", str(out)]) == 2 and not out.exists()
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and words in err and "part.lib" in err, err


#: Networks of each shape the import gives: a general network (exact Foster form), a Cauer
#: ladder past the case, a Foster chain.
IN_NGSPICE = [("infineon_optimos_n_l3.lib", "XMPL66N08", "Zthtype=1"),
              ("ir_ips10xx.lib", "XMPL1011", "--to Tambiant"),
              ("fairchild_fdm36xx.lib", "XMPL3622_JA", "")]


@pytest.mark.ngspice
@pytest.mark.parametrize("key", IN_NGSPICE, ids=[k[1] for k in IN_NGSPICE])
def test_the_imported_network_in_ngspice_matches_the_hand_cut_one(tmp_path, key):
    """Exported as the simulator reads it (Cauer, every dialect): no ``limit()`` is written
    (ngspice's is a random function), and ngspice's Zth matches the hand-cut network's."""
    from spicethermal.spice import lib as spice

    cut = CUTS[key]
    m = import_model(CORPUS / key[0], key[1], **cut.choices)
    for dialect in spice.DIALECTS:
        path = spice.export(m, tmp_path / f"{dialect}.lib", dialect, "cauer", "PART")
        assert "limit" not in path.read_text().lower()
        tstop = 20 * max(m.ladder.time_constants())
        net = spice.render_bench(path, "PART", power_w=1.0, tstop_s=tstop, tmax_s=tstop / 2000,
                                 rise_s=1e-6)
        w = spice.NgspiceBatch().run(net, ["V(TJ)"], dialect)
        late = w.t_s > 1e-4  # after the 1 us ramp of the power
        err = float(np.max(np.abs(w["V(TJ)"] - hand_zth(cut, w.t_s))[late])) / cut.rth
        assert err < TOLERANCE, f"{dialect}: {100 * err:.3g} % of Rth"
