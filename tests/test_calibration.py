"""TSP calibration against exact lines and quadratics, the linearity test, the inverse."""

from __future__ import annotations

import numpy as np
import pytest

from spicethermal.core.errors import DataFormatError
from spicethermal.identify.calibration import Calibration

T = np.array([20.0, 40.0, 60.0, 80.0, 100.0, 120.0])


def test_exact_line() -> None:
    v = 0.712 - 2.1e-3 * T
    cal = Calibration.fit(T, v)
    assert cal.degree == 1
    np.testing.assert_allclose(cal.coefficients, [0.712, -2.1e-3], rtol=1e-12)
    assert cal.k_factor_mv_per_k == pytest.approx(-2.1, rel=1e-12)
    assert cal.rms_mv < 1e-9 and cal.rms_k < 1e-9
    np.testing.assert_allclose(cal.temperature(cal.voltage([-10.0, 55.5, 200.0])),
                               [-10.0, 55.5, 200.0], rtol=1e-12)  # a line extrapolates
    assert cal.linearity.linear_ok


def test_exact_quadratic() -> None:
    v = 0.70 - 2.0e-3 * T - 4.0e-6 * T**2
    cal = Calibration.fit(T, v, degree=2)
    np.testing.assert_allclose(cal.coefficients, [0.70, -2.0e-3, -4.0e-6], rtol=1e-9)
    assert cal.k_factor_at(50.0) == pytest.approx(-2.0 - 2 * 4e-3 * 50.0, rel=1e-9)
    assert cal.k_factor_mv_per_k == pytest.approx(cal.k_factor_at(70.0), rel=1e-12)
    t = np.linspace(0.0, 140.0, 57)
    np.testing.assert_allclose(cal.temperature(cal.voltage(t)), t, atol=1e-9)
    # the line misses it; the test says so and "auto" picks the quadratic
    line = Calibration.fit(T, v)
    assert not line.linearity.linear_ok
    assert line.linearity.curvature_k > 1.0
    # curvature of the true quadratic relative to its chord over 20..120 degC: a(ΔT)²/8 / slope
    assert Calibration.fit(T, v, degree="auto").degree == 2


def test_residuals_in_mv_and_k() -> None:
    v = 0.70 - 2.0e-3 * T
    v_noisy = v.copy()
    v_noisy[2] += 1e-3  # one point 1 mV high
    cal = Calibration.fit(T, v_noisy)
    expected_mv = (v_noisy - cal.voltage(T)) * 1e3
    np.testing.assert_allclose(cal.residuals_mv, expected_mv, atol=1e-12)
    # a voltage too high reads too cold on a negative slope: residual_k = residual_v / slope
    np.testing.assert_allclose(cal.residuals_k, expected_mv * 1e-3 / cal.coefficients[1])
    assert cal.rms_mv == pytest.approx(np.sqrt(np.mean(expected_mv**2)))


def test_linearity_noise_versus_curvature() -> None:
    rng = np.random.default_rng(7)
    t = np.linspace(20, 120, 12)
    noise = rng.normal(0, 2e-4, t.size)  # 0.2 mV ≈ 0.1 K
    tiny_curve = 0.70 - 2e-3 * t - 1e-8 * t**2 + noise
    assert Calibration.fit(t, tiny_curve).linearity.linear_ok
    strong_curve = 0.70 - 2e-3 * t - 2e-6 * t**2 + noise
    test = Calibration.fit(t, strong_curve).linearity
    assert not test.linear_ok and test.p_value < 0.05 and test.curvature_k > test.tolerance_k
    assert "quadratic" in str(test)


def test_quadratic_inverse_errors_out_of_range() -> None:
    v = 0.70 - 2.0e-3 * T + 5.0e-6 * T**2  # turns at 200 degC
    cal = Calibration.fit(T, v, degree=2)
    with pytest.raises(DataFormatError, match="beyond the turning point"):
        cal.temperature(0.40)
    with pytest.raises(DataFormatError, match="outside the calibrated range"):
        cal.temperature(cal.voltage(170.0))
    assert float(cal.temperature(cal.voltage(170.0), margin_k=60)) == pytest.approx(170.0)


def test_pyrth_calibration_points() -> None:
    temp = [23.4, 37.625, 51.85, 66.075, 80.3]
    volt = [0.55843, 0.52536, 0.49232, 0.45927, 0.42621]
    cal = Calibration.fit(temp, volt)
    assert cal.k_factor_mv_per_k == pytest.approx(-2.32, abs=0.01)
    assert cal.rms_k < 0.01 and cal.linearity.linear_ok


@pytest.mark.parametrize(("temp", "volt", "degree", "words"), [
    ([25, 25, 25], [0.6, 0.6, 0.6], 1, "distinct temperatures"),
    ([25, 50], [0.6, 0.55], 2, "distinct temperatures"),
    ([25, 50], [0.6, np.nan], 1, "point 2, column v_tsp_v"),
    ([25, 50], [0.6], 1, "2 temperatures but 1 voltages"),
    ([25, 50, 75], [0.6, 0.5, 0.6], 2, "not monotonic"),
    ([25, 50], [0.6, 0.6], 1, "zero slope"),
    ([25, 50], [0.6, 0.5], 3, "degree = 3"),
])
def test_bad_calibration(temp, volt, degree, words) -> None:
    with pytest.raises(DataFormatError, match=words):
        Calibration.fit(temp, volt, degree=degree)


# ------------------------------------------------------------------ K-factor and polynomial
def test_k_factor_is_the_line_through_its_anchor() -> None:
    from spicethermal.identify.calibration import KFactor, anchored

    k = KFactor.from_mv_per_k(-2.5, v_ref_v=0.62, t_ref_c=20.0)
    t = np.array([-10.0, 20.0, 75.5])
    assert np.allclose(k.voltage(t), 0.62 - 2.5e-3 * (t - 20.0), rtol=0, atol=1e-15)
    assert np.allclose(k.temperature(k.voltage(t)), t, rtol=0, atol=1e-12)
    assert k.k_factor_mv_per_k == pytest.approx(-2.5) and k.kind == "k-factor"
    # a table re-anchored elsewhere keeps its slope and moves its level
    cal = Calibration.fit([20, 40, 60, 80], [0.60, 0.56, 0.52, 0.48])
    a = anchored(cal, 0.65, 25.0)
    assert a.k_v_per_k == pytest.approx(-2e-3, rel=1e-12)
    assert float(a.temperature(0.65 - 0.04)) == pytest.approx(45.0, abs=1e-9)


@pytest.mark.parametrize(("kwargs", "words"), [
    ({"k_v_per_k": 0.0, "v_ref_v": 0.6, "t_ref_c": 25.0}, "zero"),
    ({"k_v_per_k": "x", "v_ref_v": 0.6, "t_ref_c": 25.0}, "k_v_per_k: 'x' is not a number"),
    ({"k_v_per_k": -2e-3, "v_ref_v": float("nan"), "t_ref_c": 25.0}, "v_ref_v"),
    ({"k_v_per_k": -2e-3, "v_ref_v": 0.6, "t_ref_c": -300.0}, "absolute zero"),
])
def test_bad_k_factor_names_the_parameter(kwargs, words) -> None:
    from spicethermal.identify.calibration import KFactor

    with pytest.raises(DataFormatError, match=words):
        KFactor(**kwargs)


def test_a_bundle_holds_what_was_read_and_identify_converts_it(tmp_path) -> None:
    """io holds the calibration as read (points, the K-factor's numbers); identify builds the
    converter of any kind, and a converter in a bundle is written and read back as its law."""
    from spicethermal.identify.calibration import KFactor
    from spicethermal.identify.readings import converter
    from spicethermal.io.bundle import Bundle, CalibrationTable, KFactorLaw

    law = KFactorLaw(-2e-3, 0.6, 25.0, "x")
    k = converter(law)
    assert isinstance(k, KFactor) and k == law and hash(k) == hash(law) and str(k) == str(law)
    assert converter(k) is k and not hasattr(law, "temperature")
    back = Bundle.read(Bundle(calibration=k).write(tmp_path / "b")).calibration
    assert type(back) is KFactorLaw and back == k
    table = CalibrationTable([25.0, 50.0, 75.0], [0.6, 0.55, 0.5], coefficients=(0.65, -2e-3, 0))
    assert table.coefficients == (0.65, -2e-3)  # a zero quadratic term is dropped on reading
    poly = converter(table, degree=2)  # given: the degree asked for does not refit it
    assert poly.kind == "polynomial" and poly.coefficients == (0.65, -2e-3)
    assert converter(CalibrationTable([25.0, 75.0], [0.6, 0.5]), 1).kind == "table"
    with pytest.raises(DataFormatError, match="coefficients_v: the polynomial is not monotonic"):
        CalibrationTable([0.0, 100.0], [0.6, 0.5], coefficients=(0.6, -2e-3, 2e-5))


def test_given_polynomial_keeps_its_residuals() -> None:
    """A line fitted elsewhere (a T3Ster .tco header) against the points: residuals are the
    points minus that line, not a refit."""
    t = np.array([25.0, 40.0, 55.0, 70.0])
    v = 2.65 - 1.5e-3 * t + np.array([0.5, -0.2, 0.1, -0.4]) * 1e-3
    cal = Calibration.from_coefficients([2.65, -1.5e-3], t, v)
    assert cal.kind == "polynomial" and "given" in str(cal)
    assert np.allclose(cal.residuals_mv, [0.5, -0.2, 0.1, -0.4], atol=1e-9)
    with pytest.raises(DataFormatError, match="not monotonic"):
        Calibration.from_coefficients([0.6, -2e-3, 1e-4], [0, 20, 40], [0.6, 0.6, 0.6])
    with pytest.raises(DataFormatError, match="2 or 3"):
        Calibration.from_coefficients([0.6], [0, 20], [0.6, 0.56])
