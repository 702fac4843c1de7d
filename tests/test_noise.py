"""Noise estimates that the structure under test cannot inflate."""

from __future__ import annotations

import numpy as np
import pytest

from spicethermal.analysis.noise import calibration_degree, curve_noise, resolution

T = np.geomspace(1e-4, 100.0, 120)


@pytest.mark.parametrize("sigma", [0.01, 0.05])
def test_a_smooth_misfit_does_not_count_as_noise(sigma):
    rng = np.random.default_rng(3)
    misfit = 0.5 * np.tanh(np.log10(T)) + 0.2 * np.log10(T) ** 2 / 10  # 30× the noise and more
    estimates = [curve_noise(T, sigma * rng.standard_normal(T.size) + misfit,
                             np.zeros(T.size)) for _ in range(20)]
    assert np.median(estimates) == pytest.approx(sigma, rel=0.15)


def test_a_transient_over_a_few_readings_does_not_count_as_noise():
    rng = np.random.default_rng(4)
    r = 0.02 * rng.standard_normal(T.size)
    r[:4] += [-3.0, -1.5, -0.7, -0.3]
    assert curve_noise(T, r, np.zeros(T.size)) == pytest.approx(0.02, rel=0.3)


def test_quantised_readings_scatter_by_at_least_their_step_over_root_12():
    readings = np.round(np.linspace(30.0, 40.0, 200) / 0.06) * 0.06
    assert resolution(readings) == pytest.approx(0.06)
    assert curve_noise(T[:120], np.zeros(120), readings[:120]) == pytest.approx(
        0.06 / np.sqrt(12))


def test_the_calibration_noise_is_about_the_law_it_supports_not_about_a_line():
    rng = np.random.default_rng(5)
    t = np.linspace(20.0, 100.0, 9)
    bow = 1e-3 * (t - 60.0) ** 2
    degree, scatter, fall = calibration_degree(t, t + bow + 0.01 * rng.standard_normal(t.size))
    assert degree == 2 and scatter < 0.02 and fall > 100
    degree, _, fall = calibration_degree(t, t + 0.01 * rng.standard_normal(t.size))
    assert degree == 1 and fall == 0.0


def test_a_bow_the_noise_estimate_keeps_may_be_short_of_the_criterions_margin():
    """The F-test at p = 0.01 keeps the quadratic of 30 points whose bow lowers their χ² by
    less than the criterion's 10 beyond its ln n: a degree for the noise, no evidence that
    names an effect. The bow is the χ² fall from the line in the scatter, less ln n."""
    t = np.linspace(20.0, 100.0, 30)
    read = t + 2e-5 * (t - 60.0) ** 2 + 0.01 * np.random.default_rng(8).standard_normal(t.size)
    degree, scatter, fall = calibration_degree(t, read)
    assert degree == 2 and 0.0 < fall < 10.0
    x = (t - t.mean()) / np.ptp(t)
    rss = [np.sum((read - np.polyval(np.polyfit(x, read, d), x)) ** 2) for d in (1, 2)]
    assert fall == pytest.approx((rss[0] - rss[1]) / scatter ** 2 - np.log(t.size))


@pytest.mark.parametrize("degree", [1, 2, 3])
def test_a_law_without_scatter_gets_its_own_degree_whatever_the_rounding(degree):
    # with no scatter the residuals are rounding: their F ratio is noise of the last bits
    t = np.linspace(20, 100, 9)
    law = t + sum(c * (t - 60) ** k for k, c in ((2, 1e-3), (3, 1e-4)) if k <= degree)
    for shift in (0.0, 1e-13, 3e-13):  # the last bits of the readings, as BLAS may leave them
        assert calibration_degree(t, law * (1 + shift))[0] == degree
