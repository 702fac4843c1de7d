"""The measurement plan of a bench run: what to measure and how, one preset per known board.

A :class:`Plan` holds the calibration temperatures (and the currents of the forward-voltage
pulses taken at each), the powers and settling times, the cooling-curve sampling and the PWM
grid (SI units), checked when it is made; :data:`PLANS`
holds the presets, chosen by the board name the device reports
(:class:`spicethermal.bench.session.Session`). Every value can be overridden.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..core.errors import DataFormatError


@dataclass(frozen=True)
class Plan:
    """What to measure and how (SI units). :data:`PLANS` holds one per known board."""

    description: str = "heated device"
    reference: str = "ambient"
    calibration_c: tuple[float, ...] = (25.0, 35.0, 45.0, 55.0, 65.0, 75.0)
    calibration_settle_s: float = 300.0
    calibration_n: int = 32
    calibration_interval_s: float = 0.1
    #: Forward voltage at each calibration temperature (firmware 1.2): pulses at these currents
    #: (none: not measured), each read in its middle, ``forward_n`` per current.
    forward_currents_a: tuple[float, ...] = ()
    forward_pulse_s: float = 40e-6
    forward_n: int = 8
    forward_interval_s: float = 0.02
    forward_settle_s: float = 2.0
    window_s: float = 1e-4
    n_readings: int = 16
    rth_power_w: float = 0.094
    settle_s: float = 120.0
    cooling_powers_w: tuple[float, ...] = (0.094, 0.3)
    cooling_t_first_s: float = 1e-4
    cooling_t_last_s: float = 60.0
    per_decade: int = 10
    pwm_power_w: float = 0.094
    pwm_freqs_hz: tuple[float, ...] = (500.0, 1000.0, 3000.0, 5000.0, 10000.0, 25000.0)
    pwm_duties: tuple[float, ...] = (0.2, 0.5, 0.8)
    pwm_settle_s: float = 90.0
    pwm_n: int = 8
    pwm_interval_s: float = 0.1
    #: array boards ("heat one, read all", each heater at this power); the grid and pitch of
    #: the cells (rows 0: from the board's heaters, a Braille cell for 6 or 8)
    coupling_power_w: float = 0.25
    array_rows: int = 0
    array_cols: int = 0
    array_pitch_mm: float = 2.5

    def __post_init__(self) -> None:
        for name in ("calibration_settle_s", "calibration_interval_s", "window_s",
                     "rth_power_w", "settle_s", "cooling_t_first_s", "cooling_t_last_s",
                     "pwm_power_w", "pwm_settle_s", "pwm_interval_s", "forward_pulse_s",
                     "forward_interval_s", "forward_settle_s", "coupling_power_w",
                     "array_pitch_mm"):
            v = getattr(self, name)
            if not (isinstance(v, int | float) and np.isfinite(v) and v > 0):
                raise DataFormatError(f"bench plan: {name} = {v!r} must be a positive number")
        if not 1e-5 <= self.window_s <= 4e-3:
            raise DataFormatError(f"bench plan: window_s = {self.window_s!r} must lie in "
                                  f"10 us .. 4 ms")
        if any(not 0 < d <= 1 for d in self.pwm_duties):
            raise DataFormatError(f"bench plan: pwm duties {self.pwm_duties} must lie in (0, 1]")
        if any(p_ <= 0 for p_ in self.cooling_powers_w + self.pwm_freqs_hz):
            raise DataFormatError("bench plan: powers and frequencies must be positive")
        if self.reference not in ("ambient", "case"):
            raise DataFormatError(f"bench plan: reference {self.reference!r}: ambient or case")
        if self.cooling_t_last_s <= self.cooling_t_first_s:
            raise DataFormatError("bench plan: cooling_t_last_s must exceed cooling_t_first_s")
        if len(self.forward_currents_a) > 8 or any(
                not (isinstance(i, int | float) and 0 < i < 4000) for i in self.forward_currents_a):
            raise DataFormatError(f"bench plan: forward_currents_a {self.forward_currents_a} "
                                  "must be at most 8 currents in (0, 4000) A")
        if not 1e-5 <= self.forward_pulse_s <= 4e-3 or self.forward_n < 1:
            raise DataFormatError("bench plan: forward_pulse_s must lie in 10 us .. 4 ms and "
                                  "forward_n be at least 1")


PLANS: dict[str, Plan] = {
    "actuator": Plan(description="thermopneumatic actuator, diode heater (paper, sections 2, 7)",
                     forward_currents_a=(5e-3, 20e-3, 50e-3, 0.12, 0.35)),
    "array": Plan(description="actuator array", settle_s=300.0, cooling_t_last_s=300.0,
                  n_readings=4),
    "mur880e": Plan(description="MUR880E power diode on a heat sink, junction to case "
                    "(paper, section 5)", reference="case",
                    calibration_c=(25.0, 35.0, 45.0, 55.0, 65.0, 75.0), rth_power_w=10.0,
                    cooling_powers_w=(10.0, 20.0), cooling_t_last_s=20.0, pwm_power_w=10.0,
                    settle_s=300.0, pwm_settle_s=120.0,
                    forward_currents_a=(0.1, 0.5, 2.0, 5.0, 12.0, 20.0)),
}
