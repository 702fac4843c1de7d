"""An effect registered from outside the package, with only its own module and the entry
point its ``pyproject.toml`` declares (``tests/plugins/capacity_drop``): the diagnosis names it
on data that has it, ``fit --effect`` fits it, ``export`` writes it, and nothing in spicethermal
knows it."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest
from scenarios import actuator, scenario_bundle

from spicethermal.effects import ENTRY_POINT_GROUP, Effect, registry
from spicethermal.engines.network import NetworkBatch

PLUGIN = Path(__file__).resolve().parent / "plugins" / "capacity_drop"
pytestmark = pytest.mark.slow


@pytest.fixture
def installed(tmp_path, monkeypatch):
    """The plugin as pip would install it: its module on the path and a ``.dist-info`` with
    the entry points its ``pyproject.toml`` declares (in this process and for commands)."""
    project = tomllib.loads((PLUGIN / "pyproject.toml").read_text())["project"]
    info = tmp_path / "site" / f"spicethermal_capacity_drop-{project['version']}.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {project['name']}\n"
                                   f"Version: {project['version']}\n")
    points = project["entry-points"][ENTRY_POINT_GROUP]
    (info / "entry_points.txt").write_text(
        f"[{ENTRY_POINT_GROUP}]\n" + "".join(f"{k} = {v}\n" for k, v in points.items()))
    paths = [str(tmp_path / "site"), str(PLUGIN)]
    for p in paths:
        monkeypatch.syspath_prepend(p)
    monkeypatch.setattr(registry, "_LOADED", False)
    monkeypatch.setattr(registry, "_REGISTRY", {})
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(paths)}
    return env


def _bundle(tmp_path: Path) -> Path:
    """The actuator with its cavity node losing 60 % of its capacity above a temperature that
    only the hotter cooling curve crosses."""
    probe = Effect.create("capacity-drop", fraction=0.6, t_d_c=40.0, width_k=0.5, node=2)
    top = NetworkBatch.of(actuator()).steady(0.3, 25.0)[0, 2] + 25.0
    effect = probe.with_params(t_d_c=float(25.0 + 0.6 * (top - 25.0)))
    return scenario_bundle("clean", seed=3, effect=effect).write(tmp_path / "bundle")


def _run(env: dict, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "spicethermal.cli.main", *args], env=env,
                          capture_output=True, text=True, timeout=600)


def test_a_plugin_is_named_fitted_and_exported_with_nothing_else_changed(installed, tmp_path):
    assert "capacity-drop" in registry.known_names()
    bundle = _bundle(tmp_path)
    out = _run(installed, "diagnose", str(bundle), "--json")
    assert out.returncode == 0, out.stderr
    verdict = json.loads(out.stdout)["verdict"]
    assert verdict["effects"][:1] == ["capacity-drop"], verdict
    model = tmp_path / "m.json"
    out = _run(installed, "fit", str(bundle), "--effect", "capacity-drop", "-o", str(model))
    assert out.returncode == 0, out.stderr
    fitted = json.loads(model.read_text())["effects"][0]
    assert fitted["name"] == "capacity-drop"
    assert fitted["params"]["fraction"] == pytest.approx(0.6, rel=0.1)
    lib = tmp_path / "m.lib"
    out = _run(installed, "export", str(model), "--topology", "cauer", "-o", str(lib))
    assert out.returncode == 0, out.stderr
    text = lib.read_text()
    assert "capacity-drop" in text and "LOG(1+EXP(" in text
    assert np.isfinite(fitted["params"]["t_d_c"])
