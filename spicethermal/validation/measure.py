"""The bench: what a measurement of a :class:`~.network.Network` records, artefacts included.

:class:`Bench` says how the device is measured (powers, sampling, PWM grid, sample window,
noise, what the manifest declares) and which artefacts spoil the readings, each applied on its
own:

* **sample window**: PWM readings at the end of a power-off window or averaged over it
  (:mod:`.periodic`), while the manifest declares ``declared_window_s``;
* **electrical transient** (:class:`Transient`): cooling readings off by ``A e^{−t/τ}``, with
  ``A`` fixed, proportional to the power at cut-off, or as a damped ringing
  ``A e^{−t/τ} cos(2π f t)``;
* **TSP** (:class:`Tsp`): the sensor voltage ``V = V25 + K (u + q u² + c u³)``, ``u = T − 25``
  (``K`` < 0 for a diode, > 0 for a resistive sensor); the bench converts voltages through the
  least-squares line of its own (noisy) calibration points, so a nonlinear TSP bends every
  reading; ``volts`` stores raw voltages instead;
* **noise**: white, ``noise_k`` on every reading (``noise_k·|K|`` in volts);
* artefacts that are in no catalogue: the reference drifting during the cooling curves without
  a ``tref_c`` column (``drift_k_per_s``), a contact resistance added to the last layer from
  the second cooling curve on (``contact_k_per_w``: the device was remounted), a trigger delay
  (``time_offset_s``: a cooling reading recorded at ``t`` was taken at ``t + time_offset_s``),
  and an acquisition gain and offset error that the calibration, taken with another
  instrument, does not share (``adc_gain``, ``adc_offset_v``: ``V' = V (1 + gain) + offset``
  on every reading but the calibration's).

:func:`measure` returns a :class:`Record`: the bundle (``spicethermal-bundle/1``, built with
:class:`spicethermal.io.bundle.Bundle`) and the noise-free and measured readings in kelvin that
:mod:`.detect` needs.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..io.bundle import Bundle, CalibrationTable, CoolingTable, PwmTable
from .network import Network
from .periodic import pwm_reading, ripple_bound

__all__ = ["Bench", "Record", "Transient", "Tsp", "measure"]

FREQS_HZ = (500.0, 1e3, 3e3, 5e3, 10e3, 25e3)
DUTIES = (0.2, 0.5, 0.8)


@dataclass(frozen=True)
class Tsp:
    """Diode forward voltage ``V(T) = v25_v + k_v_per_k·(u + quad·u² + cubic·u³)``, u = T − 25 °C.

    >>> float(Tsp(0.65, -2e-3, quad=1e-3).volts(35.0))
    0.6298
    """

    v25_v: float = 0.65
    k_v_per_k: float = -2e-3
    quad: float = 0.0
    cubic: float = 0.0

    def volts(self, t_c):
        u = np.asarray(t_c, dtype=float) - 25.0
        return np.round(self.v25_v + self.k_v_per_k * (u + self.quad * u * u
                                                        + self.cubic * u ** 3), 15)


@dataclass(frozen=True)
class Transient:
    """Electrical transient on the cooling readings: ``kind`` ``"fixed"`` (``amplitude_k``),
    ``"power"`` (``amplitude_k`` per watt at cut-off) or ``"ringing"`` (``amplitude_k``,
    ``ring_hz``), decaying with ``tau_s``.

    >>> float(Transient("power", -0.1, 1e-5).offset_k(np.array([0.0]), 20.0)[0])
    -2.0
    """

    kind: str = "fixed"
    amplitude_k: float = 0.0
    tau_s: float = 2e-5
    ring_hz: float = 5e4

    def offset_k(self, t_s: np.ndarray, power_w: float) -> np.ndarray:
        a = self.amplitude_k * (power_w if self.kind == "power" else 1.0)
        out = a * np.exp(-t_s / self.tau_s)
        if self.kind == "ringing":
            out = out * np.cos(2 * math.pi * self.ring_hz * t_s)
        return out


@dataclass(frozen=True)
class Bench:
    """How a device is measured (module docstring). Powers in W, times in s, noise in K."""

    cooling_powers_w: tuple[float, ...]
    pwm_power_w: float
    reference: str = "ambient"
    tref_c: float = 25.0
    t_min_s: float = 1e-6
    t_max_s: float = 100.0
    per_decade: int = 10
    dense_pwm: bool = True
    window_s: float = 1e-4
    window_mode: str = "end"
    declared_window_s: float = 1e-4
    noise_k: float = 0.02
    steady: bool = True
    volts: bool = False
    tsp: Tsp = field(default_factory=Tsp)
    transient: Transient | None = None
    drift_k_per_s: float = 0.0
    contact_k_per_w: float = 0.0
    cal_step_k: float = 5.0
    freqs_hz: tuple[float, ...] = FREQS_HZ
    duties: tuple[float, ...] = DUTIES
    time_offset_s: float = 0.0
    adc_gain: float = 0.0
    adc_offset_v: float = 0.0

    def times(self) -> np.ndarray:
        """Cooling sample times: ``per_decade`` log-spaced samples per decade."""
        lo, hi = math.log10(self.t_min_s), math.log10(self.t_max_s)
        n = int(round((hi - lo) * self.per_decade)) + 1
        return np.logspace(lo, hi, n)

    def grid(self) -> tuple[np.ndarray, np.ndarray]:
        """PWM (frequency, duty) points, duty-major as the paper's Table 2; the sparse grid has
        every other frequency (from the second) at the lowest and highest duty.

        >>> [len(a) for a in Bench((1.0,), 1.0, dense_pwm=False).grid()]
        [6, 6]
        """
        freqs, duties = ((self.freqs_hz, self.duties) if self.dense_pwm
                         else (self.freqs_hz[1::2], (self.duties[0], self.duties[-1])))
        f = np.array([fi for _ in duties for fi in freqs])
        d = np.array([di for di in duties for _ in freqs])
        return f, d


@dataclass(frozen=True)
class Record:
    """One simulated measurement: ``bundle`` and, per data set (``cooling_1``, ...,
    ``steady``, ``pwm``, ``calibration``), the noise-free ``truth`` and ``measured`` readings
    in kelvin (calibration: voltage residuals in K about the bench's line), plus what a
    linear model needs to predict them (``inputs``)."""

    bundle: Bundle
    truth: dict[str, np.ndarray]
    measured: dict[str, np.ndarray]
    inputs: dict[str, object]


def _line(temp_c: np.ndarray, volts: np.ndarray) -> tuple[float, float]:
    """Least-squares calibration line ``V = a + b T``."""
    b, a = np.polyfit(temp_c, volts, 1)
    return float(a), float(b)


def measure(net: Network, bench: Bench, seed: int, device: str = "validation device",
            extra: dict | None = None) -> Record:
    """Simulate the bench on ``net`` (module docstring).

    Parameters
    ----------
    net : the device.
    bench : how it is measured, artefacts included.
    seed : seed of the noise (the same seed gives the same bundle).
    device, extra : the bundle's ``device`` text and extra ``bundle.json`` keys.

    Returns
    -------
    Record
        The bundle and the noise-free and measured readings in kelvin.

    Examples
    --------
    >>> from spicethermal.validation.network import Network
    >>> rec = measure(Network((10.0, 20.0), (1e-3, 0.1)), Bench((0.5,), 0.5, noise_k=0.0), 1)
    >>> round(float(rec.bundle.cooling[0].tj_steady_c), 6)
    40.0
    """
    rng = np.random.default_rng(seed)
    t = bench.times()
    tref = bench.tref_c
    curves, steadies = [], []
    for k, p in enumerate(bench.cooling_powers_w):
        nk = net
        if k >= 1 and bench.contact_k_per_w:
            r = list(net.r_k_per_w)
            r[-1] += bench.contact_k_per_w
            nk = net.with_(r_k_per_w=tuple(r))
        start = nk.steady(p, tref)
        cool = nk.cooling_branch(start)
        taken = t + bench.time_offset_s
        if cool.is_linear and not bench.drift_k_per_s:
            r_f, tau = cool.foster()
            tj = tref + p * (r_f[None, :] * np.exp(-taken[:, None] / tau[None, :])).sum(axis=1)
        else:
            _, path = cool.integrate(start, float(taken[-1]), 0.0, tref, t_eval=taken,
                                     tref_rate_k_per_s=bench.drift_k_per_s)
            tj = path[:, 0]
        curves.append(tj)
        steadies.append(float(start[0]))
    f, d = bench.grid()
    if any(ripple_bound(net, bench.pwm_power_w, f, d, h.node) > h.gap_k
           for h in net.hysteretic):
        raise ValueError("a band with hysteresis whose gap the PWM ripple exceeds: its "
                         "periodic state would exchange latent heat (not simulated)")
    pwm = np.array([pwm_reading(net, bench.pwm_power_w, fi, di, tref, bench.window_s,
                                bench.window_mode) for fi, di in zip(f, d, strict=True)])

    tsp = bench.tsp
    kv = abs(tsp.k_v_per_k)
    hottest = max(max(steadies), float(pwm.max()))
    cal_t = np.arange(20.0, max(60.0, hottest + 10.0) + 1e-9, bench.cal_step_k)
    cal_v = tsp.volts(cal_t) + rng.normal(0.0, bench.noise_k * kv, cal_t.size)
    a, b = _line(cal_t, cal_v)

    def read_k(true_c: np.ndarray, offset_k: np.ndarray | float = 0.0) -> tuple:
        """(noise-free, noisy) readings in K through the bench's line, and noisy volts."""
        v_true = tsp.volts(true_c) + tsp.k_v_per_k * np.asarray(offset_k)
        v_true = v_true * (1.0 + bench.adc_gain) + bench.adc_offset_v
        v_meas = v_true + rng.normal(0.0, bench.noise_k * kv, np.shape(true_c))
        return (v_true - a) / b, (v_meas - a) / b, v_meas

    truth: dict[str, np.ndarray] = {}
    measured: dict[str, np.ndarray] = {}
    cooling = []
    for k, (p, tj, top) in enumerate(zip(bench.cooling_powers_w, curves, steadies,
                                         strict=True)):
        name = f"cooling_{k + 1}"
        off = bench.transient.offset_k(t, p) if bench.transient is not None else 0.0
        truth[name], measured[name], volts = read_k(tj, off)
        s_true, s_meas, _ = read_k(np.array([top]))
        if bench.steady:
            truth[f"steady_{k + 1}"], measured[f"steady_{k + 1}"] = s_true, s_meas
        cols = {"v_tsp_v": np.round(volts, 8)} if bench.volts else {
            "tj_c": np.round(measured[name], 6)}
        cooling.append(CoolingTable(t, p, **cols, file=f"{name}.csv",
                                    tj_steady_c=round(float(s_meas[0]), 6) if bench.steady
                                    else None, tref_steady_c=tref))
    truth["pwm"], measured["pwm"], _ = read_k(pwm)
    pwm_table = PwmTable(f, d, np.round(measured["pwm"], 6), power_w=bench.pwm_power_w,
                         sample_window_s=bench.declared_window_s)
    truth["calibration"] = (tsp.volts(cal_t) - (a + b * cal_t)) / kv
    measured["calibration"] = (cal_v - (a + b * cal_t)) / kv
    bundle = Bundle(device=device, reference=bench.reference, ambient_c=tref,
                    calibration=CalibrationTable(cal_t, np.round(cal_v, 8)),
                    cooling=tuple(cooling), pwm=pwm_table, extra=dict(extra or {}))
    inputs = {"t_s": t, "powers_w": bench.cooling_powers_w, "freq_hz": f, "duty": d,
              "pwm_power_w": bench.pwm_power_w, "window_s": bench.declared_window_s,
              "tref_c": tref, "noise_k": bench.noise_k,
              "cal_temps_c": cal_t, "line_sign": float(np.sign(b))}
    return Record(bundle, truth, measured, inputs)
