"""ThermalModel: linear closed form, nonlinear integration, shooting, files."""

from __future__ import annotations

import json

import numpy as np
import pytest

from spicethermal.core.errors import DataFormatError
from spicethermal.core.ladder import Cauer, Foster
from spicethermal.effects import Effect, known_names
from spicethermal.engines.pwm import steady_state
from spicethermal.model import Schedule, ThermalModel


@pytest.mark.parametrize("topology", ["foster", "cauer"])
def test_linear_simulation_is_exact(actuator, topology):
    m = ThermalModel(actuator).with_topology(topology)
    t = np.logspace(-6, 2, 40)
    tr = m.simulate(t, Schedule.step(0.1))
    np.testing.assert_allclose(tr.tj_k, 0.1 * actuator.zth(t), rtol=1e-10, atol=1e-13)
    # cooling after a long heating phase follows the cooling curve
    sched = Schedule((0.0, 1000.0), (0.1, 0.0))
    t2 = 1000.0 + np.logspace(-5, 1, 20)
    np.testing.assert_allclose(m.simulate(t2, sched).tj_k,
                               0.1 * (actuator.cooling(t2 - 1000.0) - actuator.cooling(t2)),
                               rtol=1e-9, atol=1e-12)


def test_nonlinear_integrator_matches_closed_form_when_effect_is_zero(actuator):
    lin = ThermalModel(actuator.to_cauer())
    nl = lin.with_effects([Effect.create("temperature-coefficient", alpha_per_k=0.0)])
    assert not nl.is_linear
    t = np.logspace(-5, 2, 15)
    np.testing.assert_allclose(nl.simulate(t, Schedule.step(0.1)).tj_k,
                               lin.simulate(t, Schedule.step(0.1)).tj_k, rtol=1e-6, atol=1e-7)
    s_nl, s_lin = nl.pwm(0.094, 2e3, 0.3, 1e-4), steady_state(actuator, 0.094, 2e3, 0.3, 1e-4)
    for key in ("peak_k", "valley_k", "reading_k", "mean_k"):
        assert getattr(s_nl, key) == pytest.approx(getattr(s_lin, key), abs=1e-6)


def test_temperature_coefficient_steady_state_is_self_consistent():
    m = ThermalModel(Cauer([100.0], [1e-2]),
                     (Effect.create("temperature-coefficient", alpha_per_k=-2e-3, t0_c=25.0),))
    # θ = P R0 (1 + α θ)  with Tref = T0  ->  θ = P R0 / (1 - α P R0)
    p = 0.2
    expected = p * 100 / (1 + 2e-3 * p * 100)
    assert m.steady_nodes(p, tref_c=25.0)[0] == pytest.approx(expected, rel=1e-10)
    tr = m.simulate([20.0], Schedule.step(p), tref_c=25.0)
    assert tr.tj_k[0] == pytest.approx(expected, rel=1e-6)


def test_phase_change_delays_heating_through_the_band():
    lad = Cauer([50.0, 50.0], [1e-3, 1e-2])
    base = ThermalModel(lad)
    pc = base.with_effects([Effect.create("phase-change", t_c=40.0, width_k=1.0, latent_j=0.05,
                                          node=1)])
    t = np.linspace(0.01, 5, 50)
    lin = base.simulate(t, Schedule.step(0.5), tref_c=25.0).theta_k[:, 1]
    slow = pc.simulate(t, Schedule.step(0.5), tref_c=25.0).theta_k[:, 1]
    assert np.all(slow <= lin + 1e-6)  # latent heat only ever holds the node back
    lag = lin - slow
    assert lag.max() > 1.0
    assert 38 < 25 + lin[np.argmax(lag)] < 50  # most while the node crosses the band
    assert slow[-1] == pytest.approx(lin[-1], rel=1e-3)  # steady state unchanged


def test_nonlinear_pwm_shooting_converges_to_periodic_orbit():
    m = ThermalModel(Foster.from_tau([20.0, 80.0], [1e-3, 2.0]).to_cauer(),
                     (Effect.create("temperature-coefficient", alpha_per_k=-3e-3),))
    s = m.pwm(0.3, 1e3, 0.5, window_s=1e-4, tref_c=25.0)
    x0 = m.pwm_initial_state(0.3, 1e3, 0.5, tref_c=25.0)
    tr = m.simulate(np.array([0.0, 1e-3, 2e-3]), Schedule.pwm(0.3, 1e3, 0.5, 2), 25.0, x0)
    np.testing.assert_allclose(tr.theta_k[1], x0, atol=1e-6)  # the orbit is periodic
    assert s.valley_k == pytest.approx(x0[0], abs=1e-9)
    assert s.valley_k < s.mean_k < s.peak_k and s.reading_k < s.peak_k
    lin = steady_state(m.ladder, 0.3, 1e3, 0.5)
    assert s.mean_k < lin.mean_k  # Rth falls as it heats (alpha < 0)


def test_model_file_round_trip(tmp_path, actuator):
    m = ThermalModel(actuator, (Effect.create("sample-window", window_s=1e-4),), "ambient",
                     {"source": "unit test", "order": 4})
    path = m.save(tmp_path / "m.json")
    data = json.loads(path.read_text())
    assert data["format"] == "spicethermal-model/3" and data["topology"] == "foster"
    assert data["rth_k_per_w"] == pytest.approx(146.0)
    assert ThermalModel.load(path) == m


def test_a_band_away_from_the_junction_reads_as_the_version_meant(tmp_path, actuator):
    """``spicethermal-model/3`` puts a band at node k > 0 at layer k of the Cauer form; a ``/2``
    file put it at the Foster network's node k: such a file is refused (refit), one on a
    Cauer ladder or with the band at the junction means the same in both and is read."""
    from spicethermal.core.errors import DataFormatError

    band = Effect.create("phase-change", t_c=40.0, width_k=2.0, latent_j=0.05, node=1)
    m = ThermalModel(actuator, (band,))
    assert ThermalModel.load(m.save(tmp_path / "m.json")) == m
    old = {**m.to_dict(), "format": "spicethermal-model/2"}
    with pytest.raises(DataFormatError, match=r"v2.json: spicethermal-model/2 puts the "
                                              r"phase-change at node 1 of the Foster"):
        ThermalModel.from_dict(old, "v2.json")
    cauer = m.with_topology("cauer")
    assert ThermalModel.from_dict({**cauer.to_dict(), "format": "spicethermal-model/2"}) == cauer
    junction = m.with_effects([Effect.create("phase-change", t_c=40.0, width_k=2.0,
                                             latent_j=0.05)])
    assert ThermalModel.from_dict({**junction.to_dict(),
                                   "format": "spicethermal-model/2"}) == junction
    # the same device either way: the Foster model is simulated on its Cauer form
    t = np.geomspace(1e-4, 100.0, 20)
    a = m.simulate(t, Schedule.step(0.3), tref_c=25.0).tj_k
    b = cauer.simulate(t, Schedule.step(0.3), tref_c=25.0).tj_k
    np.testing.assert_allclose(a, b, atol=1e-4)


@pytest.mark.parametrize("patch, message", [
    ({"format": "other/1"}, "format"),
    ({"topology": "pi"}, "topology"),
    ({"stages": []}, "stages"),
    ({"stages": [{"r_k_per_w": 1.0}]}, "c_j_per_k"),
    ({"stages": [{"r_k_per_w": -1.0, "c_j_per_k": 1.0}]}, r"r_k_per_w\[0\]"),
    ({"effects": [{"name": "magic"}]}, "unknown effect 'magic'"),
    ({"effects": [{"name": "sample-window", "params": {"window_s": -1}}]}, "window_s"),
    ({"reference": "moon"}, "reference"),
])
def test_bad_model_files_name_the_problem(tmp_path, actuator, patch, message):
    data = ThermalModel(actuator).to_dict() | patch
    p = tmp_path / "bad.json"
    p.write_text(json.dumps(data))
    with pytest.raises(DataFormatError, match=message):
        ThermalModel.load(p)


def test_catalogue_names_are_the_contract():
    assert known_names() == sorted(["temperature-coefficient", "phase-change", "sample-window",
                                    "electrical-transient", "tsp-nonlinearity"])
    with pytest.raises(DataFormatError, match="unknown parameter"):
        Effect.create("phase-change", latent=1.0)
    with pytest.raises(DataFormatError, match="node 7 does not exist"):
        ThermalModel(Cauer([1.0], [1.0]), (Effect.create("phase-change", node=7),))
