"""The one network simulator against closed forms and against the independent validation
network (its own stiff integrator, shared physics code none)."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from scipy.special import lambertw

from spicethermal.core.ladder import Cauer, Foster
from spicethermal.effects import Effect
from spicethermal.engines.meter import SOLVE_NODES, STEP_SOLVES, metered
from spicethermal.engines.network import SHARED_STEPS, NetworkBatch
from spicethermal.validation.network import LatentHeat, Network, ResistanceLaw

R4, C4 = (4.0, 12.0, 40.0, 90.0), (2e-5, 4e-4, 8e-3, 0.3)
T = np.geomspace(1e-5, 100.0, 41)
P, TREF = 0.3, 25.0


def test_a_linear_ladder_is_its_foster_form_exactly(actuator):
    net = NetworkBatch.of(actuator)
    r, tau = net.foster()
    assert np.sort(r[0]) == pytest.approx(np.sort(actuator.r), rel=1e-9)
    assert np.sort(tau[0]) == pytest.approx(np.sort(actuator.tau), rel=1e-9)
    assert net.cooling(P, TREF, T)[0] == pytest.approx(P * actuator.cooling(T), rel=1e-9)
    theta = net.steady(P, TREF)[0]
    assert theta[0] == pytest.approx(P * actuator.rth, rel=1e-12)


def test_a_single_layer_whose_resistance_follows_its_junction_is_lambert_w():
    # C dθ/dt = −θ / (R0 (1 + αθ)) (the reference at T0): t = −C R0 (ln(θ/θ0) + α(θ − θ0))
    r0, c0, alpha, p = 10.0, 0.1, 5e-3, 2.0
    e = Effect.create("temperature-coefficient", alpha_per_k=alpha, t0_c=TREF)
    net = NetworkBatch.of(Cauer([r0], [c0]), [e])
    theta0 = float(net.steady(p, TREF)[0, 0])
    assert theta0 == pytest.approx(p * r0 / (1 - alpha * p * r0), rel=1e-10)
    t = np.array([0.1, 1.0, 3.0])
    # θ e^{αθ} = θ0 e^{αθ0} e^{−t/(R0 C)}
    exact = np.real(lambertw(alpha * theta0 * np.exp(alpha * theta0 - t / (r0 * c0)))) / alpha
    assert net.cooling(p, TREF, t)[0] == pytest.approx(exact, abs=2e-4 * theta0)


CASES = {
    "tc-junction": (dict(laws=(ResistanceLaw("linear", -6e-3),) * 4, control="junction"),
                    [Effect.create("temperature-coefficient", alpha_per_k=-6e-3)]),
    "tc-local": (dict(laws=(ResistanceLaw("linear", 6e-3),) * 4),
                 [Effect.create("temperature-coefficient", "local", alpha_per_k=6e-3)]),
    "tc-outer-power": (dict(laws=(None, None, ResistanceLaw("power", exponent=2.0),
                                  ResistanceLaw("power", exponent=2.0)),
                            c_slope_per_k=(0.0, 0.0, 3e-3, 3e-3)),
                       [Effect.create("temperature-coefficient", "power-law", exponent=2.0,
                                      c_slope_per_k=3e-3, first_layer=2)]),
    "tc-inner-quadratic": (dict(laws=(ResistanceLaw("quadratic", 4e-3, beta_per_k2=-8e-5),) * 2
                                + (None, None)),
                           [Effect.create("temperature-coefficient", "quadratic", alpha_per_k=4e-3,
                                          curvature_per_k2=-8e-5, last_layer=1)]),
    "pc-gaussian-junction": (dict(latent=(LatentHeat(0, 0.02, 60.0, 1.5, "gaussian"),)),
                             [Effect.create("phase-change", "gaussian", t_c=60.0, width_k=1.5,
                                            latent_j=0.02)]),
    "pc-logistic-2": (dict(latent=(LatentHeat(2, 0.2, 50.0, 2.0, "logistic"),)),
                      [Effect.create("phase-change", t_c=50.0, width_k=2.0, latent_j=0.2,
                                     node=2)]),
    "pc-plateau-2": (dict(latent=(LatentHeat(2, 0.3, 45.0, 4.0, "plateau"),)),
                     [Effect.create("phase-change", "plateau", t_c=45.0, width_k=4.0,
                                    edge_k=0.4, latent_j=0.3, node=2)]),
}


@pytest.mark.parametrize("name", CASES)
def test_cooling_matches_the_independent_network(name):
    changes, effects = CASES[name]
    truth = Network(R4, C4, **changes)
    start = truth.steady(P, TREF)
    _, rows = truth.integrate(start, T[-1], 0.0, TREF, t_eval=T)
    net = NetworkBatch.of(Cauer(R4, C4), effects)
    assert net.steady(P, TREF)[0] + TREF == pytest.approx(start, abs=1e-9)
    rise = net.cooling(P, TREF, T)[0]
    # 3 mK on a rise of 40 to 60 K: the transients' tolerance
    assert np.max(np.abs(rise + TREF - rows[:, 0])) < 3e-3


@pytest.mark.parametrize("name", CASES)
def test_heating_matches_the_independent_network(name):
    """Under power the fast nodes follow the state the network tends to, which moves with
    its resistances: a step that held it at the step's middle would leave them half a step
    behind (an error of the first order in the step)."""
    changes, effects = CASES[name]
    truth = Network(R4, C4, **changes)
    _, rows = truth.integrate(np.full(len(R4), TREF), T[-1], P, TREF, t_eval=T)
    net = NetworkBatch.of(Cauer(R4, C4), effects)
    with metered() as meter:
        rise = net.response(np.zeros((1, len(R4))), T, P, TREF)[0, :, 0]
    assert np.max(np.abs(rise + TREF - rows[:, 0])) < 3e-3
    # about 150 networks solved over these seven decades (with the state held at the
    # middle of each step, a temperature coefficient took 650 to 1,400)
    assert meter.solves < 300


@pytest.mark.parametrize("name", ["pc-gaussian-junction", "pc-plateau-2", "tc-local"])
def test_a_tolerance_in_kelvin_bounds_the_error_and_saves_steps(name):
    changes, effects = CASES[name]
    truth = Network(R4, C4, **changes)
    _, rows = truth.integrate(truth.steady(P, TREF), T[-1], 0.0, TREF, t_eval=T)
    tight = NetworkBatch.of(Cauer(R4, C4), effects)
    loose = NetworkBatch(tight.r, tight.c, tight.terms, tol_k=0.02)
    steps = []
    for net in (tight, loose):
        with metered() as meter:
            error = np.max(np.abs(net.cooling(P, TREF, T)[0] + TREF - rows[:, 0]))
        steps.append(meter.solves)
        assert error < max(3e-3, 2 * net.tol_k), (net.tol_k, error)
    assert steps[1] < steps[0]


def test_a_batch_is_its_members_side_by_side():
    e = Effect.create("phase-change", t_c=50.0, width_k=2.0, latent_j=0.2, node=2)
    one = NetworkBatch.of(Cauer(R4, C4), [e])
    big = one.repeat(3)
    big.r = big.r * np.array([[1.0], [1.1], [0.9]])
    together = big.cooling(P, TREF, T)
    for k, scale in enumerate((1.0, 1.1, 0.9)):
        alone = NetworkBatch.of(Cauer(np.array(R4) * scale, C4), [e]).cooling(P, TREF, T)[0]
        assert together[k] == pytest.approx(alone, abs=2e-3)


def test_members_that_repeat_are_simulated_once_and_read_back_in_place():
    e = Effect.create("phase-change", t_c=50.0, width_k=2.0, latent_j=0.2, node=2)
    big = NetworkBatch.of(Cauer(R4, C4), [e]).repeat(4)
    big.r = big.r * np.array([[1.0], [1.1], [1.0], [1.1]])
    distinct, rows = big.unique()
    assert distinct.size == 2 and rows.tolist() in ([0, 1, 0, 1], [1, 0, 1, 0])
    assert distinct.cooling(P, TREF, T)[rows] == pytest.approx(big.cooling(P, TREF, T),
                                                               abs=2e-3)
    alone, same = NetworkBatch.of(Cauer(R4, C4), [e]).unique()
    assert alone.size == 1 and same.tolist() == [0]


def test_a_member_in_thermal_runaway_is_nan_and_the_others_stand():
    e = Effect.create("temperature-coefficient", alpha_per_k=1e-2)
    net = NetworkBatch.of(Cauer(R4, C4), [e]).repeat(2)
    power = np.array([[0.1], [5.0]])  # α·P·Rth = 0.15 and 7.3: the second runs away
    theta = net.steady(power, TREF)
    assert np.all(np.isfinite(theta[0])) and np.all(np.isnan(theta[1]))


def test_pwm_frozen_at_the_mean_is_exact_for_a_linear_ladder(actuator):
    from spicethermal.engines.pwm import stage_peaks

    net = NetworkBatch.of(actuator)
    f, d = np.array([1e3, 25e3]), np.array([0.5, 0.2])
    r, tau = net.frozen_foster(np.array([0.1, 0.1]), f, d, np.array([25.0, 25.0]))
    peaks = (0.1 * stage_peaks(r[0], tau[0], 1 / f[:, None], d[:, None])).sum(axis=1)
    exact = [0.1 * stage_peaks(np.array(actuator.r), np.array(actuator.tau), 1 / fi,
                               di).sum() for fi, di in zip(f, d, strict=True)]
    assert peaks == pytest.approx(exact, rel=1e-9)


def test_model_simulation_is_the_network_simulator():
    from spicethermal.model import Schedule, ThermalModel

    e = Effect.create("temperature-coefficient", "local", alpha_per_k=6e-3)
    model = ThermalModel(Foster.from_cauer(Cauer(R4, C4)), (e,))
    x0 = model.steady_nodes(P, TREF)
    tr = model.simulate(T, Schedule((0.0,), (0.0,)), TREF, x0)
    net = NetworkBatch.of(Cauer(R4, C4), [e])
    assert tr.tj_k == pytest.approx(net.cooling(P, TREF, T)[0], abs=3e-3)
    assert math.isclose(x0[0], float(net.steady(P, TREF)[0, 0]), rel_tol=1e-9)


def test_the_meter_counts_one_solve_a_member_and_step_and_an_enclosing_count_gets_them():
    """A linear cooling is one solve a member, in one step; a nonlinear one a solve a member
    and step (and more when a step is rejected); a count inside another adds to it; the cost
    is the solves and a fixed part for each step."""
    ladder = Cauer([2.0, 5.0, 10.0], [1e-4, 1e-3, 1e-2])
    t = np.geomspace(1e-5, 1.0, 30)
    with metered() as outer:
        with metered() as inner:
            NetworkBatch(np.tile(ladder.r, (4, 1)), np.tile(ladder.c, (4, 1))).cooling(1.0, 25.0, t)
        assert inner.solves == 4 and outer.solves == 4 and inner.steps == outer.steps == 1
        assert inner.cost == 4 + STEP_SOLVES
        hot = NetworkBatch.of(ladder, [Effect.create("temperature-coefficient",
                                                     alpha_per_k=5e-3)])
        with metered() as nonlinear:
            hot.cooling(1.0, 25.0, t)
    assert nonlinear.solves > 10 and nonlinear.steps == nonlinear.solves  # a batch of one
    assert outer.solves == 4 + nonlinear.solves and outer.steps == 1 + nonlinear.steps
    assert outer.cost == outer.solves + STEP_SOLVES * outer.steps


def test_a_long_ladder_counts_more_a_member_and_a_steady_state_counts_its_newton_steps():
    long = Cauer(np.full(2 * SOLVE_NODES, 2.0), np.geomspace(1e-4, 1.0, 2 * SOLVE_NODES))
    with metered() as meter:
        NetworkBatch(np.tile(long.r, (4, 1)), np.tile(long.c, (4, 1))).foster()
    assert meter.solves == 4 * 4 and meter.steps == 1  # twice the nodes: four times a member
    hot = NetworkBatch.of(Cauer([2.0, 5.0, 10.0], [1e-4, 1e-3, 1e-2]),
                          [Effect.create("temperature-coefficient", alpha_per_k=5e-3)])
    with metered() as meter:
        hot.steady(1.0, 25.0)
    assert 2 <= meter.steps == meter.solves < 10  # a few Newton steps of one member
    with metered() as meter:
        NetworkBatch.of(Cauer([2.0, 5.0, 10.0], [1e-4, 1e-3, 1e-2])).steady(1.0, 25.0)
    assert meter.steps == 0  # a linear ladder's steady state is in closed form


@pytest.mark.parametrize("where", ["r", "c"])
@pytest.mark.parametrize("bad", [np.nan, np.inf, -1.0, 0.0])
def test_a_member_whose_network_is_not_positive_and_finite_fails_alone_and_quietly(where, bad):
    r, c = np.array([[1.0, 2.0, 3.0]] * 3), np.array([[1e-3, 1e-2, 1e-1]] * 3)
    (r if where == "r" else c)[1, 1] = bad
    with warnings.catch_warnings():
        # no invalid value reaches the eigensolver
        warnings.filterwarnings("error", message="invalid value encountered in eigh")
        with np.errstate(divide="ignore"):  # a zero resistance: an infinite conductance
            got_r, tau = NetworkBatch(r, c).foster()
    good = NetworkBatch(r[:1], c[:1]).foster()
    assert np.all(np.isnan(tau[1]))
    for i in (0, 2):
        assert np.array_equal(got_r[i], good[0][0]) and np.array_equal(tau[i], good[1][0])


def test_a_few_members_that_hold_a_batch_past_its_shared_steps_fail_and_the_others_go_on():
    # a fit's trial point far from any physical ladder (a first layer of 10^26 K/W, a
    # coefficient's quadratic law at 10^23 K): alone it takes thousands of steps
    e = Effect.create("temperature-coefficient", form="quadratic",
                      alpha_per_k=3.7124419200361553e-3, curvature_per_k2=-3.340029182924946e-05,
                      c_slope_per_k=8.13845458294043e-4)
    odd = ([1.1420073898156763e+26, 241.4250200971635, 2203.5447210763086, 5.128882702291077,
            401.5062680338615, 1423.489878169166, 596.3555737739014, 9.709419848882312],
           [2.4605130961513786e-32, 4.606777951594394e-08, 1.675376125815569e-07,
            6.36563584916833e-07, 9.054669935021068e-06, 2.149601834984747e-08,
            9.874267384153456e-4, 0.18840087793371738])
    theta = [1.3113649540513694e+23, 119.66164807960439, 114.23188430572532, 60.02952723578821,
             59.89959688914322, 49.72359699300314, 14.263252513102492, 0.22307841586497407]
    fine = (np.array(odd[0][1:] + [9.7]), np.array(odd[1][1:] + [0.19]))
    t = np.geomspace(1e-6, 3.0, 66)

    def run(rs, cs, thetas):
        net = NetworkBatch.of(Cauer(rs[0], cs[0]), [e]).repeat(len(rs))
        net = NetworkBatch(np.array(rs), np.array(cs), net.terms, tol_k=1.8e-3)
        with metered() as meter:
            out = net.response(np.array(thetas), t, 0.0, TREF)
        return out[:, :, 0], meter.steps

    alone, steps = run([odd[0]], [odd[1]], [theta])
    assert steps > 2 * SHARED_STEPS
    start = list(fine[0] * 0.3)
    ordinary, few = run([fine[0]] * 3, [fine[1]] * 3, [start] * 3)
    together, shared = run([fine[0]] * 3 + [odd[0]], [fine[1]] * 3 + [odd[1]],
                           [start] * 3 + [theta])
    assert shared < SHARED_STEPS + 2 * few
    assert np.all(np.isnan(together[3, -1])) and np.all(np.isfinite(together[:3]))
    assert together[:3] == pytest.approx(ordinary, abs=1e-2)  # a few of their tolerance
