"""Reading SPICE libraries in every dialect's spelling (issue #44, point 3): comments,
continuation lines, letter case, encodings, ``.include`` and ``.lib`` sections, expressions."""

from __future__ import annotations

import pytest

from spicethermal.cli.main import main
from spicethermal.core.errors import DataFormatError
from spicethermal.core.ladder import Cauer
from spicethermal.io.spice_expr import NotConstant, evaluate, spice_number
from spicethermal.io.spice_read import logical_lines, read_library
from spicethermal.io.vendor import import_model

#: The same two-stage network, written as each test spells it.
WANT = Cauer([1.0, 2.0], [1e-3, 3e-3])


def write(tmp_path, text, name="part.lib", encoding="utf-8"):
    path = tmp_path / name
    path.write_bytes(text.encode(encoding) if isinstance(text, str) else text)
    return path


@pytest.mark.parametrize("text", [
    # PSpice: ; comments, continuation, PARAMS:, braces
    "* PSpice\n.SUBCKT D Tj Tcase PARAMS: r1=1 ; the first layer\n"
    "R1 Tj n1 {r1}\n+ ; nothing\nC1 Tj 0 1m\nR2 n1 Tcase\n+ 2\nC2 n1 0 3m\n.ENDS D\n",
    # LTspice: lower case, .param, // comments, tabs, µ
    ".subckt d tj tcase\n.param r2=2 ; layer 2\nr1\ttj\tn1\t1 // die\nc1 tj 0 1000µ\n"
    "r2 n1 tcase {r2}\nc2 n1 0 3m\n.ends\n",
    # ngspice: $ comments, .control block, gnd, quoted expression, .end
    ".subckt D Tj Tcase $ a part\nR1 Tj n1 '0.5*2' $ die\nC1 Tj gnd 1m\nR2 n1 Tcase 2\n"
    ".control\nrun\n.endc\nC2 n1 GND 3m\n.ends\n.end\n.subckt broken\n",
    # HSPICE/LTspice forms: R=, C=, param: keyword, upper case, 4k7 style numbers
    ".SUBCKT D TJ TCASE PARAM: K=2\nR1 TJ N1 R=1\nC1 TJ 0 C=1M\nR2 N1 TCASE {K}\n"
    "C2 N1 0 3MF\n.ENDS\n",
    # PSpice schematic export: $N_ nodes, IC=0, indented continuation
    ".subckt D Tj Tcase\nR_R1 Tj $N_0001 1\nC_C1 Tj 0 1m IC=0\nR_R2 $N_0001 Tcase\n"
    "      + 2\nC_C2 $N_0001 0 3m IC=0 TC=0,0\n.ends\n",
])
def test_every_dialect_spells_the_same_network(tmp_path, text):
    m = import_model(write(tmp_path, text), "D")
    assert m.ladder.topology == "cauer"
    assert m.ladder.r == pytest.approx(WANT.r) and m.ladder.c == pytest.approx(WANT.c)


@pytest.mark.parametrize("name", ["part.lib", "part.txt", "part.mod", "part.sub", "PART.LIB"])
def test_any_file_name_but_csv_is_a_spice_library(tmp_path, name):
    text = ".subckt D Tj Tc\nR1 Tj n1 1\nC1 Tj 0 1m\nR2 n1 Tc 2\nC2 n1 0 3m\n.ends\n"
    assert import_model(write(tmp_path, text, name), "D").ladder == WANT


@pytest.mark.parametrize("encoding, text", [
    ("utf-8-sig", "* Tj in °C, 10 µs résolution ✓\n"),
    ("utf-16", "* LTspice sometimes saves UTF-16 ° \n"),
    ("latin-1", "* Température de jonction en °C\n"),
])
def test_encodings_and_unicode_comments(tmp_path, encoding, text):
    body = text + ".subckt D Tj Tc\nR1 Tj n1 1\nC1 Tj 0 1m\nR2 n1 Tc 2\nC2 n1 0 3m\n.ends\n"
    m = import_model(write(tmp_path, body, encoding=encoding), "D")
    assert m.ladder == WANT


def test_logical_lines_join_continuations_and_drop_comments():
    lines = logical_lines("* c\nR1 a b 1k ; r\n  + TC=0 // x\nC1 a 0 1u $c\n.control\n"
                          "plot v(a)\n.endc\nR2 a $N_1 1 $ r\n.end\nR3 a b 1\n", "f.lib")
    assert [(x.number, x.text) for x in lines] == [(2, "R1 a b 1k TC=0"), (4, "C1 a 0 1u"),
                                                   (8, "R2 a $N_1 1")]
    with pytest.raises(DataFormatError, match="f.lib, line 1: a continuation line"):
        logical_lines("+ R1 a b 1\n", "f.lib")


def test_includes_and_library_sections_are_followed_inside_the_folder(tmp_path):
    sub = tmp_path / "models"
    sub.mkdir()
    write(sub, ".lib typ\n.param r2=2\n.endl typ\n.lib max\n.param r2=3\n.endl\n",
          "params.lib")
    write(sub, ".subckt D Tj Tc\nR1 Tj n1 1\nC1 Tj 0 1m\nR2 n1 Tc {r2}\nC2 n1 0 3m\n.ends\n",
          "net.inc")
    top = write(tmp_path, '* top\n.include "models/net.inc"\n.lib models/params.lib typ\n'
                          ".inc models/net.inc\n", "top.cir")
    assert import_model(top, "D").ladder == WANT
    write(tmp_path, ".lib models/params.lib max\n.include models/net.inc\n", "max.cir")
    assert import_model(tmp_path / "max.cir", "D").rth == pytest.approx(4.0)
    sections = write(tmp_path, ".lib fast\n.subckt D Tj Tc\nR1 Tj Tc 1\nC1 Tj 0 1m\n.ends\n"
                               ".endl\n.lib slow\n.subckt E Tj Tc\nR1 Tj Tc 2\nC1 Tj 0 1m\n.ends\n"
                               ".endl\n", "sections.lib")
    assert [s.name for s in read_library(sections).subckts] == ["D", "E"]


def test_an_include_leading_out_of_the_folder_or_in_circles_is_one_line(tmp_path, capsys):
    inner = tmp_path / "lib"
    inner.mkdir()
    write(tmp_path, ".subckt D Tj Tc\nR1 Tj Tc 1\nC1 Tj 0 1m\n.ends\n", "outside.lib")
    lib = write(inner, ".include ../outside.lib\n", "part.lib")
    out = tmp_path / "m.json"
    assert main(["import", str(lib), "--subckt", "D", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert "leads outside" in err and err.count("\n") == 1 and not out.exists()
    write(inner, ".include b.lib\n.subckt D Tj Tc\nR1 Tj Tc 1\nC1 Tj 0 1m\n.ends\n", "a.lib")
    write(inner, ".include a.lib\n", "b.lib")
    assert import_model(inner / "a.lib", "D").rth == 1.0  # read once each
    missing = write(inner, ".include nowhere.lib\n", "c.lib")
    with pytest.raises(DataFormatError, match="no subcircuit 'D' .there are: none"):
        import_model(missing, "D")


@pytest.mark.parametrize("text", [
    "$CDNENCSTART\n0a1b2c3d4e5f\n$CDNENCFINISH\n",
    ".prot\n3jhf83hf83hf\n.unprot\n",
    "** Begin:\n" + " 3F 91 0C 5A E2 77 1B D4 08 6E A9 30 C5 F2 4B 17\n" * 9,
])
def test_encrypted_libraries_are_refused_as_encrypted(tmp_path, text):
    with pytest.raises(DataFormatError, match="the library is encrypted"):
        import_model(write(tmp_path, "* vendor header\n" + text), "PART")


def test_plain_subcircuits_next_to_an_encrypted_block_are_read(tmp_path):
    lib = write(tmp_path, ".subckt D Tj Tc\nR1 Tj Tc 1\nC1 Tj 0 1m\n.ends\n$CDNENCSTART\nab\n")
    assert import_model(lib, "D").rth == 1.0
    with pytest.raises(DataFormatError, match="no subcircuit 'E' .*its encrypted part .*line 5"):
        import_model(lib, "E")


def test_expressions_and_functions_vendors_use():
    assert spice_number("4k7") == 4700.0 and spice_number("2MEG") == 2e6
    assert evaluate("limit(5, 0, 1)", {}) == 1.0  # PSpice: a clamp
    assert evaluate("limit(-5, 1, 0)", {}) == 0.0  # bounds in any order
    assert evaluate("pwr(-2, 2) + if(1 > 2 | 0, 10, 20)", {}) == 24.0
    with pytest.raises(NotConstant, match="node voltage"):
        evaluate("{1 + V(Tj)}", {})
    with pytest.raises(NotConstant, match="TEMP"):
        evaluate("{27 * TEMP}", {})


def test_user_functions_and_temp_as_a_parameter(tmp_path):
    lib = write(tmp_path, ".func twice(x) {2*x}\n.subckt D Tj Tc\n.func rth(a,b) {a+b}\n"
                          "R1 Tj n1 {twice(0.5)}\nC1 Tj 0 1m\nR2 n1 Tc {rth(1, TEMP/25)}\n"
                          "C2 n1 0 3m\n.ends\n")
    with pytest.raises(DataFormatError, match="TEMP .give --param TEMP"):
        import_model(lib, "D")
    assert import_model(lib, "D", params={"TEMP": "25"}).ladder == WANT


def test_what_simulators_forgive_is_forgiven_and_noted(tmp_path):
    lib = read_library(write(tmp_path, ".subckt A a b\nR1 a b 1\n.ends\n.ends\n"
                                       ".subckt D Tj Tc\nR1 Tj Tc 1\nC1 Tj 0 1m\n"))
    assert [s.name for s in lib.subckts] == ["A", "D"]
    assert any("line 4: .ENDS without .SUBCKT: ignored" in n for n in lib.notes)
    assert any(".SUBCKT D has no .ENDS: it ends with the file" in n for n in lib.notes)
    assert import_model(write(tmp_path, ".subckt D Tj Tc\nR1 Tj Tc 1\nC1 Tj 0 1m\n"), "D").rth == 1


def test_an_ltspice_binary_library_is_named_as_such(tmp_path):
    path = write(tmp_path, b"\r\n<Binary File>\r\n\r\n\x1a&\x7f\xb9\x00\x01", "part.sub")
    with pytest.raises(DataFormatError, match="part.sub: an LTspice binary .encrypted. library"):
        import_model(path, "X")
