"""The joint refit of a model's effects with its ladder (spicethermal.fit.backfit)."""

from __future__ import annotations

from dataclasses import replace

import pytest

from spicethermal.analysis.scenarios import scenario_bundle
from spicethermal.effects import Effect
from spicethermal.fit.backfit import free_parameters, refit_effects
from spicethermal.fit.budget import time_limit
from spicethermal.fit.effectfit import BundleData, baseline_ladder, sse
from spicethermal.fit.fitters import fit_effect


def test_only_the_parameters_a_fit_moves_are_free():
    tc = Effect.create("temperature-coefficient", "local", alpha_per_k=0.003, t0_c=40.0,
                       first_layer=1.0, last_layer=2.0)
    pc = Effect.create("phase-change", "plateau", latent_j=0.5, t_c=55.0, width_k=3.0,
                       node=2, edge_k=0.4)
    free = {(f.effect, f.name): f for f in free_parameters([tc, pc])}
    # the reference temperature, the layer subset and the node are held; so is c_slope_per_k,
    # which the local fit held at its default
    assert set(free) == {(0, "alpha_per_k"), (1, "latent_j"), (1, "t_c"), (1, "width_k"),
                         (1, "edge_k")}
    assert free[(1, "t_c")].scale == 1.0  # a temperature moves by kelvins
    assert free[(0, "alpha_per_k")].scale == pytest.approx(0.003)
    window = Effect.create("sample-window", "end", window_s=2e-4)
    assert [f.name for f in free_parameters([window])] == ["window_s"]
    assert free_parameters([Effect.create("sample-window", "end")]) == []  # at its default


@pytest.fixture(scope="module")
def tsp_fit():
    data = BundleData.from_bundle(scenario_bundle("tsp-nonlinearity", seed=3))
    ladder = baseline_ladder(data)
    return data, fit_effect(data, ladder, "tsp-nonlinearity")


def test_refit_from_a_perturbed_start_returns_to_the_fit(tsp_fit):
    data, fit = tsp_fit
    p = dict(fit.effect.params)
    start = Effect.create("tsp-nonlinearity", fit.effect.form,
                          **{**p, "quad_k_per_k2": 0.6 * p["quad_k_per_k2"],
                             "t_cal_c": p["t_cal_c"] + 3.0})
    before = sse(data, fit.ladder, [start])
    ladder, (effect,) = refit_effects(data, fit.ladder, [start])
    after = sse(data, ladder, [effect])
    best = sse(data, fit.ladder, [fit.effect])
    assert after < before
    assert after <= best * (1 + 1e-3)
    assert effect.params["quad_k_per_k2"] == pytest.approx(p["quad_k_per_k2"], rel=0.05)
    assert effect.form == fit.effect.form


def test_refit_never_returns_worse_than_its_start(tsp_fit):
    data, fit = tsp_fit
    with time_limit(0.0):  # no time at all: the start comes back unchanged
        ladder, effects = refit_effects(data, fit.ladder, [fit.effect])
    assert effects == [fit.effect]
    assert sse(data, ladder, effects) == pytest.approx(sse(data, fit.ladder, [fit.effect]))


def test_refit_with_nothing_free_is_the_start(tsp_fit):
    data, fit = tsp_fit
    neutral = Effect.create("tsp-nonlinearity")
    ladder, effects = refit_effects(data, fit.ladder, [neutral])
    assert effects == [neutral] and ladder.rth == pytest.approx(fit.ladder.rth)
    assert refit_effects(replace(data), fit.ladder, [])[1] == []


def test_a_ladder_fit_keeps_every_stage_where_the_readings_see_it():
    """A stage parked far below the first reading (τ → 0) or a dead one (R → 0) gets no
    gradient back: the joint fit bounds τ at a tenth of the first reading's time and drops
    stages whose R is nothing (``Foster.pruned``)."""
    from spicethermal.core.ladder import Foster
    from spicethermal.fit.effectfit import joint_fit

    data = BundleData.from_bundle(scenario_bundle("clean", seed=0))
    truth = baseline_ladder(data)
    names = [c.name for c in data.cooling]
    first = min(float(c.t_s[0]) for c in data.cooling)
    parked = Foster.from_tau([*truth.r[:-1], truth.r[-1]], [1e-300, *truth.tau[1:]])
    lad, _, _ = joint_fit(data, names, parked, True, [], [], [], lambda x: [])
    assert min(lad.tau) >= 0.1 * first * (1 - 1e-9)
    assert sse(data, lad, []) < 2 * sse(data, truth, [])
    dead = Foster.from_tau([*truth.r, 1e-200 * truth.rth], [*truth.tau, 3 * max(truth.tau)])
    lad, _, _ = joint_fit(data, names, dead, True, [], [], [], lambda x: [])
    assert lad.order == truth.order
