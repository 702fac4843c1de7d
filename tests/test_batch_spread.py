"""The population's statistics: robust z-scores, outliers and their reasons, envelopes and the
PWM peak table, on ladders with a known truth (no fitting, no Dask)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from spicethermal.batch.population import (
    DEFECT,
    DEFECT_LAYER,
    LAYERS,
    VOID_FACTOR,
    nominal_cauer,
    simulate_population,
)
from spicethermal.batch.spread import (
    Z_OUTLIER,
    envelopes,
    find_outliers,
    fit_envelope,
    pwm_peaks,
    robust_z,
)
from spicethermal.core.errors import DataFormatError
from spicethermal.core.ladder import Cauer, Foster


def test_robust_z_is_the_median_and_mad_score():
    x = np.array([1.0, 2.0, 3.0, 4.0, 100.0])  # median 3, MAD 1
    assert np.allclose(robust_z(x), (x - 3.0) / 1.4826, rtol=0, atol=1e-15)
    assert np.allclose(robust_z(x, floor=10.0), (x - 3.0) / 10.0, rtol=0, atol=1e-15)
    assert robust_z([2.0, 2.0, 2.0]).tolist() == [0.0, 0.0, 0.0]


def test_population_has_the_stated_spread_and_defects():
    pop = simulate_population(600, seed=5, defects=12, spread=0.05)
    assert [d.name for d in pop[:2]] == ["device_001", "device_002"]
    bad = [d for d in pop if d.defect]
    assert len(bad) == 12 and all(d.defect == DEFECT for d in bad)
    good = [d for d in pop if not d.defect]
    nominal = nominal_cauer()
    for k in range(len(LAYERS)):
        log_r = np.log([d.cauer.r[k] / nominal.r[k] for d in good])
        log_c = np.log([d.cauer.c[k] / nominal.c[k] for d in good])
        # log-normal spread 5 %: the sample std is within 4 standard errors (5 % / sqrt(2n))
        for sample in (log_r, log_c):
            assert abs(np.std(sample, ddof=1) - 0.05) < 4 * 0.05 / math.sqrt(2 * len(good))
            assert abs(np.mean(sample)) < 4 * 0.05 / math.sqrt(len(good))
    for d in bad:
        assert VOID_FACTOR[0] <= d.void_factor <= VOID_FACTOR[1]
        assert d.cauer.r[DEFECT_LAYER] > 1.5 * nominal.r[DEFECT_LAYER] * np.exp(-0.25)
    again = simulate_population(600, seed=5, defects=12, spread=0.05)
    assert [d.cauer.r for d in again] == [d.cauer.r for d in pop]
    with pytest.raises(DataFormatError, match="defects"):
        simulate_population(3, defects=4)


def test_planted_voids_are_the_outliers_and_the_reason_locates_the_die_attach():
    pop = simulate_population(150, seed=2, defects=5)
    ladders = [d.cauer for d in pop]
    found = find_outliers([lad.rth for lad in ladders], ladders)
    assert sorted(o.index for o in found) == [i for i, d in enumerate(pop) if d.defect]
    c_die, c_attach = LAYERS[0][2], LAYERS[1][2]
    for o in found:
        truth = pop[o.index]
        extra = truth.cauer.r[DEFECT_LAYER] - np.median([d.cauer.r[DEFECT_LAYER] for d in pop])
        assert o.z_path >= Z_OUTLIER
        assert o.excess_k_per_w == pytest.approx(extra, rel=0.25)  # the void's extra resistance
        # the path matches the population through the die and departs within the die attach
        assert c_die / 2 <= o.departs_c_j_per_k <= c_die + c_attach
        assert o.reason.startswith("larger outer resistance")
        assert "voided die attach" in o.reason


def test_resistance_moved_between_layers_is_not_an_outlier_but_a_shifted_rth_is():
    rng = np.random.default_rng(0)
    nominal = nominal_cauer()
    ladders = [Cauer(np.asarray(nominal.r) * np.exp(rng.normal(0, 0.03, 4)), nominal.c)
               for _ in range(40)]
    r = list(nominal.r)
    r[1], r[2] = r[1] - 0.1, r[2] + 0.1  # a fit that shifts 0.1 K/W outwards: same Rth
    ladders[3] = Cauer(r, nominal.c)
    r = list(nominal.r)
    r[3] *= 1.5  # the outermost layer (interface): Rth +0.45 K/W
    ladders[9] = Cauer(r, nominal.c)
    found = find_outliers([lad.rth for lad in ladders], ladders)
    assert [o.index for o in found] == [9]
    assert found[0].z_rth > Z_OUTLIER
    assert found[0].departs_c_j_per_k > LAYERS[0][2] + LAYERS[1][2] + LAYERS[2][2] / 2


def test_envelopes_and_their_fit_recover_the_ladders():
    t = np.logspace(-5, 2, 71)
    a = Foster.from_tau([0.1, 0.5, 1.0], [1e-4, 1e-2, 1.0])
    b = Foster.from_tau([0.1, 0.6, 1.2], [1e-4, 1e-2, 1.0])
    c = Foster.from_tau([0.2, 0.5, 1.0], [1e-4, 1e-2, 1.0])
    curves = [{"t_s": t.tolist(), "zth_k_per_w": lad.zth(t).tolist()} for lad in (a, b, c)]
    grid, typ, worst = envelopes(curves)
    assert grid[0] == pytest.approx(1e-5) and grid[-1] == pytest.approx(100.0)
    z = np.array([lad.zth(grid) for lad in (a, b, c)])
    assert np.allclose(typ, np.median(z, axis=0), rtol=1e-12)
    assert np.allclose(worst, np.max(z, axis=0), rtol=1e-12)
    # identical devices: the typical ladder is the device's
    same = [{"t_s": t.tolist(), "zth_k_per_w": a.zth(t).tolist()}] * 3
    grid, typ, _ = envelopes(same)
    model = fit_envelope(grid, typ, a.rth, "typ")
    assert model.ladder.order == 3
    assert np.allclose(sorted(model.ladder.tau), a.tau, rtol=1e-4)
    with pytest.raises(DataFormatError, match="share no time span"):
        envelopes([{"t_s": [1e-3, 1e-2], "zth_k_per_w": [1, 2]},
                   {"t_s": [1.0, 10.0], "zth_k_per_w": [1, 2]}])


def test_pwm_peaks_are_percentiles_of_the_closed_form():
    f, d, power = 50.0, 0.3, 2.0
    r = np.linspace(1.0, 3.0, 11)
    tau = 4e-3
    period = 1 / f
    exact = power * r * -np.expm1(-d * period / tau) / -np.expm1(-period / tau)
    rows = pwm_peaks([Foster.from_tau([x], [tau]) for x in r], power, [f], [d])
    assert len(rows) == 1 and rows[0]["devices"] == 11
    assert rows[0]["peak_p50_k"] == pytest.approx(exact[5], rel=1e-6)
    assert rows[0]["peak_p90_k"] == pytest.approx(np.percentile(exact, 90), rel=1e-6)
    assert rows[0]["peak_max_k"] == pytest.approx(exact[-1], rel=1e-6)
