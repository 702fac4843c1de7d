"""What the commands say: every line a newcomer reads names what happened, with its reason."""

from __future__ import annotations

import json
import re
import shutil

import pytest
from conftest import DATA

from spicethermal.cli.main import main
from spicethermal.identify.records import read_pyrth
from spicethermal.io.importers import PYRTH_MOSFET_CALIBRATION

SAMPLE = DATA / "sample_bundle"


@pytest.fixture
def sample(tmp_path):
    return str(shutil.copytree(SAMPLE, tmp_path / "mydiode"))


def test_fit_says_nothing_was_masked_and_why_an_order_was_rejected(sample, tmp_path, capsys):
    assert main(["fit", sample, "-o", str(tmp_path / "m.json")]) == 0
    out = capsys.readouterr().out
    assert "masked 0 samples" not in out and "before 0 s" not in out
    assert "no samples masked (no electrical transient given or detected)" in out
    bic = next(line for line in out.splitlines() if line.startswith("BIC per order"))
    rejected = re.findall(r"(\d+): [-\d.]+ \(rejected\)", bic)
    assert rejected  # the sample's order 5 has a lower BIC and is rejected: say why
    for order in rejected:
        assert re.search(rf"^order {order} rejected: \S.*", out, re.M), out


def test_structure_prints_the_capacity_where_it_is_resolved(sample, capsys):
    assert main(["structure", sample, "-q"]) == 0
    line = capsys.readouterr().out.strip()
    c = float(re.search(r"where ΣC = (\S+) J/K", line)[1])
    assert 0.01 < c < 1.0  # the actuator's die and package: a fraction of a J/K
    assert "diverges to" in line and "toward the ambient" in line


def test_table1_warns_when_the_datasheet_is_another_device(sample, capsys):
    assert main(["table1", sample, "--datasheet", "mur880e"]) == 0
    out = capsys.readouterr().out
    assert re.search(r"^warning: the measured Rth \(146\.\d K/W\) is 97× the datasheet's "
                     r"\(1\.51 K/W\)", out, re.M), out
    assert out.count("early-time correction") + out.count("early time:") == 1  # said once
    assert main(["table1", sample, "--datasheet", "mur880e", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert len(doc["warnings"]) == 1 and "97×" in doc["warnings"][0]


def test_a_table_calibration_off_the_record_says_how_to_write_a_k_factor(tmp_path, capsys):
    """Raw voltages through an absolute table read the device below room temperature; the
    error gives the exact bundle.json keys, and following it word for word works."""
    b = read_pyrth(DATA / "pyrth_mosfet" / "MOSFET_dry.txt", PYRTH_MOSFET_CALIBRATION)
    cooling = b.cooling[0].__class__(b.cooling[0].t_s, 1.0, v_tsp_v=b.cooling[0].v_tsp_v,
                                     file="cooling_1.csv")
    path = b.with_(ambient_c=25.0, cooling=(cooling,)).write(tmp_path / "table")
    assert main(["structure", str(path), "-q"]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and err.endswith("--k-factor -2.324 --ambient 25")
    keys = re.search(r'"format": ("[^"]+") and "calibration": (\{[^}]+\})', err)
    assert keys, err
    doc = json.loads((path / "bundle.json").read_text())
    doc["format"], doc["calibration"] = json.loads(keys[1]), json.loads(keys[2])
    assert set(doc["calibration"]) == {"kind", "k_mv_per_k", "v_ref_v", "t_ref_c"}
    (path / "bundle.json").write_text(json.dumps(doc))
    assert main(["structure", str(path), "-q"]) == 0
    assert "Rth = 13.7" in capsys.readouterr().out
