"""Levenberg–Marquardt side by side: exact recovery on closed-form problems, bounds, failed
points, and work that depends on the input only."""

from __future__ import annotations

import numpy as np
import pytest

from spicethermal.fit.lm import levenberg_marquardt

T = np.linspace(0.0, 2.0, 30)
Y = 3.0 * np.exp(-2.0 * T) + 0.5 * np.exp(-0.2 * T)


def _two_exponentials(x, _rows):
    return (x[:, :1] * np.exp(-x[:, 1:2] * T) + x[:, 2:3] * np.exp(-x[:, 3:4] * T)) - Y


def test_every_start_recovers_the_exact_parameters():
    starts = np.array([[1.0, 1.0, 1.0, 0.1], [5.0, 4.0, 0.1, 0.5], [2.0, 3.0, 1.0, 0.05]])
    res = levenberg_marquardt(_two_exponentials, starts, [0, 0, 0, 0], [10, 10, 10, 10],
                              rounds=200)
    for x in res.x:
        pairs = sorted([(x[1], x[0]), (x[3], x[2])])
        assert [v for p in pairs for v in p] == pytest.approx([0.2, 0.5, 2.0, 3.0], rel=1e-6)
    assert np.all(res.converged) and np.max(res.cost) < 1e-16


def test_a_bound_holds_the_parameter_at_the_bound():
    res = levenberg_marquardt(lambda x, _r: x - 5.0, np.array([[1.0]]), [0.0], [2.0])
    assert res.x[0, 0] == pytest.approx(2.0)


def test_a_parameter_the_descent_pushes_past_its_bound_is_held_and_the_others_converge():
    # ½|r|² = ½(a + b − 1)² + 50(a − b − 2)²: unbounded at (1.5, −0.5); with b ≥ 0 the minimum
    # is on the bound, b = 0, a = (1 + 200)/101. The whole step, projected on the bounds,
    # goes nowhere (rejected round after round); the step of a alone reaches the minimum.
    def fun(x, _rows):
        return np.column_stack([x[:, 0] + x[:, 1] - 1.0, 10.0 * (x[:, 0] - x[:, 1] - 2.0)])

    res = levenberg_marquardt(fun, np.array([[1.5, 0.0]]), [-10.0, 0.0], [10.0, 10.0])
    assert res.x[0] == pytest.approx([201 / 101, 0.0], abs=1e-6)
    assert res.converged[0] and res.rounds <= 4


def test_points_where_the_model_fails_are_never_taken():
    res = levenberg_marquardt(lambda x, rows: np.where(x > 3.5, np.nan, x - 3.0) * np.ones(4),
                              np.array([[0.0]]), [-10.0], [10.0])
    assert np.all(np.isfinite(res.fun)) and res.x[0, 0] == pytest.approx(3.0)


def test_the_work_is_the_same_for_the_same_input():
    starts = np.array([[1.0, 1.0, 1.0, 0.1], [5.0, 4.0, 0.1, 0.5]])
    a = levenberg_marquardt(_two_exponentials, starts, [0] * 4, [10] * 4, rounds=20)
    b = levenberg_marquardt(_two_exponentials, starts, [0] * 4, [10] * 4, rounds=20)
    assert (a.rows, a.rounds) == (b.rows, b.rounds) and np.array_equal(a.x, b.x)
    assert a.rounds <= 20


def test_a_fit_stops_where_it_is_when_asked_before_a_round():
    """``go_on`` is asked before every round after the first; once it says no, the fit
    returns its points as they are, not converged, after the rounds it took."""
    starts = np.array([[1.0, 1.0, 1.0, 0.1], [5.0, 4.0, 0.1, 0.5]])
    asked = []

    def go_on():
        asked.append(True)
        return len(asked) < 3

    full = levenberg_marquardt(_two_exponentials, starts, [0] * 4, [10] * 4, rounds=200)
    cut = levenberg_marquardt(_two_exponentials, starts, [0] * 4, [10] * 4, rounds=200,
                              go_on=go_on)
    # the first evaluation and three rounds, each of two points and their four differences
    assert len(asked) == 3 and cut.rows == 2 * 5 * (1 + 3) and not np.any(cut.converged)
    assert full.rows > cut.rows
    assert np.all(cut.cost < 0.5 * np.sum(_two_exponentials(starts, None) ** 2, axis=1))
