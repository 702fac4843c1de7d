"""The diagnosis's statistics against closed forms."""

from __future__ import annotations

import math

import numpy as np
import pytest

from spicethermal.analysis.rules import correlated_gain

WHITE = np.where(np.arange(50) % 2 == 0, 1.0, -1.0)  # lag-one autocorrelation −1: ρ = 0


def test_a_white_residual_left_gives_the_plain_fall_of_chi2():
    assert correlated_gain(WHITE + 3.0, WHITE) == pytest.approx(50 * 9.0, rel=1e-12)


@pytest.mark.parametrize(("n", "level", "shift"), [(20, 2.0, 1.0), (200, 2.0, -0.5),
                                                    (8, 5.0, 3.0)])
def test_a_constant_residual_left_is_prewhitened_by_its_autocorrelation(n, level, shift):
    """A constant residual ``c`` left has ρ = (n − 1)/n (at most 0.99); both residuals are
    then prewhitened alike: the first reading by √(1 − ρ²), the others by 1 − ρ, and the
    fall divided by the innovations' variance (at least 1)."""
    rho = min((n - 1) / n, 0.99)
    weight = (1 - rho * rho) + (n - 1) * (1 - rho) ** 2
    var = max(weight * level ** 2 / n, 1.0)
    after = np.full(n, level)
    want = weight * ((level + shift) ** 2 - level ** 2) / var
    assert correlated_gain(after + shift, after) == pytest.approx(want, rel=1e-12)


def test_a_smooth_misfit_left_weighs_a_small_part_of_its_plain_fall():
    bow = 4.0 * np.sin(np.pi * np.linspace(0.0, 1.0, 50))
    plain = float(np.sum((bow + 3.0) ** 2 - bow ** 2))
    assert 0 < correlated_gain(bow + 3.0, bow) < 0.01 * plain
    assert math.isclose(correlated_gain(np.zeros(5), np.zeros(5)), 0.0)
