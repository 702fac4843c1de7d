"""Synthetic measurement bundles with one hidden effect each, for the tests (the package's own
forward model: self-consistency; the independent check is :mod:`spicethermal.validation`).

:func:`scenario_bundle` records what the paper's bench would record from a known actuator
(:data:`ACTUATOR_R`, :data:`ACTUATOR_TAU`: Rth = 146 K/W, τ from 100 µs to 30 s) with one effect
at a realistic strength, plus white noise: a TSP calibration (20…100 °C every 5 K), two cooling
curves (0.12 W and 0.30 W; 10 readings per decade from 1 µs to 100 s; the steady reading before
the cut) and the paper's 18-point PWM grid at 0.10 W read after a 100 µs sample window.

Scenarios (:data:`HIDDEN`): ``clean`` and one per catalogued effect, plus ``ambient-drift``,
physics outside the catalogue (the ambient warms by 1 K over the second curve, unrecorded).
"""

from __future__ import annotations

import functools
from dataclasses import replace

import numpy as np

from spicethermal.core.ladder import Foster
from spicethermal.effects import Effect
from spicethermal.fit.forward import predict_model
from spicethermal.fit.measurement import BundleData
from spicethermal.io.bundle import Bundle, CalibrationTable, CoolingTable, PwmTable

ACTUATOR_R = (6.0, 20.0, 50.0, 70.0)
ACTUATOR_TAU = (1e-4, 5e-3, 0.4, 30.0)
AMBIENT_C = 25.0
COOLING_POWERS_W = (0.12, 0.30)
PWM_POWER_W = 0.10
FREQS_HZ = (500.0, 1e3, 3e3, 5e3, 10e3, 25e3)
DUTIES = (0.2, 0.5, 0.8)
WINDOW_S = 1e-4
T_COOL_S = 10.0 ** (np.arange(-60, 21) / 10)
CAL_TEMPS_C = np.arange(20.0, 100.1, 5.0)
V25_V, K_V_PER_K = 0.650, -2.0e-3
DRIFT_K = 1.0


@functools.cache
def hidden() -> dict[str, Effect | None]:
    """The hidden effect of each scenario (None: none, or one outside the catalogue)."""
    return {
        "clean": None,
        "temperature-coefficient": Effect.create("temperature-coefficient", alpha_per_k=-3e-3,
                                                 t0_c=AMBIENT_C),
        "phase-change": Effect.create("phase-change", latent_j=0.02, t_c=64.7, width_k=1.5),
        "sample-window": Effect.create("sample-window", window_s=WINDOW_S),
        "electrical-transient": Effect.create("electrical-transient", amplitude_k=-5.0,
                                              masked_s=1e-4),
        "tsp-nonlinearity": Effect.create("tsp-nonlinearity", quad_k_per_k2=4e-4,
                                          t_cal_c=AMBIENT_C),
        "ambient-drift": None,
    }


def actuator() -> Foster:
    """The scenarios' actuator ladder."""
    return Foster.from_tau(ACTUATOR_R, ACTUATOR_TAU)


def scenario_bundle(name: str, seed: int = 0, noise_k: float = 0.02,
                    effect: Effect | None = None) -> Bundle:
    """The bundle of scenario ``name`` with seeded white noise ``noise_k`` (K) on every reading
    (the calibration voltages get the same in volts); ``effect`` replaces the scenario's
    hidden effect."""
    effect = effect or hidden()[name]
    rng = np.random.default_rng(seed)
    f, d = (np.array(x) for x in zip(*[(f, d) for d in DUTIES for f in FREQS_HZ], strict=True))
    declared = 0.0 if effect is not None and effect.plugin.traits.shown_by == {"pwm"} \
        else WINDOW_S
    q = effect.params["quad_k_per_k2"] if effect is not None and "quad_k_per_k2" in \
        effect.params else 0.0
    u = CAL_TEMPS_C - AMBIENT_C
    volts = V25_V + K_V_PER_K * (u + q * u * u)
    volts = volts + rng.normal(0.0, noise_k * abs(K_V_PER_K), volts.size)
    cal = CalibrationTable(CAL_TEMPS_C, np.round(volts, 7))
    skeleton = Bundle(ambient_c=AMBIENT_C, calibration=cal, cooling=tuple(
        CoolingTable(T_COOL_S, p, tj_c=np.zeros(T_COOL_S.size), tj_steady_c=0.0,
                     tref_steady_c=AMBIENT_C) for p in COOLING_POWERS_W),
        pwm=PwmTable(f, d, np.zeros(f.size), power_w=PWM_POWER_W, sample_window_s=WINDOW_S))
    data = BundleData.from_bundle(skeleton)
    pred = predict_model(data, actuator(), [effect] if effect is not None else [])
    cooling = []
    for i, p in enumerate(COOLING_POWERS_W):
        read = pred[f"cooling_{i + 1}"]
        if name == "ambient-drift" and i == 1:
            read = read + DRIFT_K * T_COOL_S / T_COOL_S[-1]
        read = read + rng.normal(0.0, noise_k, read.size)
        top = float(pred["steady"][i]) + float(rng.normal(0.0, noise_k))
        cooling.append(CoolingTable(T_COOL_S, p, tj_c=np.round(read, 5),
                                    tj_steady_c=round(top, 5), tref_steady_c=AMBIENT_C,
                                    file=f"cooling_{i + 1}.csv"))
    pwm = pred["pwm"] + rng.normal(0.0, noise_k, f.size)
    return replace(skeleton, device=f"synthetic actuator, scenario {name}, seed {seed}",
                   cooling=tuple(cooling),
                   pwm=PwmTable(f, d, np.round(pwm, 5), power_w=PWM_POWER_W,
                                sample_window_s=declared))
