"""Joint fits: starts settle to a fixed number of digits (the same fit on every run,
whatever the arrays' memory alignment), and a reference ladder never splits a time
constant in two."""

from __future__ import annotations

import numpy as np

from spicethermal.core.ladder import Cauer, Foster
from spicethermal.engines.network import NetworkBatch
from spicethermal.fit.forward import predict_model
from spicethermal.fit.joint import (
    START_DIGITS,
    Layout,
    Start,
    fit_starts,
    settled,
    stage_more,
    start_ladders,
)
from spicethermal.fit.measurement import BundleData
from spicethermal.fit.problem import MIN_TAU_RATIO
from spicethermal.io.bundle import Bundle, CoolingTable

TRUE = Foster.from_tau([2.0, 5.0], [1e-3, 0.3])
T = np.geomspace(1e-5, 30.0, 41)


def _data(ladder: Foster = TRUE) -> BundleData:
    skeleton = BundleData.from_bundle(Bundle(ambient_c=25.0, cooling=(
        CoolingTable(T, 0.5, tj_c=np.zeros(T.size), tj_steady_c=0.0, tref_steady_c=25.0),)))
    clean = predict_model(skeleton, ladder)
    wiggle = 1e-3 * np.sin(np.arange(T.size))  # a reproducible "noise"
    return BundleData.from_bundle(Bundle(ambient_c=25.0, cooling=(
        CoolingTable(T, 0.5, tj_c=clean["cooling_1"] + wiggle,
                     tj_steady_c=float(clean["steady"][0]), tref_steady_c=25.0),)))


def test_settled_keeps_the_stated_digits_and_nothing_below():
    x = np.array([1.23456789012e-7, -9.87654321098e3, 0.0, 25.0])
    got = settled(x)
    assert got[3] == 25.0 and got[2] == 0.0
    assert np.allclose(got, x, rtol=0.6 * 10.0 ** (1 - START_DIGITS), atol=0)
    assert np.array_equal(settled(x * (1 + 1e-13)), got)


def test_a_start_that_differs_below_its_digits_gives_the_same_fit_bit_for_bit():
    data = _data()
    ladder = Cauer([1.5, 5.5], [4e-4, 0.05])
    nudged = Cauer(np.array(ladder.r) * (1 + 3e-14), np.array(ladder.c) * (1 - 2e-14))
    noise = {name: 1e-3 for name in data.datasets}
    a, b = fit_starts(data, noise, Layout((), 2), [Start(ladder), Start(nudged)])
    assert a is not None and b is not None
    assert a.chi2_total == b.chi2_total
    assert a.ladder.r == b.ladder.r and a.ladder.c == b.ladder.c


def test_no_reference_ladder_splits_a_time_constant_in_two():
    ladders = start_ladders(_data(), range(1, 7))
    assert 2 in ladders  # the true order is there
    for m, ladder in ladders.items():
        _, tau = NetworkBatch(np.array([ladder.r]), np.array([ladder.c])).foster()
        ratios = np.diff(np.log(np.sort(tau[0])))
        assert np.all(ratios >= np.log(MIN_TAU_RATIO)), m


def test_a_stage_more_goes_in_every_gap_and_beyond_each_end_changing_nothing_yet():
    ladder = Cauer([1.5, 5.5], [4e-4, 0.05])
    _, tau0 = NetworkBatch(np.array([ladder.r]), np.array([ladder.c])).foster()
    t = np.geomspace(1e-6, 100.0, 50)
    before = Foster.from_tau(*NetworkBatch(np.array([ladder.r]),
                                           np.array([ladder.c])).foster()).zth(t)
    news = []
    for more in stage_more(ladder):
        r, tau = NetworkBatch(np.array([more.r]), np.array([more.c])).foster()
        assert more.order == 3
        new = [x for x in tau[0] if not np.any(np.isclose(x, tau0[0], rtol=1e-6))]
        assert len(new) == 1
        news.append(new[0])
        assert np.allclose(Foster.from_tau(r[0], tau[0]).zth(t), before, rtol=0, atol=2e-6 * 7.0)
    lo, hi = np.log(np.sort(tau0[0]))
    assert np.allclose(np.log(news), [(lo + hi) / 2, lo - 1.0, hi + 1.0])  # widest gap first
