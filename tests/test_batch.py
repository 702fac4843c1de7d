"""``spicethermal batch``: the runner on a local Dask cluster, error rows, atomic per-device
results, resume by content hash, a dead worker's retry, and the command end to end."""

from __future__ import annotations

import csv
import functools
import json
import os
import re
import sys
from pathlib import Path

import numpy as np
import pytest

from spicethermal.batch.device import COLUMNS, Options, Source, characterize
from spicethermal.batch.population import device_bundle, simulate_population, write_population
from spicethermal.batch.runner import cluster_client, find_sources, load_results, run_batch
from spicethermal.cli.main import main
from spicethermal.core.errors import DataFormatError
from spicethermal.model import ThermalModel

pytest.importorskip("distributed")


@pytest.fixture(scope="module")
def client():
    import dask

    # a task whose worker dies once is retried; twice, it is given up (KilledWorker)
    with dask.config.set({"distributed.scheduler.allowed-failures": 1}), \
            cluster_client(workers=2) as c:
        yield c


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    root = tmp_path_factory.mktemp("inputs")
    devices = write_population(root / "pop", 10, seed=4, defects=1)
    bad = root / "bad"
    bad.mkdir()
    (bad / "broken.csv").write_text("t_s,zth_k_per_w\n1e-3,0.1\nx,0.2\n")
    partial = bad / "partial"
    device_bundle(devices[0]).write(partial)
    (partial / "cooling_1.csv").unlink()
    return root, devices


def _csv_rows(path: Path) -> list[dict[str, str]]:
    with open(path, newline="") as handle:
        return list(csv.DictReader(handle))


def test_rows_models_libs_and_error_rows(client, inputs, tmp_path):
    root, devices = inputs
    out = tmp_path / "out"
    run = run_batch([root / "pop", root / "bad"], out, client=client,
                    options=Options(diagnose=False))
    assert (run.computed, run.reused) == (12, 0)
    rows = {r["name"]: r for r in run.rows}
    assert rows["broken"]["error"].endswith("broken.csv, row 3, column t_s: malformed number 'x'")
    assert "cooling_1.csv" in rows["partial"]["error"]
    for d in devices:
        row = rows[d.name]
        assert row["error"] == "" and row["order"] == 4
        assert row["rth_k_per_w"] == pytest.approx(d.cauer.rth, rel=2e-3)
        assert row["tau_max_s"] == pytest.approx(max(d.cauer.to_foster().tau), rel=0.05)
        assert row["fit_rms_k"] == pytest.approx(row["fit_rms_k_per_w"] * 20.0)
        model = ThermalModel.load(out / "devices" / d.name / "model.json")
        assert model.rth == pytest.approx(row["rth_k_per_w"], rel=1e-12)
        lib = (out / "devices" / d.name / f"{d.name}.lib").read_text()
        assert f".SUBCKT {d.name.upper()} TJ TREF" in lib
    table = _csv_rows(out / "results.csv")
    assert list(table[0]) == list(COLUMNS)
    assert [r["name"] for r in table] == [r["name"] for r in run.rows]
    import pyarrow.parquet as pq

    assert pq.read_table(out / "results.parquet").num_rows == 12
    assert not list(out.rglob("*.tmp"))


def test_resume_redoes_only_unfinished_and_changed_inputs(client, inputs, tmp_path):
    root, devices = inputs
    src = tmp_path / "src"
    for d in devices[:4]:
        device_bundle(d).write(src / d.name)
    device_bundle(devices[0]).write(src / "twin")  # the same bytes under another name
    out = tmp_path / "out"
    first = run_batch([src], out, client=client, options=Options(diagnose=False))
    assert first.computed == 5
    with pytest.raises(DataFormatError, match="--resume"):
        run_batch([src], out, client=client, options=Options(diagnose=False))
    # interrupted before device 2 finished: no result.json, a stale temporary file
    (out / "devices" / devices[1].name / "result.json").unlink()
    (out / "devices" / devices[1].name / ".result.json.x.tmp").write_text("{")
    device_bundle(devices[2], seed=99).write(src / devices[2].name)  # re-measured
    again = run_batch([src], out, client=client, options=Options(diagnose=False), resume=True)
    assert (again.computed, again.reused) == (2, 3)
    names = [d.name for d in devices[:4]] + ["twin"]
    assert [r["row"]["name"] for r in again.results] == names
    assert sorted(name for _, name in load_results(out)) == names
    assert again.rows[0]["rth_k_per_w"] == first.rows[0]["rth_k_per_w"] == \
        again.rows[4]["rth_k_per_w"]


def _crash_once(source, options, markers):
    marker = Path(markers) / source.name
    if source.name == "device_002" and not marker.exists():
        marker.write_text("died")
        os._exit(1)
    return characterize(source, options)


def _crash_always(source, options):
    if source.name == "device_003":
        os._exit(1)
    return characterize(source, options)


def test_a_dead_workers_task_is_retried_and_a_killer_input_gets_an_error_row(
        client, inputs, tmp_path):
    import cloudpickle

    root, devices = inputs
    src = tmp_path / "src"
    for d in devices[:4]:
        device_bundle(d).write(src / d.name)
    markers = tmp_path / "markers"
    markers.mkdir()
    cloudpickle.register_pickle_by_value(sys.modules[__name__])
    try:
        run = run_batch([src], tmp_path / "once", client=client,
                        options=Options(diagnose=False),
                        task=functools.partial(_crash_once, markers=str(markers)))
        assert (markers / "device_002").exists()  # its worker did die
        assert [r["error"] for r in run.rows] == [""] * 4
        run = run_batch([src], tmp_path / "always", client=client,
                        options=Options(diagnose=False), task=_crash_always)
    finally:
        cloudpickle.unregister_pickle_by_value(sys.modules[__name__])
    errors = {r["name"]: r["error"] for r in run.rows}
    assert "died" in errors.pop("device_003")
    assert set(errors.values()) == {""}


def test_sources_are_found_named_and_the_output_is_skipped(tmp_path):
    for p in ("a/x.csv", "b/x.csv", "b/.hidden.csv", "c/bundle.json", "c/in_bundle.csv",
              "out/results.csv", "notes.txt"):
        (tmp_path / p).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / p).write_text("")
    found = find_sources([tmp_path], exclude=tmp_path / "out")
    assert [(p.relative_to(tmp_path).as_posix(), n) for p, n in found] == \
        [("a/x.csv", "x"), ("b/x.csv", "x_2"), ("c", "c")]
    with pytest.raises(DataFormatError, match="no such file"):
        find_sources([tmp_path / "missing"])
    with pytest.raises(DataFormatError, match="no bundle directory or .csv"):
        find_sources([tmp_path / "out"], exclude=tmp_path / "out")


def test_content_hash_keys_on_bytes_not_paths(tmp_path):
    bundle = device_bundle(simulate_population(1)[0])
    a, b = bundle.write(tmp_path / "a"), bundle.write(tmp_path / "b")
    assert Source.read(a, "a").sha256 == Source.read(b, "b").sha256
    (b / "cooling_1.csv").write_text((b / "cooling_1.csv").read_text() + "\n# re-measured\n")
    assert Source.read(a, "a").sha256 != Source.read(b, "b").sha256


@pytest.mark.slow
def test_command_end_to_end_on_a_simulated_population(tmp_path, capsys):
    out = tmp_path / "out"
    code = main(["batch", "--simulate", "12", "--seed", "4", "-o", str(out), "--workers", "2",
                 "--effect", "electrical-transient", "--freq", "1000", "--duty", "0.2,0.8"])
    assert code == 0
    text = capsys.readouterr().out
    truth = json.loads((out / "population" / "population.json").read_text())
    planted = [d["name"] for d in truth["devices"] if d["defect"]]
    assert len(planted) == 1
    outliers = _csv_rows(out / "outliers.csv")
    assert [o["name"] for o in outliers] == planted
    assert outliers[0]["reason"].startswith("larger outer resistance")
    assert f"outlier {planted[0]}: larger outer resistance" in text
    rows = _csv_rows(out / "results.csv")
    assert len(rows) == 12 and {r["verdict"] for r in rows} == {"none"}
    # empty when the diagnosis fitted no candidate (the linear model is at the noise already)
    assert all(r["improvement"] == "" or float(r["improvement"]) > 0 for r in rows)
    for name in ("typical", "worst"):
        lib = (out / "spread" / f"{name}.lib").read_text()
        assert f".SUBCKT {name.upper()} TJ TREF" in lib
    typ = ThermalModel.load(out / "spread" / "typical.json")
    worst = ThermalModel.load(out / "spread" / "worst.json")
    good = [float(r["rth_k_per_w"]) for r in rows if r["name"] not in planted]
    assert typ.rth == pytest.approx(np.median(good), rel=1e-9)
    assert worst.rth == pytest.approx(max(good), rel=1e-9)
    t = np.logspace(-4, 1, 11)
    assert np.all(worst.ladder.zth(t) >= typ.ladder.zth(t) - 1e-3)
    peaks = _csv_rows(out / "pwm_peaks.csv")
    assert [(p["freq_hz"], p["duty"]) for p in peaks] == [("1000.0", "0.2"), ("1000.0", "0.8")]
    assert all(float(p["peak_p50_k"]) <= float(p["peak_p90_k"]) <= float(p["peak_max_k"])
               for p in peaks)
    from spicethermal.report.html import figure_is_nontrivial

    page = (out / "index.html").read_text()
    assert planted[0] in page and "larger outer resistance" in page
    for fig in ("rth_histogram", "zth_population", "verdicts"):
        assert figure_is_nontrivial(out / "figures" / f"{fig}.png")


@pytest.mark.parametrize("argv, message", [
    (["batch", "MISSING", "-o", "OUT"], "MISSING: no such file or directory"),
    (["batch", "-o", "OUT"], "give SOURCES"),
    (["batch", "--simulate", "2", "--duty", "1.5", "-o", "OUT"], "--duty 1.5"),
    (["batch", "--simulate", "2", "--effect", "nope", "-o", "OUT"], "nope"),
    (["batch", "--simulate", "2", "MISSING", "-o", "OUT"], "MISSING: no such file"),
])
def test_bad_input_is_one_line_and_writes_nothing(argv, message, tmp_path, capsys,
                                                  monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and message in err and err.startswith("spicethermal batch")
    assert not (tmp_path / "OUT").exists()


def test_workers_and_scheduler_exclude_each_other(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["batch", "x", "-o", "y", "--workers", "2", "--scheduler", "tcp://127.0.0.1:1"])
    assert exc.value.code == 2
    assert "not allowed with argument" in capsys.readouterr().err


# ------------------------------------------------------------------------------ issue #45
def _copies(root: Path, n: int) -> list[Path]:
    """``n`` copies of one simulated device, in directories of their own names."""
    bundle = device_bundle(simulate_population(1, seed=2)[0])
    return [bundle.write(root / f"copy_{i}") for i in range(n)]


def test_identical_inputs_are_flagged_and_counted_once(tmp_path):
    """Four identical inputs: one device, three duplicates (by content hash, in results.csv
    and the report); the robust σ is the documented 1 % floor, not 0; the PWM peaks are at
    the bundles' power, not 1 W (no Dask: the runner's own steps, in process)."""
    from spicethermal.batch.runner import mark_duplicates, write_table
    from spicethermal.batch.summary import summarize

    paths = _copies(tmp_path / "in", 4)
    results = [characterize(Source.read(p, p.name), Options(diagnose=False)) for p in paths]
    rows = [r["row"] for r in results]
    mark_duplicates(rows)
    write_table(rows, tmp_path / "out")
    table = _csv_rows(tmp_path / "out" / "results.csv")
    assert [r["duplicate_of"] for r in table] == ["", "copy_0", "copy_0", "copy_0"]
    summary = summarize(results, tmp_path / "out", freqs_hz=[1e3], duties=[0.5])
    power = float(table[0]["power_w"])
    assert power == pytest.approx(20.0, rel=0.05)  # the simulated bundles' power, not 1 W
    assert summary.power_w == pytest.approx(power)
    peaks = _csv_rows(tmp_path / "out" / "pwm_peaks.csv")
    assert float(peaks[0]["power_w"]) == pytest.approx(power) and peaks[0]["devices"] == "1"
    page = (tmp_path / "out" / "index.html").read_text()
    assert "robust σ 0 K/W" not in page
    assert re.search(r"robust σ [\d.]+ K/W \(1\.0 % — the floor, 1 % of the median\)", page)
    assert "3 duplicates (the same content as another input, counted once)" in page
    assert "Duplicate inputs" in page and page.count(">copy_0<") >= 4


def test_the_runner_flags_duplicates_in_results_csv(client, tmp_path):
    paths = _copies(tmp_path / "in", 2)
    run = run_batch(paths, tmp_path / "out", client=client, options=Options(diagnose=False))
    assert [r["duplicate_of"] for r in run.rows] == ["", "copy_0"]
    rows = _csv_rows(tmp_path / "out" / "results.csv")
    assert list(rows[0])[-1] == "duplicate_of" and rows[1]["duplicate_of"] == "copy_0"


def test_a_curve_files_content_is_its_bytes_not_its_name(tmp_path):
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    for p in (a, b):
        p.write_text("t_s,zth_k_per_w\n1e-3,0.1\n1e-2,0.2\n")
    assert Source.read(a, "a").sha256 == Source.read(b, "b").sha256
