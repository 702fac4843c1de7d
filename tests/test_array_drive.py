"""The array drive: coupled limits, the hold, the baselines, ngspice."""

from __future__ import annotations

import numpy as np
import pytest

from spicethermal.array.check import verify_drive
from spicethermal.array.drive import Limits, exact_peaks, plan_transition
from spicethermal.array.dynamics import ArrayDynamics
from spicethermal.array.model import ArrayModel
from spicethermal.array.refresh import drive_patterns
from spicethermal.bench.array_devices import ArrayGeometry
from spicethermal.bench.devices import preset
from spicethermal.core.errors import DataFormatError
from spicethermal.drive.optimize import optimize_drive
from spicethermal.model import ThermalModel

LIM = Limits(ambient_c=25.0, t_max_c=85.0, target_c=70.0, tol_k=1.0, actuation_c=64.7,
             margin_k=1.0, p_max_w=1.5, f_pwm_hz=1000.0)


@pytest.fixture(scope="module")
def square() -> ArrayModel:
    return ArrayGeometry(rows=2, cols=2).model()


@pytest.fixture(scope="module")
def diagonal(square):
    """Two diagonal dots up, two down: the down ones sit between them."""
    return drive_patterns(square, [(True, False, False, True)], LIM)


def test_the_transition_boosts_then_holds_with_the_coupling_counted(square) -> None:
    dyn = ArrayDynamics(square, LIM.p_max_w, LIM.f_pwm_hz)
    up = [True, False, False, True]
    tr = plan_transition(dyn, np.zeros(dyn.modes.lam.size), up, LIM)
    assert tr.steps[0][2] == (1.0, 0.0, 0.0, 1.0)  # both boost at once
    rise = dyn.steady_rise(np.array(tr.hold))
    np.testing.assert_allclose(rise[[0, 3]], LIM.tgt_k, atol=1e-9)
    lone = dyn.hold_duties([True, False, False, False], LIM.tgt_k)[0]
    assert tr.hold[0] < lone  # the neighbour's heat helps: less power holds the target
    _, pk = exact_peaks(dyn, np.zeros(dyn.modes.lam.size), tr.steps, np.array(tr.hold), 50)
    assert pk.max() <= LIM.lim_k


def test_ours_is_safe_and_settles_the_naive_one_overheats(diagonal) -> None:
    ours, naive, const = diagonal.ours, diagonal.naive_eval, diagonal.constant_eval
    assert ours.count() == 0
    assert ours.refresh_s[0] < 0.05  # the junctions reach the band in tens of ms
    assert const.refresh_s[0] > 100 * ours.refresh_s[0]  # the hold alone takes seconds
    assert naive.refresh_s[0] == np.inf  # the lone holds drift out of the band
    assert max(naive.peak_c) > max(ours.peak_c)
    assert ours.peak_c.max() <= LIM.t_max_c


def test_an_array_of_one_drives_as_the_single_actuator() -> None:
    single = ThermalModel(preset("actuator").foster)
    one = ArrayModel.from_thermal_model(single)
    cd = drive_patterns(one, [(True,)], LIM)
    lone = optimize_drive(single, LIM.t_max_c, LIM.target_c, LIM.ambient_c, p_max_w=1.5,
                          tol_k=LIM.tol_k, two_phase=False)
    assert cd.ours.refresh_s[0] == pytest.approx(lone.time_to_target_s, rel=0.05)
    assert cd.transitions[0].hold[0] == pytest.approx(lone.hold_duty, rel=1e-9)


def test_impossible_patterns_and_limits_are_refused_in_one_line(square) -> None:
    dyn = ArrayDynamics(square, LIM.p_max_w, LIM.f_pwm_hz)
    hot = Limits(25.0, 120.0, 90.0, 1.0, 40.0, 1.0, 1.5, 1000.0)
    with pytest.raises(DataFormatError, match="must stay down but its raised neighbours"):
        plan_transition(dyn, np.zeros(dyn.modes.lam.size), [True, True, True, False], hot)
    with pytest.raises(DataFormatError, match="must lie at or above the actuation"):
        Limits(25.0, 85.0, 64.0, 1.0, 64.7, 1.0, 1.5, 1000.0)
    with pytest.raises(DataFormatError, match="4 cells"):
        plan_transition(dyn, np.zeros(dyn.modes.lam.size), [True], LIM)


@pytest.mark.ngspice
def test_ngspice_confirms_the_drive_and_the_naive_violations(square) -> None:
    cd = drive_patterns(square, [(True, False, False, True), (True, True, False, False)], LIM,
                        starts=[0.0, 3.0])
    ours = verify_drive(cd, "ours")
    assert ours["t_max"] == 0 and ours["actuation"] == 0
    assert ours["peak_error_k"] < 0.05 and ours["mean_error_k"] < 0.1
    assert max(ours["peak_c"]) <= LIM.t_max_c + 0.05
    naive = verify_drive(cd, "naive")
    assert naive["t_max"] + naive["actuation"] >= 1
