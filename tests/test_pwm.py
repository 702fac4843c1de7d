"""Analytic PWM periodic steady state against closed forms and brute-force time stepping."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import expm

from spicethermal.core.errors import DataFormatError
from spicethermal.core.ladder import Foster
from spicethermal.engines import pwm


def brute_force(ladder, power_w, freq_hz, duty, window_s=0.0, tol=1e-13):
    """Step the Cauer state space period by period with exact matrix exponentials."""
    cauer = ladder.to_cauer()
    cv, g = cauer.state_matrices()
    a = -g / cv[:, None]
    b = np.zeros(cauer.order)
    b[0] = power_w / cv[0]
    period = 1 / freq_hz
    on, off = duty * period, (1 - duty) * period
    e_on, e_off = expm(a * on), expm(a * off)
    x_forced = np.linalg.solve(-a, b)  # equilibrium with power on
    x = np.zeros(cauer.order)
    for _ in range(10_000_000):
        peak = x_forced + e_on @ (x - x_forced)
        new = e_off @ peak
        if np.max(np.abs(new - x)) < tol:
            break
        x = new
    peak = x_forced + e_on @ (x - x_forced)
    reading = expm(a * window_s) @ peak
    return peak[0], x[0], reading[0]


@pytest.mark.parametrize("freq_hz, duty", [(1e4, 0.2), (2e3, 0.5), (200.0, 0.8)])
def test_steady_state_equals_brute_force(freq_hz, duty):
    f = Foster.from_tau([6.0, 20.0, 50.0], [1e-4, 5e-3, 0.05])
    s = pwm.steady_state(f, 0.094, freq_hz, duty, window_s=1e-4)
    peak, valley, reading = brute_force(f, 0.094, freq_hz, duty, 1e-4)
    assert s.peak_k == pytest.approx(peak, rel=1e-6)
    assert s.valley_k == pytest.approx(valley, rel=1e-6)
    assert s.reading_k == pytest.approx(reading, rel=1e-6)
    assert s.mean_k == pytest.approx(0.094 * duty * f.rth, rel=1e-14)


def test_single_stage_closed_form():
    f = Foster.from_tau([10.0], [1e-3])
    T, D = 1e-3, 0.3
    s = pwm.steady_state(f, 2.0, 1 / T, D, window_s=2e-4)
    peak = 20 * (1 - np.exp(-D * T / 1e-3)) / (1 - np.exp(-T / 1e-3))
    assert s.peak_k == pytest.approx(peak, rel=1e-14)
    assert s.valley_k == pytest.approx(peak * np.exp(-(1 - D) * T / 1e-3), rel=1e-14)
    assert s.reading_k == pytest.approx(peak * np.exp(-0.2), rel=1e-14)
    assert s.as_json() == {"peak_k": s.peak_k, "mean_k": s.mean_k, "valley_k": s.valley_k,
                           "reading_k": s.reading_k}


def test_phase_profile_is_continuous_and_averages_to_mean(actuator):
    freq, duty = 1e3, 0.4
    ph = np.linspace(0, 1 / freq, 20001)
    th = pwm.at_phase(actuator, 0.1, freq, duty, ph)
    s = pwm.steady_state(actuator, 0.1, freq, duty)
    assert th[0] == pytest.approx(s.valley_k, rel=1e-12)
    assert th[-1] == pytest.approx(s.valley_k, rel=1e-12)
    assert th.max() == pytest.approx(s.peak_k, rel=1e-9)
    assert np.trapezoid(th, ph) * freq == pytest.approx(s.mean_k, rel=1e-6)


def test_envelope_converges_to_steady_state(actuator):
    s = pwm.steady_state(actuator, 0.1, 500.0, 0.5)
    pk, vl = pwm.envelope(actuator, 0.1, 500.0, 0.5, [1, 10, 10**9])
    assert pk[-1] == pytest.approx(s.peak_k, rel=1e-12)
    assert vl[-1] == pytest.approx(s.valley_k, rel=1e-12)
    assert pk[0] == pytest.approx(0.1 * actuator.zth(0.5 / 500.0), rel=1e-12)
    assert np.all(np.diff(pk) > 0)


def test_duty_cycle_family(actuator):
    t = np.logspace(-6, 3, 40)
    for duty in (0.1, 0.5, 0.9):
        exact = pwm.r_duty_exact(actuator, t, duty)
        eq3 = pwm.r_duty_eq3(actuator, t, duty)
        assert np.all(exact <= eq3 + 1e-12)  # eq. 3 is conservative
        assert exact[-1] == pytest.approx(1.0, abs=1e-6)
        # exact form = periodic peak for pulse width t at duty D
        s = pwm.steady_state(actuator, 1.0, duty / t[20], duty)
        assert exact[20] == pytest.approx(s.peak_k / actuator.rth, rel=1e-12)
    np.testing.assert_allclose(pwm.r_duty_exact(actuator, t, 0.0), actuator.r_norm(t))


@pytest.mark.parametrize("kwargs, name", [
    ({"freq_hz": 0.0}, "freq_hz"), ({"duty": 1.5}, "duty"), ({"power_w": -1.0}, "power_w"),
    ({"window_s": float("nan")}, "window_s"),
])
def test_bad_drive_names_parameter(actuator, kwargs, name):
    args = {"power_w": 1.0, "freq_hz": 1e3, "duty": 0.5, "window_s": 0.0} | kwargs
    with pytest.raises(DataFormatError, match=name):
        pwm.steady_state(actuator, **args)
