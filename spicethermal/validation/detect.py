"""Is a case detectable at all? The exact truth against the best linear ladder on its own data.

A diagnosis can only be asked to name an effect that leaves a trace a linear ladder cannot
absorb. :func:`detectability` fits the best linear Foster ladder (orders 2 to 5, several
starts, every ``r`` and ``τ`` free and positive) to every reading of a
:class:`~.measure.Record` in kelvin at once — cooling curves ``T = Tref + P Σ r e^{−t/τ}``,
steady readings ``Tref + P Σ r``, PWM readings in the periodic steady state read at the end of
the *declared* sample window — read through the calibration line, whose error the fit takes
with the ladder: the bench's least-squares line is off by what its noisy calibration points
put into it, an offset and a slope that every reading shares and that the calibration's own
points bound (as every diagnosis fits them; the truth is read through that same line). The
truth is the noise-free reading. Per data set
``gain = RMS(linear) / RMS(truth)``; with ``σ`` the bench noise,
``Δχ² = (RSS_linear − RSS_truth)/σ²``.

A case is **detectable** when some data set of at least :data:`MIN_POINTS` points has
``gain ≥`` :data:`MIN_GAIN` (the truth is clearly better where it matters) and
``Δχ² ≥`` :data:`MIN_CHI2` overall (the gain is not luck).

>>> from spicethermal.validation.cases import catalogue
>>> clean = next(c for c in catalogue() if c.family == "clean")
>>> d = detectability(clean.record())
>>> d.detectable, round(d.max_gain, 1) < 1.2
(False, True)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from .measure import Record

__all__ = ["MIN_CHI2", "MIN_GAIN", "MIN_POINTS", "Detectability", "detectability",
           "linear_fit"]

MIN_GAIN = 1.5
MIN_CHI2 = 25.0
MIN_POINTS = 5
ORDERS = (2, 3, 4, 5)


@dataclass(frozen=True)
class Detectability:
    """Outcome of :func:`detectability`: RMS per data set (K) of the best linear ladder and of
    the truth, the gains, ``Δχ²`` and the verdict."""

    rms_linear: dict[str, float]
    rms_truth: dict[str, float]
    delta_chi2: float
    detectable: bool
    order: int

    @property
    def gains(self) -> dict[str, float]:
        return {k: self.rms_linear[k] / max(self.rms_truth[k], 1e-12) for k in self.rms_linear}

    @property
    def max_gain(self) -> float:
        return max(self.gains.values())

    def to_json(self) -> dict:
        return {"detectable": self.detectable, "delta_chi2": round(self.delta_chi2, 2),
                "order": self.order, "max_gain": round(self.max_gain, 3),
                "rms_linear_k": {k: round(v, 5) for k, v in self.rms_linear.items()},
                "rms_truth_k": {k: round(v, 5) for k, v in self.rms_truth.items()}}


def _groups(record: Record) -> dict[str, list[str]]:
    """Data sets as counted: the steady readings of all curves form one set."""
    keys = [k for k in record.measured if k != "calibration"]
    groups: dict[str, list[str]] = {}
    for k in keys:
        groups.setdefault("steady" if k.startswith("steady_") else k, []).append(k)
    return groups


def _predict(x: np.ndarray, record: Record) -> dict[str, np.ndarray]:
    """Linear-ladder readings (°C) of every data set, ``x`` = log r, log τ, then the line's
    error at the calibration's centre (K) and its slope (K/K): the calibration's are its
    residuals about the bench's line."""
    m = (x.size - 2) // 2
    r, tau = np.exp(x[:m]), np.exp(x[m:2 * m])
    inp = record.inputs
    cal_t = inp["cal_temps_c"]
    centre = float(np.mean(cal_t))

    def error(temp_c: np.ndarray) -> np.ndarray:  # of a reading, through the line, at temp_c
        return x[-2] + x[-1] * (temp_c - centre)

    tref, t = inp["tref_c"], inp["t_s"]
    out: dict[str, np.ndarray] = {}
    decay = np.exp(-t[:, None] / tau[None, :]) @ r
    for k, p in enumerate(inp["powers_w"]):
        out[f"cooling_{k + 1}"] = tref + p * decay
        out[f"steady_{k + 1}"] = np.array([tref + p * r.sum()])
    f, d = inp["freq_hz"][:, None], inp["duty"][:, None]
    period = 1.0 / f
    peak = r * -np.expm1(-d * period / tau) / -np.expm1(-period / tau)
    out["pwm"] = tref + inp["pwm_power_w"] * (peak * np.exp(-inp["window_s"] / tau)).sum(axis=1)
    out = {k: v + error(v) for k, v in out.items() if k in record.measured}
    out["calibration"] = inp["line_sign"] * error(cal_t)
    return out


def linear_fit(record: Record) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
    """Best linear Foster ladder of every reading of ``record``, with the calibration line's
    error (module docstring).

    Returns
    -------
    tuple
        ``(r, τ, predictions)``: the stages with the lowest sum of squares over orders
        :data:`ORDERS` and log-spaced starts, and the readings they predict per data set
        (the calibration's: its residuals about the bench's line).
    """
    keys = list(record.measured)
    y = np.concatenate([record.measured[k] for k in keys])
    inp = record.inputs
    rise = max(float(np.max(record.measured[k]) - inp["tref_c"]) for k in keys
               if k != "calibration")
    rth0 = rise / max(max(inp["powers_w"]), inp["pwm_power_w"])
    t = inp["t_s"]

    def resid(x: np.ndarray) -> np.ndarray:
        pred = _predict(x, record)
        return np.concatenate([pred[k] for k in keys]) - y

    best: tuple[float, np.ndarray] | None = None
    lo, hi = np.log(t[0]), np.log(t[-1])
    for m in ORDERS:
        for shift in (0.0, 0.5):
            tau0 = np.linspace(lo + 1.0, hi - 0.5, m) + shift
            x0 = np.concatenate([np.full(m, np.log(rth0 / m)), tau0, [0.0, 0.0]])
            low = np.concatenate([np.full(m, np.log(rth0) - 30.0), np.full(m, lo - 6.0),
                                  [-np.inf, -np.inf]])
            high = np.concatenate([np.full(m, np.log(rth0) + 5.0), np.full(m, hi + 6.0),
                                   [np.inf, np.inf]])
            sol = least_squares(resid, np.clip(x0, low + 1e-9, high - 1e-9), bounds=(low, high),
                                method="trf", max_nfev=400 * m)
            cost = float(np.sum(sol.fun ** 2))
            if best is None or cost < best[0] * (1 - 1e-9):
                best = (cost, sol.x)
    assert best is not None
    x = best[1]
    m = (x.size - 2) // 2
    return np.exp(x[:m]), np.exp(x[m:2 * m]), _predict(x, record)


def _rms(x: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(x))))


def detectability(record: Record) -> Detectability:
    """Detectability of the case behind ``record`` (module docstring).

    Parameters
    ----------
    record : a simulated measurement (:func:`~.measure.measure`).

    Returns
    -------
    Detectability
        RMS of the best linear ladder and of the truth per data set, ``Δχ²``, the mark.
    """
    r, _, pred = linear_fit(record)
    lin, tru = {}, {}
    rss_lin = rss_tru = 0.0
    for name, keys in _groups(record).items():
        meas = np.concatenate([record.measured[k] for k in keys])
        res_l = meas - np.concatenate([pred[k] for k in keys])
        res_t = meas - np.concatenate([record.truth[k] for k in keys])
        lin[name], tru[name] = _rms(res_l), _rms(res_t)
        rss_lin += float(res_l @ res_l)
        rss_tru += float(res_t @ res_t)
    cal_l = record.measured["calibration"] - pred["calibration"]
    cal_t = record.measured["calibration"] - record.truth["calibration"]
    lin["calibration"], tru["calibration"] = _rms(cal_l), _rms(cal_t)
    rss_lin += float(cal_l @ cal_l)
    rss_tru += float(cal_t @ cal_t)
    sigma = record.inputs["noise_k"]
    chi2 = (rss_lin - rss_tru) / sigma ** 2
    sizes = {name: sum(record.measured[k].size for k in keys)
             for name, keys in _groups(record).items()}
    sizes["calibration"] = record.measured["calibration"].size
    gain_ok = any(lin[k] / max(tru[k], 1e-12) >= MIN_GAIN and sizes[k] >= MIN_POINTS
                  for k in lin)
    return Detectability(lin, tru, chi2, bool(gain_ok and chi2 >= MIN_CHI2), r.size)
