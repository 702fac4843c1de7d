"""phase-change forms: exact physics hooks, the SPICE rendering of each against the model."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad

from spicethermal.core.ladder import Foster
from spicethermal.effects import Effect, phase_change
from spicethermal.model import Schedule, ThermalModel
from spicethermal.spice import lib as spice

FORMS = {"logistic": {"width_k": 2.0}, "gaussian": {"width_k": 2.0},
         "plateau": {"width_k": 6.0, "edge_k": 0.4}}


def _effect(form: str, node: int = 1, latent_j: float = 0.5, t_c: float = 40.0) -> Effect:
    return Effect.create("phase-change", form, t_c=t_c, latent_j=latent_j, node=node,
                         **FORMS[form])


@pytest.mark.parametrize("form", sorted(FORMS))
def test_heat_is_the_integral_of_the_capacity_and_totals_the_latent_heat(form):
    e = _effect(form, node=0)
    for t in (30.0, 38.5, 40.0, 43.0, 55.0):
        integral = quad(lambda x: e.extra_capacitance(0, x), -50.0, t, points=[37, 40, 43],
                        limit=200, epsabs=1e-13)[0]
        assert e.latent_heat(0, t) == pytest.approx(integral, abs=1e-9)
    assert e.latent_heat(0, 1e6) == pytest.approx(0.5, rel=1e-12)
    assert e.latent_heat(0, -1e6) == 0.0 and e.extra_capacitance(0, 1e6) == 0.0
    assert e.latent_heat(1, 40.0) == 0.0  # another node holds nothing
    low, high = phase_change.band(e)
    peak = max(e.extra_capacitance(0, t) for t in np.linspace(30, 50, 401))
    assert e.extra_capacitance(0, low) < 1.1e-6 * peak
    assert e.extra_capacitance(0, high) < 1.1e-6 * peak


def test_gaussian_closed_forms():
    e = _effect("gaussian", node=0)
    # Φ(1) and φ(0)/σ in closed form
    assert e.latent_heat(0, 42.0) == pytest.approx(0.5 * 0.5 * (1 + math.erf(1 / math.sqrt(2))),
                                                   rel=1e-14)
    assert e.extra_capacitance(0, 40.0) == pytest.approx(0.5 / (2.0 * math.sqrt(2 * math.pi)),
                                                         rel=1e-14)


def test_plateau_is_flat_between_its_edges():
    e = _effect("plateau", node=0)  # 37..43 °C, edges of 0.4 K
    # σ(x) − σ(x − w/e) in closed form: tanh(w/4e) at the centre
    assert e.extra_capacitance(0, 40.0) == pytest.approx(0.5 / 6.0 * math.tanh(3.75), rel=1e-12)
    top = [e.extra_capacitance(0, t) for t in (39.0, 40.0, 41.0)]
    assert np.allclose(top, 0.5 / 6.0, rtol=2e-2)  # flat within 2 % a few edges inside
    assert e.extra_capacitance(0, 37.0) == pytest.approx(0.5 / 12.0, rel=1e-6)  # mid-edge: half


def test_gaussian_spice_approximation_error_is_bounded():
    """The logistic-cubic Φ used in SPICE stays within GAUSSIAN_SPICE_ERROR everywhere."""
    a, b = phase_change.GAUSSIAN_LOGIT
    z = np.linspace(-10.0, 10.0, 200001)
    zc = np.clip(z, -8.0, 8.0)
    approx = 1.0 / (1.0 + np.exp(-(a * zc + b * zc ** 3)))
    exact = np.array([0.5 * math.erfc(-x / math.sqrt(2)) for x in z])
    err = float(np.max(np.abs(approx - exact)))
    assert err < phase_change.GAUSSIAN_SPICE_ERROR
    assert err > 1e-5  # an approximation indeed: the bound is not vacuous


@pytest.mark.parametrize("form", sorted(FORMS))
def test_spice_expression_is_the_python_heat(form):
    """The stored-heat expression, evaluated as Python, is the hook (gaussian: within the
    approximation's bound)."""
    e = _effect(form, node=2)
    expr = e.spice_stored_heat(2, "T")
    assert e.spice_stored_heat(1, "T") is None
    names = {"EXP": math.exp, "LOG": math.log, "MAX": max, "MIN": min,
             "PWR": lambda x, y: math.copysign(abs(x) ** y, x)}
    tol = phase_change.GAUSSIAN_SPICE_ERROR * 0.5 if form == "gaussian" else 1e-12
    for t in (-300.0, 20.0, 36.0, 38.0, 40.0, 41.5, 44.0, 90.0, 900.0):
        assert eval(expr, names, {"T": t}) == pytest.approx(e.latent_heat(2, t), abs=tol)


@pytest.mark.ngspice
@pytest.mark.parametrize("form", sorted(FORMS))
@pytest.mark.parametrize("node", [0, 2])
def test_each_form_in_ngspice_matches_the_model(tmp_path, form, node):
    ladder = Foster.from_tau([5.0, 20.0, 60.0], [1e-3, 0.05, 0.8])
    model = ThermalModel(ladder, (_effect(form, node, latent_j=0.3, t_c=40.0),))
    model = model.with_topology("cauer")
    lib = spice.export(model, tmp_path / "m.lib", "ngspice", "cauer", "PC",
                       temperature="absolute")
    net = spice.render_bench(lib, "PC", power_w=0.3, tstop_s=4.0, tmax_s=4e-3, tref_c=25.0,
                             toffset_c=None)
    w = spice.NgspiceBatch().run(net, ["V(TJ)"], "ngspice")
    t = w.t_s[w.t_s > 1e-3]
    py = model.simulate(t, Schedule((0.0, 2e-8), (0.0, 0.3)), tref_c=25.0).tj_k + 25.0
    sim = w["V(TJ)"][w.t_s > 1e-3]
    assert np.max(np.abs(sim - py)) < 0.05  # K, of a rise of about 25 K
    lin = ThermalModel(model.ladder).simulate(t, Schedule.step(0.3)).tj_k + 25.0
    assert np.max(np.abs(lin - py)) > 0.5  # the band matters at this strength
