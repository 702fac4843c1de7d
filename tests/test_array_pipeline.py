"""The whole array pipeline on the simulated eight-dot cell, through the command line: measure
(heat one, read all), fit (order by BIC), export (checked in ngspice), a line of text driven and
checked in ngspice against the naive drive. Minutes: the slow tier (``make test``)."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest

from spicethermal.array.data import coupling_from_bundle
from spicethermal.cli import main as cli
from spicethermal.io.bundle import Bundle

pytestmark = [pytest.mark.slow, pytest.mark.ngspice,
              pytest.mark.skipif(shutil.which("ngspice") is None, reason="ngspice not installed")]


def test_a_braille_cell_is_measured_fitted_exported_and_driven(tmp_path, capsys) -> None:
    bundle, model, lib = tmp_path / "cell", tmp_path / "cell.json", tmp_path / "cell.lib"
    url = "sim://array?seed=11"
    assert cli.main(["bench", "calibrate", "--port", url, "-o", str(bundle), "-q",
                     "--setpoint", "25,45,65"]) == 0
    assert cli.main(["bench", "coupling", "--port", url, "-o", str(bundle), "-q"]) == 0
    data = coupling_from_bundle(Bundle.read(bundle))
    final = data.final()
    ratio = (final / np.diag(final)[:, None])[~np.eye(len(final), dtype=bool)]
    assert len(final) == 8 and 0.05 <= ratio.min() and ratio.max() <= 0.30
    assert cli.main(["fit", str(bundle), "-o", str(model)]) == 0
    fit = json.loads(model.read_text())["provenance"]["fit"]
    assert fit["max_error"] <= 0.02  # every Z_ij within 2 % of Z_ii's final value
    capsys.readouterr()
    assert cli.main(["export", str(model), "--verify", "-o", str(lib)]) == 0
    said = capsys.readouterr().out
    assert float(said.split("largest difference from the model ")[1].split(" %")[0]) <= 0.5
    assert cli.main(["drive", str(model), "--t-max", "85", "--target", "70", "--tol", "1",
                     "--actuation", "64.7", "--power", "1.5", "--text", "quy the", "--cells", "8",
                     "--verify", "--json", "-q"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["refresh_s"]["ours"][0] is not None
    assert doc["ngspice"]["ours"]["t_max"] == 0 and doc["ngspice"]["ours"]["actuation"] == 0
    naive = doc["ngspice"]["naive"]
    assert naive["t_max"] + naive["actuation"] > 0  # crosstalk ignored: the naive one overheats
