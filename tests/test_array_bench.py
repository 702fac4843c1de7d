"""Measuring an array: the firmware's coupling procedure on the simulated array, the bundle's
coupling section (format 4), the measured Z_ij and their fit."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from spicethermal.array.data import coupling_from_bundle
from spicethermal.array.fit import fit_array
from spicethermal.bench import protocol as p
from spicethermal.bench.array_devices import ArrayGeometry
from spicethermal.bench.client import BenchClient
from spicethermal.bench.session import run_bench
from spicethermal.core.errors import DataFormatError, InstrumentError
from spicethermal.io.bundle import Bundle

GRID = {"array_rows": 2, "array_cols": 2}


@pytest.fixture(scope="module")
def square_bundle(tmp_path_factory) -> Path:
    """A 2 x 2 array measured on the simulated bench: calibration, then heat one, read all."""
    out = tmp_path_factory.mktemp("array") / "square"
    url = "sim://array?rows=2&cols=2&seed=3"
    run_bench(url, out, actions=["calibrate"], calibration_c=(25.0, 45.0, 65.0),
              calibration_settle_s=120.0, **GRID)
    run_bench(url, out, actions=["coupling"], settle_s=200.0, cooling_t_last_s=200.0, **GRID)
    return out


def test_the_board_scans_every_port_in_order() -> None:
    with BenchClient("sim://array?rows=1&cols=3&seed=1") as bench:
        assert bench.info.ports == 3 and bench.info.firmware == "1.3.0"
        assert bench.info.proto == 4
        run = bench.coupling(2, 0.25, 30.0, 1e-4, 2, 1e-4, 10.0, 10)
    kinds = {k: [s for s in run.samples if s.kind == k]
             for k in (p.KIND_CURVE, p.KIND_STEADY, p.KIND_POWER, p.KIND_COLD)}
    assert all(isinstance(s, p.ArraySample) and s.proc == p.PROC_COUPLING for s in run.samples)
    assert len(kinds[p.KIND_COLD]) == 6 and len(kinds[p.KIND_STEADY]) == 6
    assert len(kinds[p.KIND_POWER]) == 2
    assert {s.port for s in kinds[p.KIND_POWER]} == {2}  # the power of the heated port
    curve = kinds[p.KIND_CURVE]
    assert [s.port for s in curve[:6]] == [0, 1, 2, 0, 1, 2]
    assert [s.t_us for s in curve[:3]] == [100, 120, 140]  # port m at 20 us · m
    hot = [s.v_tsp_uv for s in curve[:3]]
    assert hot[2] < hot[0] < 0  # the heated diode reads hottest (its TSP falls with T)


def test_a_single_heater_board_refuses_the_coupling_in_one_line() -> None:
    with BenchClient("sim://actuator?seed=1") as bench:
        assert bench.info.ports == 0
        with pytest.raises(InstrumentError, match="not an array board") as info:
            bench.coupling(0, 0.1, 10.0, 1e-4, 1, 1e-4, 1.0, 10)
    assert "\n" not in str(info.value)
    with pytest.raises(Exception, match="options of sim://array"):
        BenchClient("sim://actuator?rows=2")


def test_the_bundle_holds_the_coupling_section_in_format_4(square_bundle) -> None:
    doc = json.loads((square_bundle / "bundle.json").read_text())
    assert doc["format"] == "spicethermal-bundle/4"
    sec = doc["coupling"]
    assert [c["heated"] for c in sec["curves"]] == ["R1C1", "R1C2", "R2C1", "R2C2"]
    assert sec["scan_s"] == pytest.approx(2e-5) and sec["raw"].startswith("raw/")
    bundle = Bundle.read(square_bundle)
    assert bundle.calibration is not None and len(bundle.coupling.curves) == 4
    header = (square_bundle / "coupling_1.csv").read_text().splitlines()[0]
    assert header == "t_s,tj1_c,tj2_c,tj3_c,tj4_c,tref_c"
    # a bundle without coupling is written as before
    again = bundle.with_(coupling=None)
    assert again.manifest()["format"] == "spicethermal-bundle/1"


def test_the_measured_matrix_is_fitted_within_two_percent(square_bundle) -> None:
    data = coupling_from_bundle(Bundle.read(square_bundle))
    assert len(data.elements) == 16
    fit = fit_array(data, order=4)
    assert fit.max_error < 0.02  # every Z_ij within 2 % of Z_ii's final value
    truth = ArrayGeometry(rows=2, cols=2).model()
    ratio = fit.model.modes.dc() / np.diag(fit.model.modes.dc())[:, None]
    true_ratio = truth.modes.dc() / np.diag(truth.modes.dc())[:, None]
    np.testing.assert_allclose(ratio, true_ratio, atol=0.02)


def test_coupling_sections_are_checked_on_reading(square_bundle, tmp_path) -> None:
    doc = json.loads((square_bundle / "bundle.json").read_text())
    for name in ("calibration.csv", *(f"coupling_{k}.csv" for k in range(1, 5))):
        (tmp_path / name).write_text((square_bundle / name).read_text())
    for older in ("spicethermal-bundle/2", "spicethermal-bundle/3"):
        (tmp_path / "bundle.json").write_text(json.dumps(dict(doc, format=older)))
        with pytest.raises(DataFormatError,
                           match="key coupling: the coupling section needs format"):
            Bundle.read(tmp_path)
    bad = json.loads(json.dumps(doc))
    bad["coupling"]["curves"][1]["heated"] = "D9"
    (tmp_path / "bundle.json").write_text(json.dumps(bad))
    with pytest.raises(DataFormatError, match=r"curves\[1\]\.heated: 'D9' is not one of"):
        Bundle.read(tmp_path)
    (tmp_path / "bundle.json").write_text(json.dumps(doc))
    (tmp_path / "coupling_2.csv").write_text("t_s,tj1_c,tj2_c,tj3_c\n0.1,30,30,30\n")
    with pytest.raises(DataFormatError, match="coupling_2.csv.*missing column tj4_c"):
        Bundle.read(tmp_path)
    with pytest.raises(DataFormatError, match="no coupling section"):
        coupling_from_bundle(Bundle.read(square_bundle).with_(coupling=None))


def test_a_protocol_3_device_refuses_the_coupling_in_one_line(monkeypatch) -> None:
    """A device older than protocol 4 has no coupling procedure: refused before any command."""
    from spicethermal.bench import client as bc

    monkeypatch.setattr(bc, "COUPLING_PROTOCOL", p.PROTOCOL_VERSION + 1)
    with BenchClient("sim://array?rows=1&cols=2&seed=1") as bench:
        with pytest.raises(InstrumentError, match="has no coupling procedure") as info:
            bench.coupling(0, 0.1, 10.0, 1e-4, 1, 1e-4, 1.0, 10)
    assert "\n" not in str(info.value)
    old = p.Info(3, 1, 2, 0, 10, 32, 0x0401, 86_400_000, "actuator", 1000)
    assert old.ports == 0  # caps bits 8..15 mean nothing before protocol 4


def test_forward_and_coupling_together_are_format_4(square_bundle, tmp_path) -> None:
    """The forward section (format 3) and the coupling section (format 4) in one bundle: /4;
    the forward section alone stays /3, and both read back."""
    from spicethermal.io.bundle import ForwardTable

    fwd = ForwardTable([25.0, 25.0, 65.0], [1e-3, 0.1, 0.1], [0.62, 0.78, 0.71],
                       [0.0, 2e-5, 2e-5], 1e-3, file="forward.csv")
    both = Bundle.read(square_bundle).with_(forward=fwd)
    assert both.manifest()["format"] == "spicethermal-bundle/4"
    assert both.with_(coupling=None).manifest()["format"] == "spicethermal-bundle/3"
    again = Bundle.read(both.write(tmp_path / "both"))
    assert again.forward.vf_v.tolist() == [0.62, 0.78, 0.71]
    assert len(again.coupling.curves) == 4
