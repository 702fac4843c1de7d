"""``spicethermal batch`` on a scheduler and workers started here as processes (the ``dask
scheduler`` and ``dask worker`` commands), and a batch interrupted (SIGINT) then resumed."""

from __future__ import annotations

import csv
import json
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from spicethermal.batch.population import write_population
from spicethermal.cli.main import main

pytest.importorskip("distributed")
DASK = Path(sys.executable).with_name("dask")
pytestmark = pytest.mark.slow


def _wait_for(predicate, timeout_s: float, what: str) -> None:
    end = time.monotonic() + timeout_s
    while not predicate():
        if time.monotonic() > end:
            raise AssertionError(f"timed out waiting for {what}")
        time.sleep(0.2)


def _stop(proc: subprocess.Popen) -> None:
    if proc.poll() is None:
        proc.send_signal(signal.SIGINT)
        try:
            proc.wait(timeout=20)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


@pytest.fixture
def scheduler(tmp_path):
    """A scheduler and one single-threaded worker on this machine; yields the address."""
    if not DASK.exists():
        pytest.skip("the dask command is not installed beside this Python")
    info = tmp_path / "scheduler.json"
    procs = [subprocess.Popen([str(DASK), "scheduler", "--host", "127.0.0.1", "--port", "0",
                               "--dashboard-address", ":0", "--scheduler-file", str(info)],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    try:
        _wait_for(info.exists, 60, "the scheduler file")
        procs.append(subprocess.Popen(
            [str(DASK), "worker", "--scheduler-file", str(info), "--nworkers", "1",
             "--nthreads", "1", "--no-dashboard"],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        address = json.loads(info.read_text())["address"]
        from distributed import Client

        with Client(address, timeout="30s") as client:
            client.wait_for_workers(1, timeout=60)
        yield address
    finally:
        for proc in reversed(procs):
            _stop(proc)


def test_batch_runs_on_a_given_scheduler(scheduler, tmp_path, capsys):
    devices = write_population(tmp_path / "pop", 5, seed=2, defects=0)
    out = tmp_path / "out"
    assert main(["batch", str(tmp_path / "pop"), "-o", str(out), "--scheduler", scheduler,
                 "--no-diagnose", "-q"]) == 0
    with open(out / "results.csv", newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert [r["name"] for r in rows] == [d.name for d in devices]
    assert all(r["error"] == "" and float(r["rth_k_per_w"]) > 0 for r in rows)
    assert (out / "index.html").exists()


def test_unreachable_scheduler_is_one_line(tmp_path, capsys):
    write_population(tmp_path / "pop", 1)
    # a port nothing listens on: the connection is refused until the 10 s timeout
    assert main(["batch", str(tmp_path / "pop"), "-o", str(tmp_path / "out"),
                 "--scheduler", "tcp://127.0.0.1:9", "-q"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("spicethermal batch: error: --scheduler tcp://127.0.0.1:9: cannot "
                          "connect") and "\n" not in err


def test_an_interrupted_batch_resumes_where_it_stopped(tmp_path):
    write_population(tmp_path / "pop", 8, seed=6, defects=1)
    out = tmp_path / "out"
    argv = [sys.executable, "-m", "spicethermal.cli.main", "batch", str(tmp_path / "pop"), "-o",
            str(out), "--workers", "1", "--effect", "electrical-transient", "-q"]
    # the interrupt must reach the batch: a test run started in the background of a
    # non-interactive shell ignores SIGINT, and a child inherits that (Python then installs no
    # KeyboardInterrupt handler)
    proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    try:
        _wait_for(lambda: len(list(out.glob("devices/*/result.json"))) >= 2 or
                  proc.poll() is not None, 120, "two finished devices")
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 2, err
    assert err.strip().splitlines()[-1] == "spicethermal batch: error: interrupted"
    done = len(list(out.glob("devices/*/result.json")))
    assert 2 <= done < 8
    assert not (out / "results.csv").exists()
    resumed = subprocess.run(argv[:-1] + ["--resume"], capture_output=True, text=True,
                             timeout=300)
    assert resumed.returncode == 0, resumed.stderr
    assert f"8 inputs ({8 - done} computed, {done} reused)" in resumed.stdout
    with open(out / "results.csv", newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert len(rows) == 8 and all(r["error"] == "" for r in rows)
