"""Effects: the catalogue contract, the fast forward models against the model's own nonlinear
integration and closed forms, and each effect's fit recovering its hidden parameters."""

from __future__ import annotations

import math
import time

import numpy as np
import pytest

from spicethermal.analysis.scenarios import HIDDEN, actuator, scenario_bundle
from spicethermal.core.errors import DataFormatError, FitError
from spicethermal.core.ladder import Foster
from spicethermal.effects import (
    CATALOGUE,
    DEVICE,
    MEASUREMENT,
    Effect,
    EffectSpec,
    Param,
    known_names,
)
from spicethermal.fit.budget import EVALUATION_S, PC_STEP_S, spent
from spicethermal.fit.effectfit import (
    BundleData,
    CalData,
    TimeLimitError,
    baseline_ladder,
    calibration_reading,
    check_time,
    pc_cooling_rise,
    pc_frozen_ladder,
    predict,
    robust_lsq,
    sse,
    time_limit,
    transient_offset,
    tsp_reading,
    tsp_true,
    window_average_k,
)
from spicethermal.fit.fitters import fit_effect, fit_effect_forms
from spicethermal.fit.tcjunction import tc_cooling_rise, tc_frozen_ladder, tc_steady_scale
from spicethermal.io.bundle import Bundle, CalibrationTable, PwmTable
from spicethermal.model import Schedule, ThermalModel

CONTRACT = {"temperature-coefficient": DEVICE, "phase-change": DEVICE,
            "sample-window": MEASUREMENT, "electrical-transient": MEASUREMENT,
            "tsp-nonlinearity": MEASUREMENT}


def test_catalogue_names_kinds_and_units():
    assert {n: CATALOGUE[n].kind for n in known_names()} == CONTRACT
    for s in CATALOGUE.values():
        assert s.params and all(p.unit is not None and p.low <= p.default <= p.high
                                for p in s.params.values())
    with pytest.raises(DataFormatError, match="known effects"):
        Effect.create("convection")
    with pytest.raises(DataFormatError, match="alpha_per_k"):
        Effect.create("temperature-coefficient", alpha_per_k=1.0)
    with pytest.raises(DataFormatError, match="unknown parameter"):
        Effect.create("sample-window", window=1e-4)


# ------------------------------------------------------------------ temperature coefficient
def test_tc_steady_scale_is_self_consistent():
    rth, alpha, p, tref = 146.0, -3e-3, 0.3, 30.0
    s = tc_steady_scale(rth, alpha, 25.0, tref, p)
    theta = p * rth * s
    assert s == pytest.approx(1 + alpha * (tref + theta - 25.0), rel=1e-14)
    with pytest.raises(Exception, match="steady state"):
        tc_steady_scale(rth, 0.02, 25.0, 25.0, 1.0)  # runaway: 1 - α P Rth < 0


def test_tc_cooling_is_the_models_nonlinear_solution(actuator):
    """The warped-time closed form against the model's Radau integration of the network."""
    alpha = -3e-3
    m = ThermalModel(actuator, (Effect.create("temperature-coefficient", alpha_per_k=alpha),))
    t = np.geomspace(1e-5, 100, 15)
    theta0 = m.steady_nodes(0.3, 25.0)
    exact = m.simulate(t, Schedule((0.0,), (0.0,)), 25.0, theta0).tj_k
    fast = tc_cooling_rise(actuator, alpha, 25.0, 25.0, 0.3, t)
    assert np.max(np.abs(fast - exact)) < 1e-5
    assert tc_cooling_rise(actuator, alpha, 25.0, 25.0, 0.3, [0.0])[0] == pytest.approx(
        theta0[0], rel=1e-12)
    lin = tc_cooling_rise(actuator, 0.0, 25.0, 25.0, 0.3, t)
    assert np.allclose(lin, 0.3 * actuator.cooling(t), rtol=1e-13, atol=0)


def test_tc_pwm_quasi_static_matches_shooting(actuator):
    """Frozen at the mean temperature vs the model's shooting solution (two corners)."""
    eff = Effect.create("temperature-coefficient", alpha_per_k=-3e-3)
    m = ThermalModel(actuator, (eff,))
    for f, d in ((500.0, 0.8), (25e3, 0.2)):
        exact = m.pwm(0.1, f, d, 1e-4, 25.0).reading_k
        lad = tc_frozen_ladder(actuator, -3e-3, 25.0, 25.0, 0.1 * d)
        from spicethermal.engines.pwm import steady_state

        assert steady_state(lad, 0.1, f, d, 1e-4).reading_k == pytest.approx(exact, abs=5e-3)


# ------------------------------------------------------------------------- phase change
def test_pc_cooling_matches_the_models_integration(actuator):
    eff = HIDDEN["phase-change"]
    m = ThermalModel(actuator, (eff,))
    t = np.geomspace(1e-5, 100, 25)
    from spicethermal.analysis.compare import cooling_rise_k

    exact = cooling_rise_k(m, 0.3, t, 25.0)
    fast = pc_cooling_rise(actuator, eff, 25.0, 0.3, t)
    assert np.max(np.abs(fast - exact)) < 2e-3
    lin = 0.3 * actuator.cooling(t)
    assert np.max(fast - lin) > 1.0  # the latent heat holds the junction up by kelvins
    cold = pc_cooling_rise(actuator, eff, 25.0, 0.12, t)  # never reaches the band
    assert np.array_equal(cold, 0.12 * actuator.cooling(t))


def test_pc_cooling_counts_its_work_and_stops_at_its_budget(actuator):
    """The integration runs in ODEPACK's own loop (:mod:`spicethermal.fit.lsoda`): it still
    counts :data:`PC_STEP_S` per right-hand side, and a budget spent within it stops it (the
    error raised in the right-hand side goes through the compiled loop)."""
    eff = HIDDEN["phase-change"]
    t = np.geomspace(1e-5, 100, 25)
    before = spent()
    pc_cooling_rise(actuator, eff, 25.0, 0.3, t)
    steps = (spent() - before) / 1e9 / PC_STEP_S
    assert 50 < steps < 5000
    with pytest.raises(TimeLimitError), time_limit(PC_STEP_S * steps / 2):
        pc_cooling_rise(actuator, eff, 25.0, 0.3, t)


@pytest.mark.parametrize("node", [1, 2])
def test_a_band_away_from_the_junction_sits_at_the_physical_layer(node):
    """A band at node k > 0 of a fitted Foster ladder is the band at layer k of the device:
    the cooling of the diode's four layers with latent heat at layer ``node``, integrated by
    the independent generator, is what the Foster ladder of the same device gives with the
    band at that node (fast model and :class:`ThermalModel` alike). On the Foster network's
    own node k (``spicethermal-model/2``) it was 0.18 K off at node 1 and 1.3 K at node 2."""
    from spicethermal.analysis.compare import cooling_rise_k
    from spicethermal.core.ladder import Cauer
    from spicethermal.validation.cases import DEVICES
    from spicethermal.validation.network import LatentHeat, Network

    dev = DEVICES["diode"]
    p, tref = dev.bench.cooling_powers_w[1], 25.0
    rise = dev.node_rise_k(node)
    t_c, width = tref + 0.6 * rise, 0.1 * rise
    latent = 2.0 * sum(dev.c_j_per_k[node:node + 2]) * rise
    net = Network(dev.r_k_per_w, dev.c_j_per_k,
                  latent=(LatentHeat(node, latent, t_c, width, "logistic"),))
    t = np.geomspace(1e-5, 5.0, 30)
    _, nodes = net.integrate(net.steady(p, tref), float(t[-1]), 0.0, tref, t_eval=t,
                             rtol=1e-10)
    exact = nodes[:, 0] - tref
    foster = Cauer(dev.r_k_per_w, dev.c_j_per_k).to_foster()
    band = Effect.create("phase-change", latent_j=latent, t_c=t_c, width_k=width, node=node)
    assert band.physical_nodes
    fast = pc_cooling_rise(foster, band, tref, p, t)
    model = cooling_rise_k(ThermalModel(foster, (band,)), p, t, tref)
    assert np.max(np.abs(fast - exact)) < 2e-3 and np.max(np.abs(model - exact)) < 2e-3
    assert np.max(np.abs(p * foster.cooling(t) - exact)) > 0.5  # the band shows


def test_pc_with_tc_matches_the_models_integration(actuator):
    pc = HIDDEN["phase-change"]
    tc = Effect.create("temperature-coefficient", alpha_per_k=-3e-3)
    t = np.geomspace(1e-5, 100, 25)
    from spicethermal.analysis.compare import cooling_rise_k

    exact = cooling_rise_k(ThermalModel(actuator, (tc, pc)), 0.35, t, 25.0)
    fast = pc_cooling_rise(actuator, pc, 25.0, 0.35, t, tc)
    assert np.max(np.abs(fast - exact)) < 2e-3
    alone = tc_cooling_rise(actuator, -3e-3, 25.0, 25.0, 0.35, t)
    assert np.max(np.abs(fast - alone)) > 1.0


def test_pc_frozen_ladder_keeps_rth_and_slows_the_junction(actuator):
    eff = Effect.create("phase-change", latent_j=0.05, t_c=40.0, width_k=2.0)
    lad = pc_frozen_ladder(actuator, eff, 25.0, 0.2, 1e3, 0.5)  # mean node rise 14.6 K: in band
    assert lad.rth == pytest.approx(actuator.rth, rel=1e-10)
    assert lad.zth(1e-3) < actuator.zth(1e-3)


def test_pwm_rows_frozen_under_an_integrated_effect_are_counted_as_work(actuator):
    """Freezing a PWM row's ladder under a band or a local coefficient costs ten times the
    row's closed form, and a diagnosis freezes tens of thousands: each is counted, so the
    budgets bound the CPU time they spend (a junction coefficient's closed form is not)."""
    from spicethermal.fit.budget import FROZEN_ROW_S, spent
    from spicethermal.fit.forward import pwm_true_c
    from spicethermal.fit.measurement import PwmData

    rows = 5
    grid = PwmData(np.geomspace(10.0, 1e4, rows), np.full(rows, 0.5), np.full(rows, 0.2),
                   np.full(rows, 25.0), np.zeros(rows), 1e-5)
    band = Effect.create("phase-change", latent_j=0.05, t_c=40.0, width_k=2.0)
    far = Effect.create("phase-change", latent_j=0.05, t_c=400.0, width_k=2.0)
    local = Effect.create("temperature-coefficient", "local", alpha_per_k=2e-3)
    junction = Effect.create("temperature-coefficient", alpha_per_k=2e-3)
    for effects, frozen in (([], 0), ([band], rows), ([far], 0), ([local], rows),
                            ([junction], 0), ([local, band], 2 * rows)):
        w0 = spent()
        pwm_true_c(grid, actuator, effects)
        assert spent() - w0 == frozen * round(FROZEN_ROW_S * 1e9), effects


@pytest.mark.parametrize(("node", "max_k", "rms_k"), [(0, 0.35, 0.09), (1, 0.015, 0.004)])
def test_pc_pwm_reading_near_the_exact_periodic_state(node, max_k, rms_k):
    # a diode's band at 45 % of the node's PWM rise, 5 % wide: the ripple crosses it. The
    # independent generator's shooting gives the exact periodic state; the capacity at the
    # mean temperature (the tangent) was off by 0.46 K / 0.116 K RMS at the junction and
    # 0.032 K / 0.008 K one node out, the secant over the swing by 0.29 / 0.072 and 0.008 /
    # 0.002 K
    from spicethermal.core.ladder import Cauer
    from spicethermal.engines.pwm import steady_state
    from spicethermal.validation.cases import DEVICES
    from spicethermal.validation.measure import DUTIES, FREQS_HZ
    from spicethermal.validation.network import LatentHeat, Network
    from spicethermal.validation.periodic import pwm_reading

    dev = DEVICES["diode"]
    p = dev.bench.pwm_power_w
    rise = dev.node_rise_k(node) * p / dev.bench.cooling_powers_w[1]
    t_c, width = 25.0 + 0.45 * rise, 0.05 * rise
    latent = 0.3 * sum(dev.c_j_per_k[node:node + 3]) * rise
    exact_net = Network(dev.r_k_per_w, dev.c_j_per_k,
                        latent=(LatentHeat(node, latent, t_c, width, "gaussian"),))
    ladder = Cauer(dev.r_k_per_w, dev.c_j_per_k)
    eff = Effect.create("phase-change", "gaussian", latent_j=latent, t_c=t_c, width_k=width,
                        node=node)
    err = [25.0 + steady_state(pc_frozen_ladder(ladder, eff, 25.0, p, f, d), p, f, d,
                               1e-5).reading_k - pwm_reading(exact_net, p, f, d, 25.0, 1e-5)
           for f in FREQS_HZ for d in DUTIES]
    assert np.max(np.abs(err)) < max_k
    assert math.sqrt(np.mean(np.square(err))) < rms_k


# ------------------------------------------------------------------------- measurement
def test_tsp_reading_and_its_inverse():
    eff = Effect.create("tsp-nonlinearity", quad_k_per_k2=4e-4, t_cal_c=25.0)
    t = np.linspace(0.0, 150.0, 31)
    r = tsp_reading(t, eff)
    assert r[t == 85.0][0] == pytest.approx(85.0 + 4e-4 * 3600, abs=1e-12)
    assert np.allclose(tsp_true(r, eff), t, atol=1e-10)


def test_predict_calibration_curvature_is_exact():
    """A quadratic TSP seen through the least-squares line: predicted = observed residuals."""
    temps = np.arange(20.0, 101.0, 10.0)
    q = 4e-4
    volts = 0.65 - 2e-3 * ((temps - 25) + q * (temps - 25) ** 2)
    b = Bundle(ambient_c=25.0, calibration=CalibrationTable(temps, volts),
               pwm=PwmTable([1e3], [0.5], [30.0], power_w=0.1))
    data = BundleData.from_bundle(b)
    eff = Effect.create("tsp-nonlinearity", quad_k_per_k2=q, t_cal_c=25.0)
    pred = predict(data, Foster.from_tau([100.0], [1.0]), [eff])["calibration"]
    assert np.max(np.abs(pred - data.calibration.read_c)) < 1e-9
    assert np.ptp(data.calibration.read_c - temps) > 0.3


def test_sample_window_prediction_reads_lower_than_the_peak(actuator):
    b = Bundle(ambient_c=25.0, pwm=PwmTable([500.0, 25e3], [0.5, 0.5], [30.0, 30.0],
                                            power_w=0.1))
    data = BundleData.from_bundle(b)
    peak = predict(data, actuator)["pwm"]
    read = predict(data, actuator, [Effect.create("sample-window", window_s=1e-4)])["pwm"]
    assert np.all(read < peak)
    assert peak[0] - read[0] > peak[1] - read[1] > 0.1  # larger ripple at 500 Hz


# -------------------------------------------------------------------------------- fits
@pytest.mark.parametrize("name, key, rel", [
    ("temperature-coefficient", "alpha_per_k", 0.03),
    ("phase-change", "latent_j", 0.05),
    ("sample-window", "window_s", 0.12),
    ("electrical-transient", "amplitude_k", 0.02),
    ("tsp-nonlinearity", "quad_k_per_k2", 0.05),
])
def test_fit_recovers_the_hidden_parameter(name, key, rel):
    data = BundleData.from_bundle(scenario_bundle(name, seed=3))
    fit = fit_effect(data, baseline_ladder(data), name)
    truth = HIDDEN[name].params[key]
    assert fit.effect.params[key] == pytest.approx(truth, rel=rel)
    if name == "phase-change":
        assert fit.effect.params["t_c"] == pytest.approx(64.7, abs=0.3)


def test_fit_needs_the_right_data():
    data = BundleData.from_bundle(Bundle(ambient_c=25.0,
                                         pwm=PwmTable([1e3], [0.5], [30.0], power_w=0.1)))
    with pytest.raises(FitError, match="cooling"):
        fit_effect(data, actuator(), "temperature-coefficient")
    with pytest.raises(DataFormatError, match="known effects"):
        fit_effect(data, actuator(), "no-such-effect")
    assert math.isfinite(predict(data, actuator())["pwm"][0])


# ------------------------------------------------------------------------------- forms
def test_every_form_is_valid_and_round_trips():
    for name in known_names():
        s = CATALOGUE[name]
        assert s.forms and len(set(s.forms)) == len(s.forms)
        for form in s.forms:
            e = Effect.create(name, form)
            assert Effect.from_dict(e.to_dict()) == e
    assert "form" not in Effect.create("sample-window").to_dict()  # default: as before
    with pytest.raises(DataFormatError, match="form 'sine'"):
        Effect.create("electrical-transient", "sine")


def test_transient_forms_follow_their_closed_forms():
    t = np.array([0.0, 1e-5, 4e-5])
    fixed = Effect.create("electrical-transient", amplitude_k=-2.0, masked_s=1e-4)
    power = Effect.create("electrical-transient", "power", k_per_w=-4.0, masked_s=1e-4)
    ring = Effect.create("electrical-transient", "ringing", amplitude_k=-2.0, masked_s=1e-4,
                         ring_hz=2.5e4)
    decay = np.exp(-5 * t / 1e-4)
    assert np.allclose(transient_offset(t, fixed, 9.0), -2.0 * decay, rtol=1e-14)
    assert np.allclose(transient_offset(t, power, 0.5), -2.0 * decay, rtol=1e-14)
    assert transient_offset(t, ring)[2] == pytest.approx(-2.0 * decay[2] * math.cos(2.0 * math.pi),
                                                         rel=1e-12)
    assert transient_offset(1e-5, ring) == pytest.approx(-2.0 * decay[1] * math.cos(0.5 * math.pi),
                                                         abs=1e-15)


def test_cubic_tsp_reading_and_its_inverse():
    eff = Effect.create("tsp-nonlinearity", "cubic", quad_k_per_k2=3e-4, cub_k_per_k3=-2e-6,
                        t_cal_c=30.0)
    t = np.linspace(0.0, 150.0, 31)
    r = tsp_reading(t, eff)
    assert r[t == 80.0][0] == pytest.approx(80 + 3e-4 * 2500 - 2e-6 * 125000, abs=1e-12)
    assert np.allclose(tsp_true(r, eff), t, atol=1e-9)


def test_calibration_reading_equals_the_quadratic_closed_form():
    """(u − P u) q / (1 + q b_u): the line regressed on T absorbs the straight part."""
    temps = np.arange(20.0, 101.0, 5.0)
    cal = CalData(temps, temps)
    eff = Effect.create("tsp-nonlinearity", quad_k_per_k2=-6e-4, t_cal_c=40.0)
    basis, b_u = cal.curvature_basis(40.0)
    closed = temps + -6e-4 * basis / (1 - 6e-4 * b_u)
    assert np.allclose(calibration_reading(temps, eff), closed, atol=1e-12)


def test_window_average_is_the_mean_of_the_end_readings(actuator):
    """The mean over the window of the readings taken at each instant of it."""
    from spicethermal.engines.pwm import steady_state

    w = 3e-4
    s = np.linspace(0.0, w, 4001)
    ends = [steady_state(actuator, 0.1, 2e3, 0.4, x).reading_k for x in s]
    assert window_average_k(actuator, 0.1, 2e3, 0.4, w) == pytest.approx(
        np.trapezoid(ends, s) / w, rel=1e-6)


def test_extra_capacitance_is_finite_far_from_the_band():
    e = Effect.create("phase-change", latent_j=5.0, t_c=50.0, width_k=0.05, node=1)
    assert e.extra_capacitance(1, 1e5) == 0.0 and e.extra_capacitance(1, -1e5) == 0.0
    assert e.latent_heat(1, 1e5) == 5.0 and e.extra_capacitance(0, 50.0) == 0.0


# ----------------------------------------------------------------------------- registry
def test_a_plugin_effect_registers_and_is_listed(register_plugin, capsys, tmp_path):
    """A toy effect from outside the package, through the entry-point group."""
    from spicethermal.cli.main import main

    toy = EffectSpec.create("toy-gain", MEASUREMENT, "a toy reading gain",
                            gain=Param("", 1.0, 0.0, 2.0))

    register_plugin(toy)
    assert "toy-gain" in known_names()
    assert Effect.create("toy-gain", gain=1.5).params["gain"] == 1.5
    bundle = scenario_bundle("sample-window", seed=0)
    data = BundleData.from_bundle(bundle)
    with pytest.raises(FitError, match="has no fit"):
        fit_effect(data, actuator(), "toy-gain")
    bundle.write(tmp_path / "b")
    assert main(["diagnose", str(tmp_path / "b"), "--effect", "toy-gain", "-q"]) == 0
    assert "toy-gain                 not tried: fit failed: effect 'toy-gain' has no fit" in \
        capsys.readouterr().out


# ------------------------------------------------------------------------ robust fitting
def test_a_nested_fit_never_fits_worse_than_the_linear_ladder():
    data = BundleData.from_bundle(scenario_bundle("clean", seed=2))
    lad = baseline_ladder(data)
    for name in known_names():
        for fit in fit_effect_forms(data, lad, name):
            assert sse(data, fit.ladder, [fit.effect]) <= sse(data, lad, []) * (1 + 1e-12)


def test_numerical_failures_and_the_time_limit_end_a_fit_cleanly():
    def overflow(x):
        if x[0] > 1.5:
            raise OverflowError("math range error")
        return np.array([x[0] - 2.0, 0.1])

    res = robust_lsq(overflow, [1.0], [0.0], [3.0])
    assert res.x[0] <= 1.5 + 1e-9  # the failing region is never the answer
    with pytest.raises(FitError, match="start point"):
        robust_lsq(overflow, [2.0], [0.0], [3.0])

    def busy(x):  # about 5 ms of CPU per evaluation, minimum at x = 2
        t0 = time.process_time()
        while time.process_time() - t0 < 5e-3:
            pass
        return np.array([math.cosh(x[0]) - math.cosh(2.0), 1e-3 * x[0]])

    # CPU that the budget's costs do not count (a hang): its CPU backstop ends the fit
    with time_limit(0.03):
        res = robust_lsq(busy, [10.0], [-800.0], [800.0], x_scale=1.0)
    assert res.status == -9 and res.cost < 0.5 * (math.cosh(10.0) - math.cosh(2.0)) ** 2

    def counted(x):  # the same residuals, at no cost beyond their evaluation's
        calls.append(float(x[0]))
        return np.array([math.cosh(x[0]) - math.cosh(2.0), 1e-3 * x[0]])

    runs = []
    for _ in range(3):  # the budget is work: it stops the fit at the same point every time
        calls: list[float] = []
        with time_limit(12 * EVALUATION_S):
            res = robust_lsq(counted, [10.0], [-800.0], [800.0], x_scale=1.0)
        runs.append((res.status, calls))
    assert runs[0][0] == -9 and 10 <= len(runs[0][1]) <= 12
    assert runs[1] == runs[0] and runs[2] == runs[0]
    with time_limit(0.0), pytest.raises(TimeLimitError):
        check_time()
