"""Synthetic measurement bundles with one hidden effect each, for tests and studies.

:func:`scenario_bundle` records what the paper's bench would record from a known actuator
(:data:`ACTUATOR`, 4 stages, Rth = 146 K/W, τ from 100 µs to 30 s) with one effect at a
realistic strength, plus white noise: a TSP calibration (20…100 °C every 5 K), two cooling
curves (0.12 W and 0.30 W: rises of about 17 K and 44 K; 10 samples per decade from 1 µs to
100 s; the steady reading just before the cut) and the 18-point PWM grid of the paper's
Table 2 at 0.10 W, read at the end of a 100 µs power-off sample window (declared in the
manifest as ``sample_window_s = 1e-4``).

Scenarios (:data:`SCENARIOS`):

* ``clean`` — the linear ladder only;
* ``temperature-coefficient`` — ``R(T) = R0 (1 − 3e-3/K (T − 25 °C))``;
* ``phase-change`` — methanol latent heat, 0.02 J over 64.7 ± 1.5 °C at the junction node:
  only the 0.30 W curve (68.8 °C at the cut) crosses the band;
* ``sample-window`` — the bench reads after a 100 µs window but the manifest declares none;
* ``electrical-transient`` — cooling readings off by ``−5 K·e^{−5t/100 µs}`` (the reading is
  pulled low and recovers, as in the paper's Fig. 4);
* ``tsp-nonlinearity`` — the diode voltage has a quadratic term: readings through the
  bench's linear calibration (tangent at 25 °C) are ``T + 4e-4/K·(T − 25)²`` (1.4 K at a
  60 K rise);
* ``ambient-drift`` — an effect **outside** the catalogue: the ambient warms by 1 K,
  linearly over the 100 s of the second cooling curve, and no ``tref_c`` column records it.

Device effects are simulated by default with the fast exact solutions of
:mod:`spicethermal.fit.effectfit`; ``exact=True`` uses the :class:`~spicethermal.model.ThermalModel`
integration (Radau, shooting) instead — slower, and independent of the fitting code.

>>> b = scenario_bundle("clean", seed=1)
>>> [round(c.power_w, 2) for c in b.cooling], len(b.pwm.tj_c)
([0.12, 0.3], 18)
"""

from __future__ import annotations

import functools
from collections.abc import Mapping
from typing import TYPE_CHECKING

import numpy as np

from ..core.errors import DataFormatError
from ..core.ladder import Foster
from ..effects import Effect
from ..fit.effectfit import (
    CurveData,
    PwmData,
    cooling_true_c,
    pwm_true_c,
    transient_offset,
    tsp_reading,
)
from ..io.bundle import Bundle, CalibrationTable, CoolingTable, PwmTable
from ..model import ThermalModel
from .compare import cooling_rise_k

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

#: The actuator of the scenarios: R (K/W) and τ (s) of its Foster stages.
ACTUATOR_R = (6.0, 20.0, 50.0, 70.0)
ACTUATOR_TAU = (1e-4, 5e-3, 0.4, 30.0)
AMBIENT_C = 25.0
COOLING_POWERS_W = (0.12, 0.30)
PWM_POWER_W = 0.10
FREQS_HZ = (500.0, 1e3, 3e3, 5e3, 10e3, 25e3)
DUTIES = (0.2, 0.5, 0.8)
WINDOW_S = 1e-4
T_COOL_S = 10.0 ** (np.arange(-60, 21) / 10)  # 1 µs ... 100 s, 10 per decade
CAL_TEMPS_C = np.arange(20.0, 100.1, 5.0)
V25_V, K_V_PER_K = 0.650, -2.0e-3
DRIFT_K = 1.0

#: The hidden effect of each scenario (None: none, or one outside the catalogue).
HIDDEN: Mapping[str, Effect | None] = {
    "clean": None,
    "temperature-coefficient": Effect.create("temperature-coefficient", alpha_per_k=-3e-3,
                                             t0_c=AMBIENT_C),
    "phase-change": Effect.create("phase-change", latent_j=0.02, t_c=64.7, width_k=1.5, node=0),
    "sample-window": Effect.create("sample-window", window_s=WINDOW_S),
    "electrical-transient": Effect.create("electrical-transient", amplitude_k=-5.0,
                                          masked_s=1e-4),
    "tsp-nonlinearity": Effect.create("tsp-nonlinearity", quad_k_per_k2=4e-4,
                                      t_cal_c=AMBIENT_C),
    "ambient-drift": None,
}
SCENARIOS = tuple(HIDDEN)


def actuator() -> Foster:
    """The scenarios' actuator ladder (Rth = 146 K/W, the paper's value)."""
    return Foster.from_tau(ACTUATOR_R, ACTUATOR_TAU)


def expected_effect(name: str) -> str | None:
    """The catalogue name the diagnosis should report for scenario ``name`` (None for
    ``clean`` and for an effect outside the catalogue)."""
    effect = HIDDEN[name]
    return None if effect is None else effect.name


@functools.lru_cache(maxsize=32)
def _truth(name: str, exact: bool) -> tuple[tuple[NDArray, ...], NDArray, NDArray]:
    """Noise-free true junction temperatures: cooling curves, steady states, PWM readings."""
    effect = HIDDEN[name]
    device = [effect] if effect is not None and effect.kind == "device" else []
    window = WINDOW_S
    ladder = actuator()
    model = ThermalModel(ladder, tuple(device))
    curves, steady = [], []
    for p in COOLING_POWERS_W:
        tref = np.full(T_COOL_S.size, AMBIENT_C)
        if exact and device:

            tj = AMBIENT_C + cooling_rise_k(model, p, T_COOL_S, AMBIENT_C)
        else:
            c = CurveData("c", T_COOL_S, tref, tref, p, AMBIENT_C, None, False)
            tj = cooling_true_c(c, ladder, device)
        curves.append(tj)
        steady.append(AMBIENT_C + float(model.steady_nodes(p, AMBIENT_C)[0]))
    f, d = (np.array(x) for x in zip(*[(f, d) for d in DUTIES for f in FREQS_HZ], strict=True))
    if exact and device:
        pwm = np.array([AMBIENT_C + model.pwm(PWM_POWER_W, fi, di, window, AMBIENT_C).reading_k
                        for fi, di in zip(f, d, strict=True)])
    else:
        data = PwmData(f, d, np.full(f.size, PWM_POWER_W), np.full(f.size, AMBIENT_C),
                       np.zeros(f.size), window)
        pwm = pwm_true_c(data, ladder, device)
    return tuple(curves), np.array(steady), pwm


def scenario_bundle(name: str, seed: int = 0, *, noise_k: float = 0.02,
                    exact: bool = False) -> Bundle:
    """The bundle of scenario ``name`` (module docstring) with seeded noise ``noise_k`` (K,
    standard deviation, on every reading; the calibration voltages get the same in volts).

    >>> b = scenario_bundle("sample-window")
    >>> b.pwm.sample_window_s
    0.0
    """
    if name not in HIDDEN:
        raise DataFormatError(f"unknown scenario {name!r}; known: {', '.join(SCENARIOS)}")
    if not (np.isfinite(noise_k) and noise_k >= 0):
        raise DataFormatError(f"noise_k = {noise_k!r}: must be >= 0")

    rng = np.random.default_rng(seed)
    effect = HIDDEN[name]
    tsp = effect if name == "tsp-nonlinearity" else None
    transient = effect if name == "electrical-transient" else None
    curves, steady, pwm_true = _truth(name, exact)

    cooling = []
    for i, (p, tj, top) in enumerate(zip(COOLING_POWERS_W, curves, steady, strict=True)):
        true = tj.copy()
        if name == "ambient-drift" and i == 1:
            true = true + DRIFT_K * T_COOL_S / T_COOL_S[-1]
        read = tsp_reading(true, tsp) + transient_offset(T_COOL_S, transient)
        read = read + rng.normal(0.0, noise_k, read.size)
        top_read = float(tsp_reading(top, tsp)) + float(rng.normal(0.0, noise_k))
        cooling.append(CoolingTable(T_COOL_S, p, tj_c=np.round(read, 5),
                                    tj_steady_c=round(top_read, 5), tref_steady_c=AMBIENT_C,
                                    file=f"cooling_{i + 1}.csv"))
    f, d = (np.array(x) for x in zip(*[(f, d) for d in DUTIES for f in FREQS_HZ], strict=True))
    pwm_read = tsp_reading(pwm_true, tsp) + rng.normal(0.0, noise_k, pwm_true.size)
    declared = 0.0 if name == "sample-window" else WINDOW_S
    pwm = PwmTable(f, d, np.round(pwm_read, 5), power_w=PWM_POWER_W, sample_window_s=declared)

    q = tsp.params["quad_k_per_k2"] if tsp is not None else 0.0
    u = CAL_TEMPS_C - AMBIENT_C
    volts = V25_V + K_V_PER_K * (u + q * u * u)
    volts = volts + rng.normal(0.0, noise_k * abs(K_V_PER_K), volts.size)
    cal = CalibrationTable(CAL_TEMPS_C, np.round(volts, 7))
    return Bundle(device=f"synthetic actuator, scenario {name}, seed {seed}",
                  ambient_c=AMBIENT_C, calibration=cal, cooling=tuple(cooling), pwm=pwm,
                  extra={"scenario": {"name": name, "seed": seed, "noise_k": noise_k,
                                      "hidden": None if effect is None else effect.to_dict()}})
