"""Shared fixtures: reference ladders and small helpers for exact comparisons."""

from __future__ import annotations

import importlib.metadata
import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest

from spicethermal.core.ladder import Foster

ROOT = Path(__file__).resolve().parent.parent
#: Data shipped in the repository (paper tables, real MOSFET transients, with their sources).
DATA = ROOT / "spicethermal" / "data"
NETLISTS = ROOT / "netlists"

#: The paper-like actuator ladder used across tests: Rth = 146 K/W, taus from 100 µs to 30 s.
ACTUATOR_R = (6.0, 20.0, 50.0, 70.0)
ACTUATOR_TAU = (1e-4, 5e-3, 0.4, 30.0)


@pytest.fixture
def actuator() -> Foster:
    return Foster.from_tau(ACTUATOR_R, ACTUATOR_TAU)


@pytest.fixture
def register_plugin(monkeypatch):
    """``register_plugin(cls)``: the plugin class ``cls`` offered through the
    ``spicethermal.effects`` entry-point group beside the installed ones, as an installed
    third-party package would, for the test's duration (the registry reloads its entry points;
    it is restored afterwards)."""
    from spicethermal.effects import ENTRY_POINT_GROUP, registry

    installed = list(importlib.metadata.entry_points(group=ENTRY_POINT_GROUP))

    def register(cls) -> None:
        class EntryPoint:
            def load(self):
                return cls

        monkeypatch.setattr(registry, "_LOADED", False)
        monkeypatch.setattr(registry, "_REGISTRY", {})
        monkeypatch.setattr(importlib.metadata, "entry_points",
                            lambda group: [*installed, EntryPoint()]
                            if group == ENTRY_POINT_GROUP else [])

    return register


def ramp_response(ladder, t, rise_s: float) -> np.ndarray:
    """Exact rise per watt when power ramps linearly from 0 to 1 W over ``rise_s``, then stays."""
    f = ladder.to_foster() if ladder.topology == "cauer" else ladder
    r, tau = np.asarray(f.r), np.asarray(f.tau)
    t = np.asarray(t, dtype=float)[:, None]
    late = r * (1 - tau / rise_s * np.exp(-t / tau) * np.expm1(rise_s / tau))
    early = r * (t / rise_s - tau / rise_s * -np.expm1(-t / tau))
    return np.where(t >= rise_s, late, early).sum(axis=1)



def bench_script(name: str):
    """The benchmark script ``bench/<name>.py`` as a module, loaded once (the benchmarks'
    case generators are tested and reused here; bench/ is not a package)."""
    key = f"_spicethermal_bench_{name}"
    if key not in sys.modules:
        spec = importlib.util.spec_from_file_location(key, ROOT / "bench" / f"{name}.py")
        sys.modules[key] = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(sys.modules[key])
    return sys.modules[key]
