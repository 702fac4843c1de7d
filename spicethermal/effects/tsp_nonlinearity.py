"""``tsp-nonlinearity`` (measurement): the TSP (diode forward voltage) is not linear in T.

Readings through a linear calibration are ``T + q (T − t_cal_c)²`` (form ``quadratic``,
``q = quad_k_per_k2``) plus ``c (T − t_cal_c)³`` (form ``cubic``, ``c = cub_k_per_k3``); the
calibration's own residuals bow accordingly. The diagnosis judges it from the calibration
residuals against their scatter (and from the curves when the calibration is sparse), on
readings that went through a linear calibration only (never counted twice).
"""

from __future__ import annotations

from .catalogue import MEASUREMENT, EffectSpec, Param, register

SPEC = register(EffectSpec(
    "tsp-nonlinearity", MEASUREMENT, "the TSP (diode forward voltage) is not linear in T",
    {"quad_k_per_k2": Param("1/K", 0.0, -1.0, 1.0, "reading error per (T − T_cal)², K/K²"),
     "t_cal_c": Param("°C", 25.0, -273.15, 1000.0, "centre of the linear calibration"),
     "cub_k_per_k3": Param("1/K²", 0.0, -0.1, 0.1, "reading error per (T − T_cal)³, K/K³ "
                           "(form cubic)")},
    ("quadratic", "cubic"), fit="spicethermal.fit.measfit:fit_tsp_nonlinearity"))
