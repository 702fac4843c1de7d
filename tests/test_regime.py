"""The change of regime that passes for a temperature coefficient: the rival law against closed
forms, and the diagnosis of a convection switch (independent generator) against a real
coefficient's."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from spicethermal.analysis.regime import Switch
from spicethermal.core.ladder import Cauer, Foster
from spicethermal.effects.temperature_coefficient import law, law_slope
from spicethermal.fit.tcforward import local_cooling_rise, local_steady_nodes, tc_cooling

#: full diagnoses: the slow tier (`make test` runs it, `make check` does not)
pytestmark = pytest.mark.slow


def test_the_step_law_and_its_slope_are_the_logistic_step():
    s = Switch.of(0.3, 40.0, 2.0, 0, 0, 25.0)
    assert law(s, 40.0) == pytest.approx(0.85, rel=1e-15)
    assert law(s, -1e4) == pytest.approx(1.0) and law(s, 1e4) == pytest.approx(0.7)
    # d/dT (1 − d σ(z)) = −d σ (1 − σ) / w
    assert law_slope(s, 40.0) == pytest.approx(-0.3 * 0.25 / 2.0, rel=1e-15)
    t = np.linspace(30.0, 50.0, 41)
    numeric = np.gradient(law(s, t), t)
    assert np.max(np.abs(numeric[1:-1] - law_slope(s, t)[1:-1])) < 2e-3


def test_one_layer_under_the_step_settles_where_its_implicit_equation_says():
    """One layer of R0 = 10 K/W at 2 W: Δ = P R0 (1 − d σ((T_ref + Δ/2 − Ts)/w))."""
    s = Switch.of(0.4, 35.0, 1.5, 0, 0, 25.0)
    delta = float(local_steady_nodes(Cauer([10.0], [1.0]), s, 25.0, 2.0)[0])
    sig = 1 / (1 + math.exp(-(25.0 + delta / 2 - 35.0) / 1.5))
    assert delta == pytest.approx(20.0 * (1 - 0.4 * sig), rel=1e-12)


def test_a_step_of_nothing_cools_as_the_linear_ladder():
    f = Foster.from_tau([1.0, 2.0], [1e-3, 1.0])
    t = [1e-4, 0.01, 1.0, 5.0]
    flat = Switch.of(0.0, 40.0, 2.0, 0, 5, 25.0)
    assert np.array_equal(tc_cooling(f, flat, 25.0, 3.0, t), 3.0 * f.cooling(t))
    # a step far above every temperature reached changes nothing either (integrated)
    far = Switch.of(0.5, 500.0, 1.0, 0, 5, 25.0)
    assert np.allclose(local_cooling_rise(f, far, 25.0, 3.0, t), 3.0 * f.cooling(t), atol=1e-4)


@pytest.mark.parametrize(("n", "seed", "name", "named", "after"), [
    # an outer convection that switches at 39.6 °C on an actuator: taken for a coefficient of
    # its outer layers before (100 % of the misfit, the PWM readings left at 3.6× their noise)
    (12, 67, "011 uncatalogued/convection-switch at 39.6 degC", [], ""),
    # taken for a coefficient, then a TSP's bow mopped up what its smooth law left: the step
    # alone fits as well as the two
    (24, 5, "023 uncatalogued/convection-switch at 40.9 degC", [], "as well as"),
    # taken for a junction coefficient, then a latent heat: the step needs the ladder refitted
    # (the junction coefficient's ladder scales every layer with the junction's temperature)
    (36, 67, "035 uncatalogued/convection-switch at 31 degC", [], "better than"),
    # a real coefficient of the inner layers, whose form leaves the PWM readings at 5.9×
    # their noise: the step fits it far worse, and it keeps its name
    (33, 67, "032 temperature-coefficient/inner/0.012/K", ["temperature-coefficient"], ""),
])
def test_a_convection_switch_is_no_coefficient_and_a_coefficient_is(n, seed, name, named,
                                                                     after):
    """Draws of ``bench/bench_validation_random.py 40 --seed S`` (independent generator)."""
    from conftest import bench_script

    from spicethermal.analysis.diagnose import diagnose

    c = bench_script("bench_validation_random").draw(n, seed)[n - 1]
    assert c.name == name
    d = diagnose(c.record().bundle)
    assert d.effects == named, d.verdict_reason
    assert ("a change of regime" in d.verdict_reason) == (not named), d.verdict_reason
    if not named:
        assert d.candidates[0].effect.name == "temperature-coefficient"  # the one it passed for
        assert "not in the catalogue" in d.verdict_reason
    # the effects added after the coefficient are no better than the step alone
    assert bool(re.search(rf"{after} it does with [a-z-]+ added", d.verdict_reason)) == \
        bool(after), d.verdict_reason
