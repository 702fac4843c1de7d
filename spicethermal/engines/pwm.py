"""Analytic response of a linear ladder to a rectangular power train (PWM).

A train of amplitude P, frequency f and duty D switches power on for ``D/f`` then off for
``(1-D)/f``. Each Foster stage is a first-order system, so every quantity has a closed form:

* periodic steady state of stage i at the end of an on-phase (its peak)
  ``θi = P ri (1 - e^{-DT/τi}) / (1 - e^{-T/τi})``, and at the end of an off-phase
  ``θi e^{-(1-D)T/τi}``; the junction is the sum;
* the bench *reading* (DESIGN.md): power stays off for a sample window ``w`` starting when an
  on-phase ends, so the reading is ``Σ θi e^{-w/τi}`` (``w = 0`` reads the peak);
* the envelope from a cold start after k periods: the same peak times ``1 - e^{-kT/τi}``.

The duty-cycle impedance family of the paper's Fig. 8 comes in two forms: eq. 3,
``r_D(t) = D + (1 - D) r(t)`` (conservative), and the exact single-train form, the
periodic-steady-state peak per watt for pulses of width t at duty D.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..core.errors import DataFormatError
from ..io.jsondoc import JsonDocument

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import ArrayLike, NDArray

    from ..core.ladder import Cauer, Foster


def check_drive(freq_hz: float, duty: float, power_w: float | None = None,
                window_s: float = 0.0) -> None:
    """Validate PWM parameters, raising :class:`DataFormatError` that names the bad one."""
    if not (np.isfinite(freq_hz) and freq_hz > 0):
        raise DataFormatError(f"freq_hz = {freq_hz!r}: must be positive and finite")
    if not (np.isfinite(duty) and 0 <= duty <= 1):
        raise DataFormatError(f"duty = {duty!r}: must lie in [0, 1]")
    if power_w is not None and not (np.isfinite(power_w) and power_w >= 0):
        raise DataFormatError(f"power_w = {power_w!r}: must be non-negative and finite")
    if not (np.isfinite(window_s) and window_s >= 0):
        raise DataFormatError(f"window_s = {window_s!r}: must be non-negative and finite")


def _stages(ladder: Foster | Cauer) -> tuple[NDArray, NDArray]:
    f = ladder._foster()
    return np.asarray(f.r), np.asarray(f.tau)


def stage_peaks(r: NDArray, tau: NDArray, period: float, duty: NDArray | float) -> NDArray:
    """Per-stage rise per watt at the end of the on-phase, periodic steady state.

    ``ri (1 - e^{-D T/τi}) / (1 - e^{-T/τi})`` for Foster stages ``r``, ``tau``; arrays
    broadcast (a column of duties against the stages gives one row per duty).

    Parameters
    ----------
    r, tau : NDArray
        Foster stages: resistances (K/W) and time constants (s).
    period : float
        PWM period, s.
    duty : NDArray or float
        Duty cycle(s), 0..1.

    Returns
    -------
    NDArray
        Peak rise of each stage per watt of amplitude, K/W.

    Examples
    --------
    >>> stage_peaks(np.array([2.0]), np.array([1.0]), 1e-6, 0.25).round(6)  # fast: D·r
    array([0.5])
    """
    on = -np.expm1(-duty * period / tau)
    whole = -np.expm1(-period / tau)
    return r * on / whole


@dataclass(frozen=True)
class PwmState(JsonDocument):
    """Periodic steady state of a ladder under PWM. Temperatures are rises in K over the reference.

    >>> from spicethermal.core.ladder import Foster
    >>> s = steady_state(Foster.from_tau([10.0], [1.0]), 2.0, 1.0, 0.5)
    >>> round(s.mean_k, 12)
    10.0
    """

    freq_hz: float
    duty: float
    power_w: float
    window_s: float
    peak_k: float
    mean_k: float
    valley_k: float
    reading_k: float

    def to_dict(self) -> dict[str, float]:
        """The ``spicethermal pwm --json`` document.

        Returns
        -------
        dict
            ``peak_k``, ``mean_k``, ``valley_k`` and ``reading_k``.
        """
        return {"peak_k": self.peak_k, "mean_k": self.mean_k, "valley_k": self.valley_k,
                "reading_k": self.reading_k}

    #: Deprecated spelling of :meth:`to_dict` (kept for existing callers).
    as_json = to_dict


def steady_state(ladder: Foster | Cauer, power_w: float, freq_hz: float, duty: float,
                 window_s: float = 0.0) -> PwmState:
    """Peak, mean, valley and bench reading of the periodic steady state.

    Parameters
    ----------
    ladder : Foster or Cauer
    power_w : float
        Power amplitude during the on-phase, W.
    freq_hz, duty : float
        PWM frequency and duty cycle (0..1).
    window_s : float
        Sample window (power off) that starts when an on-phase ends; the reading is the
        junction rise at its end. 0 reads the peak.

    Returns
    -------
    PwmState
        Peak, mean, valley and reading, K above the reference.

    Examples
    --------
    >>> from spicethermal.core.ladder import Foster
    >>> s = steady_state(Foster.from_tau([10.0], [1e-3]), 1.0, 1e6, 0.5)
    >>> round(s.peak_k, 2), round(s.valley_k, 2)   # 1 MHz on 1 ms: the ripple is 2 mK
    (5.0, 5.0)
    """
    check_drive(freq_hz, duty, power_w, window_s)
    r, tau = _stages(ladder)
    period = 1.0 / freq_hz
    peaks = power_w * stage_peaks(r, tau, period, duty)
    return PwmState(
        freq_hz=float(freq_hz), duty=float(duty), power_w=float(power_w), window_s=float(window_s),
        peak_k=float(peaks.sum()),
        mean_k=float(power_w * duty * r.sum()),
        valley_k=float((peaks * np.exp(-(1 - duty) * period / tau)).sum()),
        reading_k=float((peaks * np.exp(-window_s / tau)).sum()),
    )


def at_phase(ladder: Foster | Cauer, power_w: float, freq_hz: float, duty: float,
             phase_s: ArrayLike) -> NDArray:
    """Junction rise (K) in the periodic steady state at times ``phase_s`` into a period.

    A period starts when power switches on. Phases are taken modulo the period.

    >>> from spicethermal.core.ladder import Foster
    >>> f = Foster.from_tau([10.0], [1e-3])
    >>> peak = steady_state(f, 1.0, 100.0, 0.5).peak_k
    >>> bool(np.isclose(at_phase(f, 1.0, 100.0, 0.5, 0.005), peak))
    True
    """
    check_drive(freq_hz, duty, power_w)
    r, tau = _stages(ladder)
    period = 1.0 / freq_hz
    on = duty * period
    peaks = stage_peaks(r, tau, period, duty)
    valleys = peaks * np.exp(-(period - on) / tau)
    ph = np.mod(np.asarray(phase_s, dtype=float), period)[..., None]
    heating = r + (valleys - r) * np.exp(-ph / tau)
    cooling = peaks * np.exp(-(ph - on) / tau)
    return power_w * np.where(ph <= on, heating, cooling).sum(axis=-1)


def envelope(ladder: Foster | Cauer, power_w: float, freq_hz: float, duty: float,
             cycles: ArrayLike) -> tuple[NDArray, NDArray]:
    """Peak and valley rise (K) of the k-th period after a cold start, k = ``cycles`` (1, 2, ...).

    >>> from spicethermal.core.ladder import Foster
    >>> pk, vl = envelope(Foster.from_tau([1.0], [1.0]), 1.0, 1.0, 1.0, [1])
    >>> bool(round(float(pk[0]), 12) == round(1 - np.exp(-1), 12))
    True
    """
    check_drive(freq_hz, duty, power_w)
    r, tau = _stages(ladder)
    period = 1.0 / freq_hz
    k = np.asarray(cycles, dtype=float)[..., None]
    build = -np.expm1(-k * period / tau)
    peaks = power_w * stage_peaks(r, tau, period, duty) * build
    valleys = peaks * np.exp(-(1 - duty) * period / tau)
    return peaks.sum(axis=-1), valleys.sum(axis=-1)


def r_duty_eq3(ladder: Foster | Cauer, t_s: ArrayLike, duty: float) -> NDArray:
    """Conservative duty-cycle impedance of the paper's eq. 3: ``D + (1 - D) r(t)``.

    >>> from spicethermal.core.ladder import Foster
    >>> float(r_duty_eq3(Foster.from_tau([1.0], [1.0]), 0.0, 0.3))
    0.3
    """
    check_drive(1.0, duty)
    return duty + (1 - duty) * ladder.r_norm(t_s)


def r_duty_exact(ladder: Foster | Cauer, t_s: ArrayLike, duty: float) -> NDArray:
    """Exact normalized peak rise for pulses of width ``t`` repeated at duty ``D``.

    ``r_D(t) = Σ ri (1 - e^{-t/τi}) / (1 - e^{-t/(D τi)}) / Rth``; D = 0 is the single pulse
    r(t), D = 1 is 1.

    >>> from spicethermal.core.ladder import Foster
    >>> f = Foster.from_tau([1.0, 1.0], [1e-3, 1.0])
    >>> bool(np.all(r_duty_exact(f, [1e-4, 1e-2], 0.5) <= r_duty_eq3(f, [1e-4, 1e-2], 0.5)))
    True
    """
    check_drive(1.0, duty)
    r, tau = _stages(ladder)
    t = np.asarray(t_s, dtype=float)[..., None]
    if duty == 0:
        return ladder.r_norm(t_s)
    if duty == 1:
        return np.ones(np.shape(t_s))
    return (r * -np.expm1(-t / tau) / -np.expm1(-t / (duty * tau))).sum(axis=-1) / r.sum()
