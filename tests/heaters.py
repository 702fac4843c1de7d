"""A heater diode for the tests: the simulated bench's (1N4148-like, its TSP at 1 mA
0.6 V − 2 mV/K (T − 25 °C)) on the simulated actuator's ladder, and the points the bench would
take of it."""

from __future__ import annotations

import numpy as np

from spicethermal.core.diode import DiodeLaw
from spicethermal.core.ladder import Foster
from spicethermal.model import ThermalModel

#: The simulated actuator's ladder and a 1N4148-like heater whose TSP at 1 mA is
#: 0.6 V − 2 mV/K (T − 25 °C), as the simulated bench's.
MODEL = ThermalModel(Foster.from_tau([6.0, 20.0, 50.0, 70.0], [2e-4, 5e-3, 0.4, 12.0]))
K_Q, T0K = 8.617333262e-5, 298.15


def heater(n: float = 1.75, rs: float = 0.57) -> DiodeLaw:
    a = n * K_Q
    eg = 0.6 - rs * 1e-3 + 2e-3 * T0K
    b = -2e-3 - a * np.log(1e-3)
    return DiodeLaw(n=n, is_a=float(np.exp(-(b + eg / T0K) / a)), rs_ohm=rs, xti=0.0,
                    eg_ev=eg, sense_current_a=1e-3)


def bench_points(seed: int = 1, noise_v: float = 0.6e-3, cal_noise_v: float = 1e-5):
    """Forward points as the bench takes them (pulsed, self-heated by the pulse) and the TSP
    calibration (the junction under the sense current, against a 0.6 V reference diode)."""
    rng = np.random.default_rng(seed)
    law = heater()
    temps = np.array([25.0, 35.0, 45.0, 55.0, 65.0, 75.0])
    t, i = (x.ravel() for x in np.meshgrid(temps, [5e-3, 2e-2, 5e-2, 0.12, 0.35]))
    tp = np.full(t.size, 2e-5)
    tj = t + i * law.voltage(i, t) * MODEL.ladder.zth(tp)
    v = law.voltage(i, tj) + rng.normal(0, noise_v, t.size)
    cal = law.voltage(1e-3, temps) - 0.6 + rng.normal(0, cal_noise_v, temps.size)
    return law, temps, (t, i, v, tp), cal


