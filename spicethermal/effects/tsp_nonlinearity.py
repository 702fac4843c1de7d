"""``tsp-nonlinearity`` (measurement): the TSP (diode forward voltage) is not linear in T.

The sensor reads ``T + q (T − t_cal_c)²`` (form ``quadratic``, ``q = quad_k_per_k2``) plus
``c (T − t_cal_c)³`` (form ``cubic``, ``c = cub_k_per_k3``) through its tangent at
``t_cal_c``; the least-squares line of the calibration points absorbs the straight part of the
curvature, and the calibration's own residuals bow. Whether the other readings bend too
depends on how they were converted (``through_line``): through that line, or without
calibration points through the tangent (1: readings converted from voltages by a linear law),
or by a law that follows the TSP's curvature (0: a bench that converts with a quadratic; only
the calibration shows the law). Readings in volts went through the line; readings in °C may
have gone either way, and a fit tries both.

>>> import numpy as np
>>> from spicethermal.effects import Effect
>>> e = Effect.create("tsp-nonlinearity", quad_k_per_k2=1e-3, t_cal_c=20.0)
>>> t = np.array([20.0, 40.0, 60.0, 80.0])
>>> (calibrated(e, t, t) - t).round(4).tolist()
[0.3774, -0.3774, -0.3774, 0.3774]
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np

from .base import (
    CALIBRATION,
    COOLING,
    PWM,
    STEADY,
    Evidence,
    MeasurementEffect,
    Observation,
    Param,
    Traits,
    scalar_params,
)

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

    from .base import Effect


def _sensor(form: str, p: Mapping[str, NDArray], t: NDArray) -> NDArray:
    d = t - p["t_cal_c"]
    out = t + p["quad_k_per_k2"] * d * d
    return out + p["cub_k_per_k3"] * d ** 3 if form == "cubic" else out


def _through_line(form: str, p: Mapping[str, NDArray], t: NDArray,
                  line: NDArray | None) -> NDArray:
    """What the bench reads at true ``t`` ``(B, N)`` through the least-squares line of its
    calibration points ``line`` (the tangent when None)."""
    r = _sensor(form, p, t)
    if line is None:
        return r
    x = np.asarray(line, dtype=float)[None, :]
    y = _sensor(form, p, np.broadcast_to(x, (r.shape[0], x.shape[1])))
    xm, ym = x.mean(axis=1, keepdims=True), y.mean(axis=1, keepdims=True)
    slope = ((x - xm) * (y - ym)).sum(axis=1, keepdims=True) / ((x - xm) ** 2).sum(
        axis=1, keepdims=True)
    return (r - (ym - slope * xm)) / slope


def calibrated(effect: Effect, t_c: NDArray, line_c: NDArray | None) -> NDArray:
    """What the bench reads at true temperatures ``t_c`` through the least-squares line of
    the calibration points ``line_c`` (the tangent when None).

    Parameters
    ----------
    effect : Effect
    t_c : ndarray
    line_c : ndarray or None

    Returns
    -------
    ndarray
    """
    return _through_line(effect.form, scalar_params(effect),
                         np.asarray(t_c, dtype=float)[None, :], line_c)[0]


class TspNonlinearity(MeasurementEffect):
    """The TSP's law bends (see the module docstring)."""

    name = "tsp-nonlinearity"
    summary = "the TSP (diode forward voltage) is not linear in T"
    forms = ("quadratic", "cubic")
    params = {
        "quad_k_per_k2": Param("1/K", 0.0, -1.0, 1.0, "reading error per (T − T_cal)², K/K²",
                               typical=1e-4),
        "t_cal_c": Param("°C", 25.0, -273.15, 1000.0, "centre of the linear calibration",
                         fitted=False),
        "cub_k_per_k3": Param("1/K²", 0.0, -0.1, 0.1, "reading error per (T − T_cal)³, K/K³ "
                              "(form cubic)", ("cubic",), typical=1e-6),
        "through_line": Param("", 1.0, 0.0, 1.0, "1: the other readings went through a linear "
                              "calibration and bend too; 0: they were converted by a law that "
                              "follows the TSP", fitted=False),
    }
    traits = Traits(frozenset({COOLING, STEADY, PWM, CALIBRATION}),
                    needs=frozenset({CALIBRATION}), cost=1.0,
                    confusable_with={"temperature-coefficient": "a TSP calibration over the "
                                     "temperatures reached"})
    stage = 1

    def read(self, form: str, p: Mapping[str, NDArray], obs: Observation,
             values: NDArray) -> NDArray:
        if obs.kind == CALIBRATION:
            return _through_line(form, p, values, obs.x)
        bent = _through_line(form, p, values, obs.line_temps_c)
        return values + p["through_line"] * (bent - values)

    def variants(self, form: str, evidence: Evidence) -> Sequence[Mapping[str, float]]:
        if evidence.in_volts or evidence.calibration is None:
            return ({"through_line": 1.0},)
        return ({"through_line": 1.0}, {"through_line": 0.0})

    def guess(self, form: str, fixed: Mapping[str, float],
              evidence: Evidence) -> Sequence[Mapping[str, float]]:
        t_cal = evidence.reference_c
        base = {"t_cal_c": t_cal, **({"cub_k_per_k3": 0.0} if form == "cubic" else {})}
        if evidence.calibration is not None and evidence.calibration[0].size >= 3:
            temp, read = evidence.calibration
            a = np.column_stack([np.ones_like(temp), temp])
            cols = [(temp - t_cal) ** 2] + ([(temp - t_cal) ** 3] if form == "cubic" else [])
            v = np.column_stack([c - a @ np.linalg.lstsq(a, c, rcond=None)[0] for c in cols])
            coef = np.linalg.lstsq(v, read - temp, rcond=None)[0]
            start = {**base, "quad_k_per_k2": float(coef[0])}
            if form == "cubic":
                start["cub_k_per_k3"] = float(coef[1])
            return (start,)
        q = 1e-4
        return ({**base, "quad_k_per_k2": q}, {**base, "quad_k_per_k2": -q})

    def describe(self, effect: Effect) -> str:
        p = effect.params
        cubic = (f" + {p['cub_k_per_k3']:.3g} K/K³·(T − T_cal)³" if effect.form == "cubic"
                 else "")
        where = ("" if p["through_line"] else
                 " (the other readings were converted by a law that follows it)")
        return (f"the TSP reads {p['quad_k_per_k2']:.3g} K/K²·(T − T_cal)²{cubic} off its "
                f"tangent at {p['t_cal_c']:.4g} °C{where}")
