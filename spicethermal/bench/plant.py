"""The simulated plant: the device's thermal network and the bench's analog front end.

:class:`Plant` holds the node temperature rises θ of the device's Cauer network (from
:meth:`spicethermal.core.ladder.Cauer.state_matrices`, ``C dθ/dt = −G θ + e0 P``) over its reference
(the ambient, or the calibration hot plate while that is on) and steps it exactly for
piecewise-constant power: in the eigenbasis of the symmetrised network every mode is a scalar
exponential, so a step of any length, and a block of N whole PWM periods, cost O(n) (the
matrix exponential in closed form, the periodic sum as a geometric series). Device effects
(any device plugin of :mod:`spicethermal.effects`, through its own physics: the factor on each
layer's resistance, the heat stored at each node) make the network depend on temperature;
they are applied with coefficients frozen over short chunks
(the driver keeps chunks below :attr:`Plant.max_chunk_s`), which the tests check against
:meth:`spicethermal.model.ThermalModel.simulate`.

:class:`Frontend` turns the plant's temperatures into the voltages at the ADC pins — the diode
TSP with its curvature, the electrical transient after a power cut (the hardware artefacts of
:data:`~spicethermal.bench.devices.ARTEFACTS`), noise — and quantizes them like the PIC's
10-bit ADC.

>>> from spicethermal.bench.devices import preset
>>> p = Plant(preset("actuator"), effects=())
>>> p.step(1e4, 0.1)   # ten thousand seconds at 0.1 W: the steady state
>>> round(p.tj_c - p.ambient_c(), 6)
14.6
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import TYPE_CHECKING

import numpy as np

from ..core.diode import K_OVER_Q, ZERO_C_K
from ..core.errors import InstrumentError
from ..core.ladder import Cauer
from .devices import CURVED_TSP, CUT_TRANSIENT

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

    from .devices import Preset

FIXTURE_TAU_S = 40.0          # calibration hot plate: first-order approach to its setpoint
AMBIENT_DRIFT_K = 0.03        # slow ambient drift amplitude ...
AMBIENT_DRIFT_PERIOD_S = 3600.0  # ... and period


class Plant:
    """Thermal state of the simulated device (see the module docstring).

    Parameters
    ----------
    preset : the device.
    effects : names of the enabled effects (only device effects matter here:
        :meth:`~spicethermal.bench.devices.Preset.device_effects`).
    """

    def __init__(self, preset: Preset, effects: Iterable[str] = ()) -> None:
        self.preset = preset
        cauer = preset.foster.to_cauer()
        if preset.heatsink is not None:
            cauer = Cauer(cauer.r + (preset.heatsink[0],), cauer.c + (preset.heatsink[1],))
        self.cauer = cauer
        self.c0, self.g0 = cauer.state_matrices()
        self.n = cauer.order
        self.device_effects = preset.device_effects(effects)
        self._reset()

    def _reset(self) -> None:
        """The state at the start: everything at the reference, the hot plate off."""
        self._rate_k_per_s = math.inf   # fastest node change of the last step (effects only)
        self._cache: dict = {}
        self.theta = np.zeros(self.n)
        self.t_s = 0.0
        self.fixture_c: float | None = None      # hot plate temperature while it is on
        self.fixture_set_c: float | None = None
        self._modal_cache: tuple | None = None

    # -- temperatures ------------------------------------------------------------------
    def ambient_c(self, t_s: float | None = None) -> float:
        t = self.t_s if t_s is None else t_s
        return self.preset.ambient_c + AMBIENT_DRIFT_K * math.sin(
            2 * math.pi * t / AMBIENT_DRIFT_PERIOD_S)

    @property
    def base_c(self) -> float:
        """Temperature of the network's reference node (hot plate while on, else ambient)."""
        return self.fixture_c if self.fixture_c is not None else self.ambient_c()

    @property
    def tj_c(self) -> float:
        return self.base_c + float(self.theta[0])

    @property
    def sensed_c(self) -> float:
        """What the TSP diode reads: the junction (an array plant reads the selected port)."""
        return self.tj_c

    @property
    def tref_c(self) -> float:
        """What the reference thermocouple touches: the ambient, or the case (heat sink)."""
        if self.preset.reference == "case":
            return self.base_c + float(self.theta[-1])
        return self.ambient_c()

    # -- fixture -----------------------------------------------------------------------
    def set_fixture(self, setpoint_c: float | None) -> None:
        """Put the device on the hot plate at ``setpoint_c`` or (None) take it off.

        Taking it off keeps the device's heat: its node rises are now over the ambient."""
        if setpoint_c is None:
            if self.fixture_c is not None:
                self.theta = self.theta + (self.fixture_c - self.ambient_c())
            self.fixture_c = self.fixture_set_c = None
            return
        if self.fixture_c is None:
            self.fixture_c = self.ambient_c()
        self.fixture_set_c = setpoint_c

    # -- stepping ----------------------------------------------------------------------
    @property
    def max_chunk_s(self) -> float:
        """Longest step the driver should take: 0.1 s for a linear plant; with device
        effects, short enough that no node moves more than ~0.02 K with frozen coefficients."""
        if not self.device_effects:
            return 0.1
        return min(0.5, max(1e-3, 0.02 / max(self._rate_k_per_s, 1e-9)))

    def drive_changed(self) -> None:
        """The heater drive changed abruptly: restart with short steps (device effects)."""
        self._rate_k_per_s = math.inf

    def _track(self, before: NDArray, dt: float) -> None:
        if self.device_effects:
            self._rate_k_per_s = float(np.max(np.abs(self.theta - before))) / dt

    def _modal(self) -> tuple[NDArray, NDArray, NDArray, NDArray]:
        """(λ, W, W⁻¹, q) with θ = W z and dz/dt = λ z + q P, for the current coefficients."""
        if not self.device_effects:
            if self._modal_cache is None:
                self._modal_cache = self._decompose(self.c0, self.g0)
            return self._modal_cache
        temps = self.base_c + self.theta
        key = tuple(np.round(temps / 0.01).astype(int))  # coefficients frozen per 10 mK
        hit = self._cache.get(key)
        if hit is not None:
            return hit
        ends = np.append(temps, self.base_c)  # layer k joins node k to node k + 1
        layers = 0.5 * (ends[:-1] + ends[1:])
        scales = np.ones(self.n)
        c = self.c0.copy()
        for e in self.device_effects:
            scales *= np.array(e.resistance_scales(layers, float(temps[0])))
            c += np.array(e.extra_capacities(temps, self.c0))
        g = self.g0 if np.all(scales == 1.0) else \
            Cauer(np.asarray(self.cauer.r) * scales, self.cauer.c).state_matrices()[1]
        if len(self._cache) > 20000:
            self._cache.clear()
        hit = self._cache[key] = self._decompose(c, g)
        return hit

    @staticmethod
    def _decompose(c: NDArray, g: NDArray) -> tuple[NDArray, NDArray, NDArray, NDArray]:
        s = 1 / np.sqrt(c)
        lam, u = np.linalg.eigh(s[:, None] * g * s[None, :])
        w = s[:, None] * u
        w_inv = u.T * np.sqrt(c)[None, :]
        q = w_inv @ (np.eye(len(c))[0] / c)
        return -lam, w, w_inv, q

    def _advance_fixture(self, dt: float) -> None:
        if self.fixture_c is not None and self.fixture_set_c is not None:
            self.fixture_c = self.fixture_set_c + (self.fixture_c - self.fixture_set_c) * math.exp(
                -dt / FIXTURE_TAU_S)

    def step(self, dt: float, power_w: float, track: bool = True) -> None:
        """Advance ``dt`` seconds at constant heater power (``track``: judge the step length
        for device effects on this step; off for the phases inside a PWM period)."""
        if dt <= 0:
            return
        lam, w, w_inv, q = self._modal()
        before = self.theta
        z = w_inv @ self.theta
        z = np.exp(lam * dt) * z + np.expm1(lam * dt) / lam * q * power_w
        self.theta = w @ z
        if track:
            self._track(before, dt)
        self.t_s += dt
        self._advance_fixture(dt)

    def heat(self, duration_s: float, power_w: float) -> None:
        """Advance ``duration_s`` at constant power in chunks of at most :attr:`max_chunk_s`
        (so device effects follow the temperature)."""
        n = max(1, math.ceil(duration_s / self.max_chunk_s))
        for _ in range(n):
            self.step(duration_s / n, power_w)

    def step_periods(self, periods: int, period_s: float, on_s: float, power_w: float) -> None:
        """Advance ``periods`` whole PWM periods, each an on-phase of ``on_s`` then off."""
        if periods <= 0:
            return
        lam, w, w_inv, q = self._modal()
        z = w_inv @ self.theta
        a_off = np.exp(lam * (period_s - on_s))
        b = a_off * np.expm1(lam * on_s) / lam * q * power_w
        geometric = np.expm1(lam * period_s * periods) / np.expm1(lam * period_s)
        z = np.exp(lam * period_s * periods) * z + b * geometric
        before = self.theta
        self.theta = w @ z
        self._track(before, periods * period_s)
        self.t_s += periods * period_s
        self._advance_fixture(periods * period_s)


class Frontend:
    """Analog front end and ADC of the bench: temperatures → pin voltages → 10-bit codes.

    Parameters
    ----------
    preset : the device and its board.
    artefacts : the front end's artefacts switched on (of
        :data:`~spicethermal.bench.devices.ARTEFACTS`; the TSP's curvature and the transient
        after the cut matter here).
    noise_k : standard deviation of the TSP reading noise, expressed in kelvin.
    rng : the random generator (seeded by the URL's ``seed``).
    """

    def __init__(self, preset: Preset, artefacts: Iterable[str], noise_k: float,
                 rng: np.random.Generator) -> None:
        if not (math.isfinite(noise_k) and noise_k >= 0):
            raise InstrumentError(f"noise = {noise_k!r}: must be >= 0 (kelvin)")
        self.preset = preset
        on = set(artefacts)
        self.curved_tsp = CURVED_TSP in on
        self.cut_transient = CUT_TRANSIENT in on
        self.noise_k = noise_k
        self.rng = rng

    def v_forward(self, t_c: float) -> float:
        """TSP diode forward voltage at the bias current."""
        d = self.preset.diode
        x = t_c - 25.0
        return d.v25 + d.slope_v_per_k * x + (d.quad_v_per_k2 * x * x if self.curved_tsp else 0.0)

    def v_diode(self, i_a: float, t_c: float) -> float:
        """Heater diode voltage at current ``i_a`` (the heating current, a forward-voltage
        pulse): the TSP's law at the bias current carried to ``i_a`` by the diode law."""
        d = self.preset.diode
        n_vt = d.n * K_OVER_Q * (t_c + ZERO_C_K)
        return self.v_forward(t_c) + n_vt * math.log(max(i_a, 1e-12) / d.i_bias_a) + \
            d.rs_ohm * (i_a - d.i_bias_a)

    @staticmethod
    def code(v: float) -> int:
        """Ideal 10-bit ADC over 0..5 V, rounding to the nearest code."""
        return int(min(1023, max(0, math.floor(v / 5.0 * 1024 + 0.5))))

    def codes(self, *, tj_c: float, tj_tsp_c: float, ambient_c: float, tref_c: float,
              taux_c: float, heater_on: bool, current_a: float,
              since_cut_s: float | None) -> list[int]:
        """ADC codes of the five channels (st_proto.h order) for one conversion.

        ``tj_tsp_c`` is the junction temperature the TSP channel sees (held at the window
        start when the bench has an ideal track-and-hold); the reference diode sits on the board
        at ``ambient_c``; ``tref_c`` is what the reference thermocouple touches, ``taux_c`` the
        auxiliary one; ``since_cut_s`` the time since the last power cut-off (the electrical
        transient), None if long ago.
        """
        b, d = self.preset.board, self.preset.diode
        noise_v = self.noise_k * abs(d.slope_v_per_k)
        gauss = self.rng.normal
        if heater_on:
            vd = self.v_diode(current_a, tj_c)
            tsp_pin = 0.0  # the INA saturates low while the heating current flows
            i = current_a
        else:
            vd = self.v_forward(tj_tsp_c)
            if self.cut_transient and since_cut_s is not None and \
                    since_cut_s < 50 * self.preset.transient_tau_s:
                vd += self.preset.transient_v * math.exp(-since_cut_s /
                                                          self.preset.transient_tau_s)
            vd += gauss(0.0, noise_v) if noise_v else 0.0
            tsp_pin = b.tsp_offset_v - b.tsp_gain * (vd - self.v_forward(ambient_c))
            i = d.i_bias_a
        return [
            self.code(tsp_pin),
            self.code(vd + gauss(0.0, 2.5e-3)),
            self.code(i * b.i_sense_v_per_a + gauss(0.0, 2.5e-3)),
            self.code(b.tamb_offset_v + b.tamb_v_per_k * (tref_c + gauss(0.0, 0.01))),
            self.code(b.taux_offset_v + b.taux_v_per_k * (taux_c + gauss(0.0, 0.05))),
        ]
