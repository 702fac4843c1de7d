"""Progress on stderr: shown on a terminal, off with -q and off when stderr is not a terminal."""

from __future__ import annotations

import io
import shutil
import sys
from pathlib import Path

import pytest
from conftest import DATA

from spicethermal.cli import main as cli
from spicethermal.core.ladder import Foster
from spicethermal.core.progress import bar, enabled, task
from spicethermal.demo import Steps
from spicethermal.effects import Effect
from spicethermal.model import ThermalModel


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_bar_on_a_terminal_and_off_otherwise(monkeypatch):
    term = _Terminal()
    monkeypatch.setattr(sys, "stderr", term)
    assert enabled() and not enabled(quiet=True)
    assert list(bar(range(4), desc="points")) == [0, 1, 2, 3]
    assert "points" in term.getvalue() and "/4 " in term.getvalue()
    quiet = _Terminal()
    monkeypatch.setattr(sys, "stderr", quiet)
    assert list(bar(range(4), desc="points", quiet=True)) == [0, 1, 2, 3]
    assert quiet.getvalue() == ""
    piped = io.StringIO()  # not a terminal: nothing, whatever -q says
    monkeypatch.setattr(sys, "stderr", piped)
    assert not enabled() and list(bar(iter(range(2)), total=2)) == [0, 1]
    assert piped.getvalue() == ""


# ------------------------------------------------------------------------ every long command
def _stderr(monkeypatch, argv: list[str]) -> str:
    """What ``spicethermal argv`` writes on a stderr that is a terminal."""
    term = _Terminal()
    monkeypatch.setattr(sys, "stderr", term)
    assert cli.main(argv) == 0
    return term.getvalue()


def _shown_unless_quiet(monkeypatch, argv: list[str], marker: str) -> None:
    assert marker in _stderr(monkeypatch, argv)
    assert marker not in _stderr(monkeypatch, [*argv, "-q"])


def _tc_model(path: Path) -> str:
    effect = Effect.create("temperature-coefficient", alpha_per_k=2e-3, t0_c=25.0)
    return str(ThermalModel(Foster.from_tau([30.0, 70.0], [0.01, 1.0]), (effect,)).save(path))


@pytest.mark.parametrize("command", ["spectrum", "structure"])
def test_bootstrap_progress(monkeypatch, command):
    argv = [command, str(DATA / "sample_bundle"), "--bootstrap", "2", "--iterations", "100"]
    _shown_unless_quiet(monkeypatch, argv, "bootstrap resamples")


def test_bench_procedure_progress(monkeypatch, tmp_path):
    common = ["--port", "sim://actuator?seed=1", "-o", str(tmp_path / "b")]
    for action, options in (("calibrate", ["--setpoint", "25,35"]), ("rth", []),
                            ("cooling", ["--cooling-power", "0.094", "--t-last", "1"]),
                            ("pwm", ["--freq", "25k", "--duty", "0.5"])):
        _shown_unless_quiet(monkeypatch, ["bench", action, *common, *options],
                            "% ")  # the bar's percentage


@pytest.mark.ngspice
@pytest.mark.skipif(shutil.which("ngspice") is None, reason="ngspice not installed")
def test_predict_with_device_effects_progress(monkeypatch, tmp_path):
    (tmp_path / "p.csv").write_text("t_s,power_w\n0,0\n1e-3,0.5\n0.5,0.5\n")
    argv = ["predict", _tc_model(tmp_path / "m.json"), "--profile", str(tmp_path / "p.csv"),
            "-o", str(tmp_path / "tj.csv")]
    _shown_unless_quiet(monkeypatch, argv, "ngspice transient")


@pytest.mark.ngspice
@pytest.mark.skipif(shutil.which("ngspice") is None, reason="ngspice not installed")
def test_drive_verify_progress(monkeypatch, tmp_path):
    path = ThermalModel(Foster.from_tau([30.0, 70.0], [0.01, 1.0])).save(tmp_path / "m.json")
    argv = ["drive", str(path), "--t-max", "70", "--target", "55", "--power", "1", "--verify"]
    _shown_unless_quiet(monkeypatch, argv, "ngspice drive check")


def test_demo_stages_progress(monkeypatch):
    for quiet, terminal, shown in ((False, True, True), (True, True, False),
                                   (False, False, False)):
        err = _Terminal() if terminal else io.StringIO()
        monkeypatch.setattr(sys, "stderr", err)
        steps = Steps(total=2, quiet=quiet)
        assert steps.run("adding", lambda: 1 + 1) == 2
        assert ("[1/2] adding ..." in err.getvalue()) is shown
        assert list(steps.timings) == ["adding"]


def test_task_shows_its_name_while_it_runs(monkeypatch):
    for quiet, terminal, shown in ((False, True, True), (True, True, False),
                                   (False, False, False)):
        err = _Terminal() if terminal else io.StringIO()
        monkeypatch.setattr(sys, "stderr", err)
        with task("ngspice transient", quiet=quiet):
            during = err.getvalue()
        assert ("ngspice transient" in during) is shown
