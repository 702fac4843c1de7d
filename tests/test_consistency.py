"""The consistency of a device effect with the cooling dynamics: a power that sags with
temperature is not a temperature coefficient, a real R(T) keeps its name."""

from __future__ import annotations

import numpy as np
import pytest

from spicethermal.analysis.diagnose import diagnose
from spicethermal.analysis.scenarios import ACTUATOR_R, ACTUATOR_TAU, scenario_bundle
from spicethermal.core.ladder import Foster
from spicethermal.io.bundle import Bundle, CoolingTable

T = 10.0 ** (np.arange(-50, 21) / 10)  # 10 µs ... 100 s


def _sagging_heater(gamma_per_k: float, seed: int = 0, noise_k: float = 0.02) -> Bundle:
    """Two cooling curves of a linear ladder whose heater dissipates ``P (1 − γ θj)`` in the
    steady state (the nominal ``P`` recorded): each curve is the linear Zth shape scaled by
    the power actually dissipated, ``θj = P Rth / (1 + γ P Rth)``."""
    lad = Foster.from_tau(ACTUATOR_R, ACTUATOR_TAU)
    rng = np.random.default_rng(seed)
    curves = []
    for p in (0.12, 0.30):
        actual = p / (1 + gamma_per_k * p * lad.rth)
        tj = 25.0 + actual * lad.cooling(T) + rng.normal(0.0, noise_k, T.size)
        curves.append(CoolingTable(T, p, tj_c=tj, tref_steady_c=25.0,
                                   tj_steady_c=25.0 + actual * lad.rth))
    return Bundle(ambient_c=25.0, cooling=curves, source="sagging heater")


def test_amplitude_only_physics_is_not_named_temperature_coefficient():
    d = diagnose(_sagging_heater(4e-3))
    assert d.effects == [] and d.verdict_effect is None
    assert "scaled per curve" in d.verdict_reason and "not in the catalogue" in d.verdict_reason
    # it is the temperature coefficient that the rule refused, on the cooling dynamics
    assert d.candidates[0].effect.name == "temperature-coefficient"
    assert d.candidates[0].improvement > 3


@pytest.mark.parametrize("seed", [0, 1])
def test_a_real_temperature_coefficient_keeps_its_name(seed):
    d = diagnose(scenario_bundle("temperature-coefficient", seed=seed))
    assert d.effects[:1] == ["temperature-coefficient"]
