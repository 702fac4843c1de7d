"""Ladders: closed forms, validation, and exact Foster <-> Cauer conversion."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from spicethermal.core.errors import DataFormatError
from spicethermal.core.ladder import ROUND_TRIP_RTOL, Cauer, Foster, round_trip_error


def test_single_stage_closed_forms():
    f = Foster.from_tau([4.0], [2e-3])
    t = np.array([0.0, 1e-3, 2e-3, 1.0])
    np.testing.assert_allclose(f.zth(t), 4 * (1 - np.exp(-t / 2e-3)), rtol=1e-15, atol=0)
    np.testing.assert_allclose(f.cooling(t), 4 * np.exp(-t / 2e-3), rtol=1e-15)
    np.testing.assert_allclose(f.r_norm(t), 1 - np.exp(-t / 2e-3), rtol=1e-15)
    w = np.array([0.0, 500.0, 1e6])
    np.testing.assert_allclose(f.impedance(w), 4 / (1 + 1j * w * 2e-3), rtol=1e-15)
    assert f.rth == 4.0 and f.order == 1 and len(f) == 1
    np.testing.assert_allclose(f.time_constants(), [2e-3])


def test_heating_plus_cooling_is_rth(actuator):
    t = np.logspace(-6, 3, 50)
    np.testing.assert_allclose(actuator.zth(t) + actuator.cooling(t), actuator.rth, rtol=1e-14)


def test_foster_stages_sorted_and_immutable():
    f = Foster.from_tau([1.0, 2.0], [10.0, 1e-3])
    assert f.tau == pytest.approx((1e-3, 10.0))
    assert f.r == (2.0, 1.0)
    with pytest.raises(dataclasses.FrozenInstanceError):
        f.r = (1.0,)


@pytest.mark.parametrize("r, c, where", [
    ([1.0, -1.0], [1.0, 1.0], "r_k_per_w[1]"),
    ([1.0, float("nan")], [1.0, 1.0], "r_k_per_w[1]"),
    ([1.0, 1.0], [1.0, -1.0], "c_j_per_k[1]"),
    ([1.0, 1.0], [1.0, float("inf")], "c_j_per_k[1]"),
    ([], [], "at least one stage"),
    ([1.0, 1.0], [1.0], "expected 2 values"),
])
def test_invalid_ladders_name_the_parameter(r, c, where):
    for kind in (Foster, Cauer):
        with pytest.raises(DataFormatError, match=where.replace("[", r"\[").replace("]", r"\]")):
            kind(r, c)


def test_two_stage_cauer_by_hand():
    # Z(s) = 1/(1+s) + 1/(1+10 s): Cauer C1 = lim Y/s = 1/(r1 τ1^-1 ... ) computed by hand:
    # Z = (2 + 11 s) / ((1+s)(1+10 s)), Y = (1 + 11 s + 10 s²)/(2 + 11 s)
    # C1 = 10/11; remainder Y - sC1 = (1 + (11 - 20/11) s)/(2 + 11 s) -> R1 = 11/(101/11) ...
    f = Foster.from_tau([1.0, 1.0], [1.0, 10.0])
    c = f.to_cauer()
    c1 = 10 / 11
    r1 = 11 / (11 - 20 / 11)
    assert c.c[0] == pytest.approx(c1, rel=1e-15)
    assert c.r[0] == pytest.approx(r1, rel=1e-15)
    assert c.rth == pytest.approx(2.0, rel=1e-15)
    s = 1j * np.logspace(-3, 3, 13)
    z_cauer = 1 / (s * c.c[0] + 1 / (c.r[0] + 1 / (s * c.c[1] + 1 / c.r[1])))
    np.testing.assert_allclose(z_cauer, f.impedance(s.imag), rtol=1e-13)


@pytest.mark.parametrize("order", [1, 2, 3, 5, 8, 12, 16, 20, 50, 200])
def test_round_trip_is_exact_over_eight_decades(order):
    rng = np.random.default_rng(order)
    tau = np.logspace(-5, 3, order) * rng.uniform(0.7, 1.3, order) if order > 1 else [1e-2]
    f = Foster.from_tau(rng.uniform(0.05, 20.0, order), tau)
    back = f.to_cauer().to_foster()
    np.testing.assert_allclose(back.r, f.r, rtol=1e-9, atol=0)
    np.testing.assert_allclose(back.tau, f.tau, rtol=1e-9, atol=0)
    # and the Cauer network itself has the same impedance (independent check, nodal solve)
    cauer = f.to_cauer()
    cv, g = cauer.state_matrices()
    w = np.logspace(-4, 6, 7)
    e0 = np.zeros(order)
    e0[0] = 1.0
    z = [np.linalg.solve(1j * wi * np.diag(cv) + g, e0)[0] for wi in w]
    np.testing.assert_allclose(z, f.impedance(w), rtol=1e-8)


def test_cauer_responses_go_through_foster(actuator):
    cauer = Cauer.from_foster(actuator)
    t = np.logspace(-6, 3, 30)
    np.testing.assert_allclose(cauer.zth(t), actuator.zth(t), rtol=1e-12)
    assert Foster.from_cauer(cauer) == cauer.to_foster()
    np.testing.assert_allclose(cauer.time_constants(), actuator.time_constants(), rtol=1e-12)


@pytest.mark.parametrize("order", [2, 6, 13, 20])
def test_bidiagonal_conversion_agrees_with_exact_rationals(order):
    rng = np.random.default_rng(10 + order)
    f = Foster.from_tau(rng.uniform(0.05, 20.0, order),
                        np.logspace(-5, 3, order) * rng.uniform(0.8, 1.2, order))
    exact = f.to_cauer("rational")
    fast = f.to_cauer("bidiagonal")
    np.testing.assert_allclose(fast.r, exact.r, rtol=1e-11, atol=0)
    np.testing.assert_allclose(fast.c, exact.c, rtol=1e-11, atol=0)


def test_cauer_to_foster_two_stage_closed_form():
    # Cauer r = (1, 1), c = (1, 1): C dθ/dt = -G θ + e0 P, G = [[1, -1], [-1, 2]], so
    # Z(s) = e0ᵀ (sC + G)⁻¹ e0 = (s + 2) / (s² + 3 s + 1), poles -λ with λ = (3 ± √5)/2,
    # residues (2 - λ) / (3 - 2 λ) = r/τ = r λ
    f = Cauer([1.0, 1.0], [1.0, 1.0]).to_foster()
    lam = np.array([(3 + 5**0.5) / 2, (3 - 5**0.5) / 2])
    res = (2 - lam) / (3 - 2 * lam)
    np.testing.assert_allclose(f.tau, 1 / lam, rtol=1e-15)
    np.testing.assert_allclose(f.r, res / lam, rtol=1e-14)


def test_lost_precision_is_a_one_line_refusal_naming_the_limit():
    n = 400  # 400 stages within a factor 2 of time constant: no double-precision Cauer exists
    f = Foster.from_tau(np.ones(n), np.linspace(1.0, 2.0, n))
    with pytest.raises(DataFormatError, match=r"order 400: .*limited to 100 stages") as err:
        f.to_cauer()
    assert "\n" not in str(err.value)


def test_round_trip_error_measures_the_worst_stage():
    f = Foster.from_tau([1.0, 2.0], [1e-3, 1.0])
    off = Cauer(f.to_cauer().r, np.multiply(f.to_cauer().c, [1.0, 1.0 + 1e-6]))
    assert 1e-7 < round_trip_error(f, off) < 1e-5
    assert round_trip_error(f, f.to_cauer()) <= ROUND_TRIP_RTOL
