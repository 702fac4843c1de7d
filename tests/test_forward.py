"""The one forward model: every data set's prediction, each measurement effect's reading
against its closed form, and the effects composed without being named."""

from __future__ import annotations

import numpy as np
import pytest

from spicethermal.core.ladder import Foster
from spicethermal.effects import Effect
from spicethermal.engines.meter import metered
from spicethermal.engines.network import NetworkBatch
from spicethermal.engines.pwm import stage_peaks, steady_state
from spicethermal.fit.forward import (
    EXACT_TOL_K,
    MeasurementTerm,
    predict,
    predict_model,
    pwm_correction,
)
from spicethermal.fit.joint import Layout, Start, fit_starts
from spicethermal.fit.measurement import BundleData
from spicethermal.fit.search import settle
from spicethermal.io.bundle import Bundle, CalibrationTable, CoolingTable, PwmTable
from spicethermal.model import ThermalModel

LADDER = Foster.from_tau([6.0, 20.0, 50.0, 70.0], [1e-4, 5e-3, 0.4, 30.0])
T = np.geomspace(1e-5, 100.0, 31)
F = np.array([500.0, 5e3, 25e3, 500.0, 5e3, 25e3])
D = np.array([0.2, 0.2, 0.2, 0.8, 0.8, 0.8])


def _data(window_s: float = 1e-4, steady: bool = True) -> BundleData:
    cal = CalibrationTable(np.arange(20.0, 101.0, 10.0), 0.65 - 2e-3 * np.arange(-5.0, 76.0, 10))
    return BundleData.from_bundle(Bundle(
        ambient_c=25.0, calibration=cal,
        cooling=(CoolingTable(T, 0.12, tj_c=np.zeros(T.size),
                              tj_steady_c=0.0 if steady else None, tref_steady_c=25.0),
                 CoolingTable(T, 0.30, tj_c=np.zeros(T.size),
                              tj_steady_c=0.0 if steady else None, tref_steady_c=25.0)),
        pwm=PwmTable(F, D, np.zeros(F.size), power_w=0.1, sample_window_s=window_s)))


def test_the_linear_model_is_the_ladders_closed_forms():
    pred = predict_model(_data(), LADDER)
    assert pred["cooling_2"] == pytest.approx(25.0 + 0.3 * LADDER.cooling(T), rel=1e-9)
    assert pred["steady"] == pytest.approx(25.0 + np.array([0.12, 0.3]) * LADDER.rth)
    assert pred["pwm"] == pytest.approx(
        [25.0 + steady_state(LADDER, 0.1, f, d, 1e-4).reading_k for f, d in zip(F, D, strict=True)],
        rel=1e-9)
    assert pred["calibration"] == pytest.approx(np.arange(20.0, 101.0, 10.0))


def test_without_steady_readings_there_is_no_steady_data_set():
    assert "steady" not in predict_model(_data(steady=False), LADDER)


def test_an_electrical_transient_adds_its_closed_form_to_the_cooling_readings():
    base = predict_model(_data(), LADDER)
    e = Effect.create("electrical-transient", "power", k_per_w=-10.0, masked_s=1e-4)
    pred = predict_model(_data(), LADDER, [e])
    assert pred["cooling_2"] - base["cooling_2"] == pytest.approx(
        -10.0 * 0.3 * np.exp(-5 * T / 1e-4))
    assert pred["pwm"] == pytest.approx(base["pwm"]) and pred["steady"] == \
        pytest.approx(base["steady"])


@pytest.mark.parametrize("form", ["end", "average"])
def test_a_sample_window_reads_where_it_says(form):
    w = 3e-4
    pred = predict_model(_data(), LADDER, [Effect.create("sample-window", form, window_s=w)])
    r, tau = np.array(LADDER.r), np.array(LADDER.tau)
    peaks = 0.1 * stage_peaks(r, tau, 1 / F[:, None], D[:, None])
    if form == "end":
        exact = (peaks * np.exp(-w / tau)).sum(axis=1)
    else:  # Σ pᵢ τᵢ/w (1 − e^{−w/τᵢ})
        exact = (peaks * tau / w * -np.expm1(-w / tau)).sum(axis=1)
    assert pred["pwm"] == pytest.approx(25.0 + exact, abs=1e-6)


def test_a_tsp_bends_the_calibration_and_through_its_line_every_reading():
    q = 5e-4
    e = Effect.create("tsp-nonlinearity", quad_k_per_k2=q, t_cal_c=25.0)
    pred = predict_model(_data(), LADDER, [e])
    temps = np.arange(20.0, 101.0, 10.0)
    u = (temps - 25.0) ** 2
    a = np.column_stack([np.ones_like(temps), temps])
    bow = u - a @ np.linalg.lstsq(a, u, rcond=None)[0]
    slope = np.linalg.lstsq(a, u, rcond=None)[0][1]
    assert pred["calibration"] - temps == pytest.approx(q * bow / (1 + q * slope), abs=1e-9)
    held = predict_model(_data(), LADDER, [e.with_params(through_line=0.0)])
    base = predict_model(_data(), LADDER)
    assert held["cooling_1"] == pytest.approx(base["cooling_1"])
    assert not np.allclose(pred["cooling_1"], base["cooling_1"])


def test_rivals_read_as_they_say():
    base = predict_model(_data(), LADDER)
    g = predict_model(_data(), LADDER, [Effect.create("power-error", gamma_per_w=0.5)])
    assert g["cooling_2"] - 25.0 == pytest.approx((base["cooling_2"] - 25.0) / 1.15)
    d = predict_model(_data(), LADDER, [Effect.create("reference-drift", rate_k_per_s=0.01)])
    assert d["cooling_1"] - base["cooling_1"] == pytest.approx(0.01 * T)


def test_effects_compose_in_the_order_of_their_stage():
    e1 = Effect.create("electrical-transient", amplitude_k=-2.0, masked_s=1e-4)
    e2 = Effect.create("tsp-nonlinearity", quad_k_per_k2=5e-4, t_cal_c=25.0)
    one = predict_model(_data(), LADDER, [e1, e2])
    other = predict_model(_data(), LADDER, [e2, e1])
    assert one["cooling_1"] == pytest.approx(other["cooling_1"])
    tsp_only = predict_model(_data(), LADDER, [e2])
    # the transient is added to the reading: after the sensor's law
    assert one["cooling_1"] - tsp_only["cooling_1"] == pytest.approx(
        -2.0 * np.exp(-5 * T / 1e-4))


# -- the exact periodic state of a nonlinear model -----------------------------------------
SLOW_F = np.array([1.0, 5.0, 50.0, 1.0, 5.0, 50.0])
TC = Effect.create("temperature-coefficient", "local", alpha_per_k=5e-3)


def _slow_pwm(readings: np.ndarray | None = None, noise_k: float = 0.0) -> BundleData:
    """A curve and a PWM grid down to 1 Hz at 0.3 W, where the 0.4 s stage swings whole."""
    rng = np.random.default_rng(3)
    cooling = predict_model(BundleData.from_bundle(Bundle(ambient_c=25.0, cooling=(
        CoolingTable(T, 0.3, tj_c=np.zeros(T.size), tref_steady_c=25.0),))), LADDER, [TC])
    pwm = np.zeros(F.size) if readings is None else readings
    return BundleData.from_bundle(Bundle(
        ambient_c=25.0,
        cooling=(CoolingTable(T, 0.3, tj_c=cooling["cooling_1"] + rng.normal(0, noise_k, T.size),
                              tref_steady_c=25.0),),
        pwm=PwmTable(SLOW_F, D, pwm + rng.normal(0, noise_k, F.size), power_w=0.3,
                     sample_window_s=1e-4)))


def _exact(effects) -> np.ndarray:
    model = ThermalModel(LADDER, tuple(effects))
    return np.array([25.0 + model.pwm_reading(0.3, f, d, 1e-4) for f, d in zip(SLOW_F, D,
                                                                                strict=True)])


def test_the_correction_makes_a_nonlinear_models_pwm_readings_exact():
    data = _slow_pwm()
    closed = predict_model(data, LADDER, [TC])["pwm"]
    correction = pwm_correction(data, LADDER, [TC])
    held = data.with_pwm_correction(correction, [TC])
    exact = _exact([TC])
    assert np.max(np.abs(closed - exact)) > 0.2  # first order in the ripple: a quarter kelvin
    # to the shooting's tolerance
    assert predict_model(held, LADDER, [TC])["pwm"] == pytest.approx(exact, abs=EXACT_TOL_K)
    # a sample window of the declared length reads the corrected state too
    window = Effect.create("sample-window", "end", window_s=1e-4)
    assert predict_model(held, LADDER, [TC, window])["pwm"] == pytest.approx(exact,
                                                                             abs=EXACT_TOL_K)


def test_the_correction_is_held_for_the_models_that_keep_the_device_effects_it_was_for():
    data = _slow_pwm()
    correction = pwm_correction(data, LADDER, [TC])
    held = data.with_pwm_correction(correction, [TC])
    # a model with a further device effect keeps it (a candidate weighed against the model
    # it was computed at is weighed with it) ...
    band = Effect.create("phase-change", t_c=60.0, width_k=3.0, latent_j=1e-3)
    assert predict_model(held, LADDER, [TC, band])["pwm"] == \
        pytest.approx(predict_model(data, LADDER, [TC, band])["pwm"] + correction, abs=1e-12)
    # ... one without it, or with the effect in another form, does not
    other = Effect.create("temperature-coefficient", "junction", alpha_per_k=5e-3)
    for effects in ([other], [], [band]):
        assert predict_model(held, LADDER, effects)["pwm"] == \
            pytest.approx(predict_model(data, LADDER, effects)["pwm"], abs=0)


def test_a_linear_model_needs_no_correction():
    data = _slow_pwm()
    assert pwm_correction(data, LADDER, []) is None
    assert pwm_correction(data, LADDER, [Effect.create("sample-window", window_s=1e-3)]) is None
    assert pwm_correction(_data(), LADDER, [TC]) is not None
    no_grid = BundleData.from_bundle(Bundle(ambient_c=25.0, cooling=(
        CoolingTable(T, 0.3, tj_c=np.zeros(T.size), tref_steady_c=25.0),)))
    assert pwm_correction(no_grid, LADDER, [TC]) is None


def test_settling_brings_a_nonlinear_models_pwm_readings_to_their_noise():
    noise_k = 0.01
    data = _slow_pwm(_exact([TC]), noise_k)
    noise = {n: noise_k for n in data.datasets}
    cauer = LADDER.to_cauer()
    layout = Layout(((TC.plugin, TC.form),), cauer.order)
    fit = fit_starts(data, noise, layout, [Start(cauer, (dict(TC.params),))], 30)[0]
    n = data.pwm.tj_c.size
    assert fit.chi2["pwm"] > 10 * n  # the closed form cannot reach the exact readings
    held, settled = settle(data, noise, fit, 30)
    assert settled.chi2["pwm"] < n + 3 * np.sqrt(2 * n)
    assert settled.chi2_total < fit.chi2_total
    # the correction held is the settled model's own: its predictions are exact
    model = ThermalModel(settled.ladder, settled.effects)
    assert settled.predictions["pwm"] == pytest.approx(
        [25.0 + model.pwm_reading(0.3, f, d, 1e-4) for f, d in zip(SLOW_F, D, strict=True)],
        abs=1e-4)
    assert held.pwm.tj_c is data.pwm.tj_c  # the readings themselves are untouched


def test_a_memo_spares_the_network_a_fit_that_moves_only_measurements_and_changes_nothing():
    data = _data()
    band = Effect.create("phase-change", "logistic", node=1.0, t_c=40.0, width_k=3.0,
                         latent_j=1e-3)
    window = Effect.create("sample-window", "average", window_s=3e-4)
    net = NetworkBatch.of(LADDER, [band])
    terms = [MeasurementTerm(window.plugin, window.form,  # type: ignore[arg-type]
                             {"window_s": np.array([[3e-4]])})]
    plain = predict(data, net, terms)
    memo: dict = {}
    with metered() as first:
        once = predict(data, net, terms, memo=memo)
    terms2 = [MeasurementTerm(window.plugin, window.form,  # type: ignore[arg-type]
                              {"window_s": np.array([[5e-4]])})]
    with metered() as second:
        again = predict(data, NetworkBatch.of(LADDER, [band]), terms2, memo=memo)
    assert all(np.array_equal(plain[k], once[k]) for k in plain)
    assert first.cost > 0 and second.cost == 0
    assert again["cooling_1"] == pytest.approx(once["cooling_1"], abs=0)
    assert not np.allclose(again["pwm"], once["pwm"])  # the window moved the readings
    other = NetworkBatch.of(Foster.from_tau([6.0, 20.0, 50.0, 71.0], [1e-4, 5e-3, 0.4, 30.0]),
                            [band])
    with metered() as third:
        predict(data, other, terms, memo=memo)
    assert third.cost > 0 and len(memo) == 1  # another network: simulated, and the one kept
