"""Every input class of the reliability issue's CLI fuzz ends in exit 0 or in one printable
line and exit 2; JSON output never carries NaN or Infinity (docs/reliability.md)."""

from __future__ import annotations

import json
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

from spicethermal.cli.main import main
from spicethermal.core.ladder import Foster
from spicethermal.io.bundle import Bundle, CoolingTable, PwmTable
from spicethermal.model import ThermalModel

LADDER = Foster.from_tau((6.0, 20.0, 50.0, 70.0), (1e-4, 5e-3, 0.4, 30.0))


def run(argv: list[str], capsys) -> tuple[int, str, str]:
    capsys.readouterr()
    with warnings.catch_warnings():
        warnings.simplefilter("default")  # as a user runs it: warnings are not errors
        code = main(argv)
    out, err = capsys.readouterr()
    return code, out, err


def one_line_error(code: int, err: str, *needles: str) -> None:
    assert code == 2, err
    assert err.count("\n") == 1 and err.endswith("\n") and err[:-1].isprintable(), err
    assert "Traceback" not in err and "internal error" not in err and "Warning" not in err
    for needle in needles:
        assert needle in err, err


def strict_json(text: str):
    return json.loads(text, parse_constant=lambda c: pytest.fail(f"{c} in JSON output"))


@pytest.fixture
def model(tmp_path: Path) -> Path:
    return ThermalModel(LADDER).save(tmp_path / "model.json")


def bundle(tmp_path: Path, t_s=None) -> Path:
    t = np.geomspace(1e-4, 30.0, 20) if t_s is None else np.asarray(t_s)
    tj = 25.0 + 0.1 * (LADDER.rth - LADDER.zth(t))
    duties = np.array([0.2, 0.8, 0.2, 0.8])
    tj_pwm = 25.0 + 0.1 * LADDER.rth * duties
    return Bundle(ambient_c=25.0, cooling=(CoolingTable(t, 0.1, tj, tj_steady_c=39.6,
                                                        tref_steady_c=25.0),),
                  pwm=PwmTable([1e3, 1e3, 1e4, 1e4], duties, tj_pwm, power_w=0.1)
                  ).write(tmp_path / "b")


def test_provenance_that_is_not_an_object(tmp_path, model, capsys) -> None:
    doc = json.loads(model.read_text())
    doc["provenance"] = [1, 2]
    model.write_text(json.dumps(doc))
    code, _, err = run(["export", str(model), "-o", str(tmp_path / "x.lib")], capsys)
    one_line_error(code, err, "model.json", "'provenance' must be an object")


@pytest.mark.parametrize("text,needle", [("[" * 100000 + "]" * 100000, "nested 100000 levels"),
                                         ('{"format": 1e400}', "1e400 is out of range")])
def test_deep_or_overflowing_json(tmp_path, capsys, text, needle) -> None:
    (tmp_path / "m.json").write_text(text)
    code, _, err = run(["pwm", str(tmp_path / "m.json"), "--freq", "1000", "--duty", "0.5",
                        "--power", "1"], capsys)
    one_line_error(code, err, "m.json", needle)


def test_nul_and_control_characters_in_file_names(tmp_path, model, capsys) -> None:
    code, _, err = run(["export", str(tmp_path / "a\x00b.json"), "-o", "x.lib"], capsys)
    one_line_error(code, err, "NUL character")
    odd = tmp_path / "a\nb\x1b[31m.json"
    odd.write_text(model.read_text().replace("foster", "nonsense"))
    p = subprocess.run([sys.executable, "-m", "spicethermal.cli.main", "export", str(odd), "-o",
                        str(tmp_path / "x.lib")], capture_output=True, text=True, timeout=120)
    one_line_error(p.returncode, p.stderr, "a\\nb\\x1b[31m.json")


def test_1e400_in_a_csv_names_file_row_and_column(tmp_path, model, capsys) -> None:
    b = bundle(tmp_path)
    lines = (b / "cooling_1.csv").read_text().splitlines()
    lines[3] = "1e400," + lines[3].split(",", 1)[1]
    (b / "cooling_1.csv").write_text("\n".join(lines) + "\n")
    code, _, err = run(["compare", str(model), str(b)], capsys)
    one_line_error(code, err, "cooling_1.csv, row 4, column t_s", "not a finite number")


def test_absurd_power_gives_a_result_or_a_clean_error(model, capsys) -> None:
    code, out, err = run(["pwm", str(model), "--freq", "1000", "--duty", "0.5", "--power",
                          "1e306", "--json"], capsys)
    if code == 0:
        strict_json(out)
    else:
        one_line_error(code, err)


@pytest.mark.parametrize("rows", [
    ["1000,0.2,30,30", "1000,0.8,30,30", "25000,0.2,30,30", "25000,0.8,30,30"],  # constant
    ["1000,0.2,29.4,29.4", "1000,0.8,40.2,40.2", "25000,0.2,29.4,29.4",
     "25000,0.8,40.2,40.2"],  # measured equal to simulated
])
def test_degenerate_table2_columns(tmp_path, capsys, rows) -> None:
    path = tmp_path / "t2.csv"
    path.write_text("freq_hz,duty,tj_exp_c,tj_model_c\n" + "\n".join(rows) + "\n")
    code, out, err = run(["diagnose", str(path), "--json"], capsys)
    if code == 0:
        strict_json(out)
    else:
        one_line_error(code, err)


def test_diagnose_with_a_model_on_single_point_curves(tmp_path, model, capsys) -> None:
    b = bundle(tmp_path, t_s=[1e-3])
    code, out, err = run(["diagnose", str(b), "--model", str(model), "--json", "-q"], capsys)
    if code == 0:
        strict_json(out)
    else:
        one_line_error(code, err)


@pytest.mark.parametrize("name", ["a$b.png", "x^2.png", "$^$.png"])
def test_mathtext_characters_in_a_figure_name(tmp_path, model, capsys, name) -> None:
    code, _, err = run(["curves", str(model), "--plot", str(tmp_path / name)], capsys)
    assert code == 0, err
    assert (tmp_path / name).stat().st_size > 0


def test_absurd_pwm_readings_are_refused_on_reading(tmp_path, model, capsys) -> None:
    b = bundle(tmp_path)
    text = (b / "pwm.csv").read_text().splitlines()
    cells = text[2].split(",")
    cells[2] = "1e308"  # freq_hz, duty, tj_c
    text[2] = ",".join(cells)
    (b / "pwm.csv").write_text("\n".join(text) + "\n")
    code, _, err = run(["diagnose", str(b), "--model", str(model), "-q"], capsys)
    one_line_error(code, err, "pwm.csv, row 3, column tj_c", "above 2000 degC")
