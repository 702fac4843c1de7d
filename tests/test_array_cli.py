"""The array through the command line: ``fit`` of a coupling bundle, ``export`` of an array
model (checked in ngspice), ``drive`` of patterns and of a line of text with its report, the
one-line refusals, and the single-device flow left as it was."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from spicethermal.array.model import ArrayModel, is_array_document
from spicethermal.bench.array_devices import ArrayGeometry
from spicethermal.bench.session import run_bench
from spicethermal.cli import main as cli
from spicethermal.core.ladder import Foster
from spicethermal.model import ThermalModel
from spicethermal.spice.lib import Pins, render_lib

NGSPICE = pytest.mark.skipif(shutil.which("ngspice") is None, reason="ngspice not installed")
DRIVE = ["--t-max", "85", "--target", "70", "--tol", "1", "--actuation", "64.7", "--power", "1.5"]


@pytest.fixture(scope="module")
def square_bundle(tmp_path_factory) -> Path:
    """A 2 x 2 array measured on the simulated bench (calibration, heat one, read all)."""
    out = tmp_path_factory.mktemp("cli") / "square"
    url = "sim://array?rows=2&cols=2&seed=5"
    grid = {"array_rows": 2, "array_cols": 2}
    run_bench(url, out, actions=["calibrate"], calibration_c=(25.0, 45.0, 65.0),
              calibration_settle_s=120.0, **grid)
    run_bench(url, out, actions=["coupling"], settle_s=200.0, cooling_t_last_s=200.0, **grid)
    return out


@pytest.fixture(scope="module")
def square_model(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("cli") / "square.json"
    ArrayGeometry(rows=2, cols=2).model().save(path)
    return path


@pytest.fixture(scope="module")
def braille_model(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("cli") / "cell.json"
    ArrayGeometry().model().save(path)  # an eight-dot cell, ports D1 ... D8
    return path


def _one_line_error(capsys, code: int, *words: str) -> None:
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1, err
    assert "Traceback" not in err and all(w in err for w in words), err


def test_fit_of_a_coupling_bundle_writes_the_array_model_with_every_element(
        square_bundle, tmp_path, capsys) -> None:
    out = tmp_path / "fit.json"
    assert cli.main(["fit", str(square_bundle), "--order", "2", "-o", str(out)]) == 0
    text = capsys.readouterr().out
    assert "error per element, % of Z_ii final" in text
    rows = [line.split() for line in text.splitlines() if line.startswith("R") and "  " in line]
    table = [r for r in rows if len(r) == 5 and r[0] in ("R1C1", "R1C2", "R2C1", "R2C2")]
    assert len(table) == 4  # one row per read port, one column per heated port
    model = ArrayModel.load(out)
    fit = model.provenance["fit"]
    assert fit["order"] == 2 and np.array(fit["error_per_element"]).shape == (4, 4)
    shown = np.array([[float(x) for x in r[1:]] for r in table])
    np.testing.assert_allclose(shown, 100 * np.array(fit["error_per_element"]), atol=0.006)
    assert is_array_document(out)


def test_array_only_and_single_only_options_are_refused_in_one_line(
        square_bundle, square_model, tmp_path, capsys) -> None:
    code = cli.main(["fit", str(square_bundle), "--bootstrap", "5", "-o", str(tmp_path / "x")])
    _one_line_error(capsys, code, "--bootstrap", "not for an array")
    code = cli.main(["export", str(square_model), "--topology", "foster", "-o",
                     str(tmp_path / "x.lib")])
    _one_line_error(capsys, code, "--topology", "TJ1 ... TJN TREF")
    assert not (tmp_path / "x.lib").exists()
    code = cli.main(["export", str(square_model), "--electrothermal", "-o",
                     str(tmp_path / "x.lib")])
    _one_line_error(capsys, code, "--electrothermal", "array model")
    assert not (tmp_path / "x.lib").exists()
    code = cli.main(["drive", str(square_model), *DRIVE, "--text", "ab", "--circuit"])
    _one_line_error(capsys, code, "--circuit", "not for an array")
    code = cli.main(["drive", str(square_model), "--t-max", "85", "--target", "70",
                     "--text", "ab"])
    _one_line_error(capsys, code, "--actuation")
    code = cli.main(["drive", str(square_model), *DRIVE])
    _one_line_error(capsys, code, "--text", "--patterns")
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps([{"up": ["R1C1"]}, {"up": ["Z9"]}]))
    code = cli.main(["drive", str(square_model), *DRIVE, "--patterns", str(bad)])
    _one_line_error(capsys, code, "bad.json", "pattern 2", "R1C1")
    code = cli.main(["drive", str(square_model), *DRIVE, "--text", "ab"])
    _one_line_error(capsys, code, "D1")  # text needs a Braille cell


@NGSPICE
def test_export_of_an_array_is_the_n_port_lib_checked_in_ngspice(square_model, tmp_path,
                                                                  capsys) -> None:
    out = tmp_path / "square.lib"
    assert cli.main(["export", str(square_model), "--name", "SQ4", "--verify",
                     "-o", str(out)]) == 0
    text = out.read_text()
    assert ".SUBCKT SQ4 TJ1 TJ2 TJ3 TJ4 TREF" in text and "limit(" not in text.lower()
    said = capsys.readouterr().out
    worst = float(said.split("largest difference from the model ")[1].split(" %")[0])
    assert worst < 0.5  # % of Z_ii


@NGSPICE
def test_drive_of_patterns_is_verified_and_compared_with_the_naive_one(square_model, tmp_path,
                                                                        capsys) -> None:
    patterns = tmp_path / "p.json"
    patterns.write_text(json.dumps([{"up": ["R1C1", "R2C2"]}, {"up": ["R1C2"]}]))
    assert cli.main(["drive", str(square_model), *DRIVE, "--patterns", str(patterns),
                     "--verify", "--json", "-q"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["format"] == "spicethermal-array-drive/1" and doc["kind"] == "patterns"
    assert [p["up"] for p in doc["patterns"]] == [["R1C1", "R2C2"], ["R1C2"]]
    for pat in doc["patterns"]:
        assert pat["refresh_s"]["ours"] is not None and pat["raised_s"]["ours"] is not None
        assert pat["raised_s"]["ours"] <= pat["refresh_s"]["ours"]
    assert doc["violations"]["ours"] == {"t_max": 0, "actuation": 0}
    check = doc["ngspice"]["ours"]
    assert check["t_max"] == 0 and check["actuation"] == 0 and check["runs"] >= 2
    assert max(check["peak_c"]) <= 85.0 and check["peak_error_k"] < 0.05
    assert set(doc["ngspice"]) == {"ours", "naive"}


def test_drive_of_a_line_of_text_writes_the_heat_map_report(braille_model, tmp_path,
                                                            capsys) -> None:
    report = tmp_path / "report"
    assert cli.main(["drive", str(braille_model), *DRIVE, "--text", "ab", "--cells", "3",
                     "--report", str(report), "-q"]) == 0
    said = capsys.readouterr().out
    assert "refresh rate of a line from blank" in said and "naive" in said
    doc = json.loads((report / "drive.json").read_text())
    assert doc["kind"] == "text" and doc["cells"] == 3 and doc["lines"] == ["ab"]
    assert doc["distinct_columns"] == 3  # 'a', 'b' and the blank
    ours = doc["refresh_s"]["ours"][0]
    assert ours is not None and doc["refresh_rate_hz"][0] == pytest.approx(1 / ours)
    assert doc["violations"]["ours"] == {"t_max": 0, "actuation": 0}
    page = (report / "index.html").read_text()
    assert "heatmap.png" in page and f"{1e3 * ours:.1f}" in page
    assert (report / "heatmap.png").stat().st_size > 10_000


def test_the_single_device_flow_is_unchanged(tmp_path, capsys) -> None:
    single = ThermalModel(Foster.from_tau([6.0, 20.0, 50.0, 70.0], [2e-4, 5e-3, 0.4, 12.0]))
    path = single.save(tmp_path / "single.json")
    assert not is_array_document(path)
    out = tmp_path / "single.lib"
    assert cli.main(["export", str(path), "--name", "ACT", "-o", str(out)]) == 0
    assert "TJ1" not in capsys.readouterr().out
    assert out.read_text() == render_lib(single, "ngspice", None, "ACT", filename=out.name,
                                         pins=Pins.parse("TJ,TREF"), temperature="absolute")
    code = cli.main(["drive", str(path), "--t-max", "85", "--target", "70", "--text", "ab"])
    _one_line_error(capsys, code, "--text", "single device")
    assert cli.main(["drive", str(path), "--t-max", "85", "--target", "70", "--power", "1",
                     "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert not str(doc.get("format", "")).startswith("spicethermal-array")


def test_an_order_the_records_do_not_determine_is_refused_with_the_reason(
        square_bundle, tmp_path, capsys) -> None:
    code = cli.main(["fit", str(square_bundle), "--order", "99", "-o", str(tmp_path / "x")])
    _one_line_error(capsys, code, "order-99", "do not determine 99 levels per cell", "'auto'")
    assert not (tmp_path / "x").exists()
