"""What a population of one part shows: which samples stand out and why, the typical and
worst-case ladders (datasheets' Zth typ/max), and the spread of the PWM peak.

Outliers (:func:`find_outliers`)
--------------------------------
Robust z-scores, ``z = (x − median) / s`` with ``s = 1.4826 · MAD`` (the standard deviation
for Gaussian data, unmoved by the outliers themselves), but never below
:data:`RESOLUTION` × the median Rth: differences smaller than that are the fitted ladders' own
wobble, not the parts. A device stands out when ``|z| ≥`` :data:`Z_OUTLIER` (Iglewicz and
Hoaglin's 3.5) for

* its Rth, or
* its heat path: the cumulative structure function ΣR(ΣC) of its fitted ladder (exact
  Cauer equivalent, :mod:`spicethermal.identify.structure`) read at fixed ΣC levels
  (:data:`LEVELS_PER_DECADE` per decade, from the population's first to last ΣC), each level
  z-scored across the population. As a path is compared at many levels, its limit is
  raised so that a device has the same chance of a false alarm as from its Rth alone
  (Bonferroni: ``|z| ≥ Φ⁻¹(1 − p/(2m))`` for ``m`` levels, ``p`` the two-sided tail beyond
  :data:`Z_OUTLIER`; 4.37 for the 37 levels of 4.5 decades). Extra resistance in a layer
  (a voided die attach, a dry interface) stays in ΣR all the way out, so the excess must
  *persist*: from the level where ``|z|`` is largest to the end of the path, ΔR stays at
  least half as large, with the same sign. A fit that only moves resistance between
  neighbouring stages (ΣR dips and comes back) does not count. The reason names where the
  excess begins: the path matches the population up to the last level before ``|z|``
  climbs above :data:`Z_OUTLIER`.

Typical and worst case (:func:`envelopes`)
------------------------------------------
On a common log time grid (10 points per decade over the span every curve covers), the
median and the maximum of the measured Zth(t) of the devices that are not outliers (an
outlier is a part production would screen), each fitted like any curve (automatic order,
ΣR held at the median and at the maximum Rth).

PWM peaks (:func:`pwm_peaks`)
-----------------------------
For each (frequency, duty) of a grid, the periodic steady-state junction peak of every
device's model (:func:`spicethermal.engines.pwm.steady_state`) and its percentiles over the
population: the measured population is the Monte-Carlo sample.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from .. import __version__
from ..core.errors import DataFormatError
from ..engines.pwm import steady_state
from ..fit.ladder import fit_model
from ..identify.curves import ZthCurve
from ..identify.structure import StructureFunction
from ..model import ThermalModel

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import ArrayLike, NDArray


__all__ = ["PERCENTILES", "RESOLUTION", "Z_OUTLIER", "Outlier", "envelopes", "find_outliers",
           "fit_envelope", "path_limit", "population_power", "pwm_peaks", "robust_scale",
           "robust_z"]

#: A robust z-score at or beyond this marks an outlier (Iglewicz & Hoaglin).
Z_OUTLIER = 3.5
#: Robust scales are at least this fraction of the median Rth.
RESOLUTION = 0.01
#: ΣC levels per decade at which structure functions are compared.
LEVELS_PER_DECADE = 8
#: Percentiles of the PWM peak table.
PERCENTILES = (50, 90, 99)
_MAD_TO_SIGMA = 1.4826


def robust_scale(values: ArrayLike, floor: float = 0.0) -> NDArray:
    """The robust σ, ``max(1.4826 · MAD, floor)`` (per column of a 2-D array): the scale of
    :func:`robust_z`, never below ``floor`` (for Rth, :data:`RESOLUTION` × the median).

    >>> float(robust_scale([2.0, 2.0, 2.0, 2.0], floor=0.02))  # identical inputs: the floor
    0.02
    """
    x = np.asarray(values, dtype=float)
    return np.maximum(_MAD_TO_SIGMA * np.median(np.abs(x - np.median(x, axis=0)), axis=0),
                      floor)


def robust_z(values: ArrayLike, floor: float = 0.0) -> NDArray:
    """Robust z-scores ``(x − median) / max(1.4826 · MAD, floor)`` (0 where the scale is 0).

    >>> robust_z([1.0, 2.0, 3.0, 4.0, 100.0]).round(2).tolist()
    [-1.35, -0.67, 0.0, 0.67, 65.43]
    """
    x = np.asarray(values, dtype=float)
    med = np.median(x, axis=0)
    scale = robust_scale(x, floor)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(scale > 0, (x - med) / np.where(scale > 0, scale, 1.0), 0.0)


@dataclass(frozen=True)
class Outlier:
    """A device that stands out: its index in the population, robust z of its Rth and of its
    heat path (the largest persistent one, 0 if none), where the path departs (ΣC and ΣR of
    the population there, None when it does not) and the reason in one sentence."""

    index: int
    z_rth: float
    z_path: float
    excess_k_per_w: float
    departs_c_j_per_k: float | None
    departs_r_k_per_w: float | None
    reason: str


def _structures(ladders: Sequence[Any]) -> list[Any]:
    return [StructureFunction.from_ladder(lad) for lad in ladders]


def find_outliers(rth_k_per_w: ArrayLike, ladders: Sequence[Any]) -> list[Outlier]:
    """The devices that stand out (module docstring), in input order.

    Parameters
    ----------
    rth_k_per_w : Rth of each device (K/W).
    ladders : the fitted ladder of each device (Foster or Cauer), same order.

    Returns
    -------
    list of Outlier

    Examples
    --------
    >>> from spicethermal.core.ladder import Cauer
    >>> rng = np.random.default_rng(0)
    >>> parts = [Cauer([0.05, 0.2, 1.0] * np.exp(rng.normal(0, 0.05, 3)), [2e-4, 5e-3, 1.0])
    ...          for _ in range(30)]
    >>> parts[7] = Cauer([0.05, 0.6, 1.0], [2e-4, 5e-3, 1.0])   # extra 0.4 K/W after the die
    >>> found = find_outliers([p.rth for p in parts], parts)
    >>> [(o.index, round(o.excess_k_per_w, 1), round(o.departs_c_j_per_k, 4)) for o in found]
    [(7, 0.4, 0.0003)]
    """
    rth = np.asarray(rth_k_per_w, dtype=float)
    if rth.size != len(ladders):
        raise DataFormatError("find_outliers: one Rth per ladder")
    if rth.size < 3:
        return []
    floor = RESOLUTION * float(np.median(rth))
    z_rth = robust_z(rth, floor)
    sfs = _structures(ladders)
    lo = float(np.median([s.c_j_per_k[0] for s in sfs]))
    hi = float(np.median([s.c_j_per_k[-1] for s in sfs]))
    n_levels = max(2, int(round(LEVELS_PER_DECADE * math.log10(hi / lo))) + 1)
    levels = np.logspace(math.log10(lo), math.log10(hi), n_levels)
    path = np.array([s.r_at(levels) for s in sfs])
    typical = np.median(path, axis=0)
    z_path = robust_z(path, floor)
    limit = path_limit(n_levels)
    out = []
    for i in range(rth.size):
        excess = path[i] - typical
        k, persistent = _persistent_peak(z_path[i], excess)
        zp = float(z_path[i, k]) if persistent and abs(z_path[i, k]) >= limit else 0.0
        if abs(z_rth[i]) < Z_OUTLIER and zp == 0.0:
            continue
        if zp != 0.0:
            start = k
            while start > 0 and z_path[i, start - 1] * np.sign(zp) >= Z_OUTLIER:
                start -= 1
            c0 = float(levels[start - 1]) if start > 0 else None
            r0 = float(typical[start - 1]) if start > 0 else None
            reason = _path_reason(float(excess[k]), zp, c0, r0, float(z_rth[i]), rth[i],
                                  float(np.median(rth)))
            out.append(Outlier(i, float(z_rth[i]), zp, float(excess[k]), c0, r0, reason))
        else:
            reason = (f"Rth {rth[i]:.4g} K/W is {z_rth[i]:+.1f} robust σ from the median "
                      f"{np.median(rth):.4g} K/W; the heat path shows no layer that stands out "
                      f"by itself")
            out.append(Outlier(i, float(z_rth[i]), 0.0, float(rth[i] - np.median(rth)), None,
                               None, reason))
    return out


def path_limit(levels: int) -> float:
    """The |z| a heat path compared at ``levels`` ΣC levels must reach (module docstring).

    >>> round(path_limit(1), 6) == Z_OUTLIER, round(path_limit(37), 2)
    (True, 4.37)
    """
    from scipy.special import ndtr, ndtri

    return float(-ndtri(ndtr(-Z_OUTLIER) / levels))  # the normal tail, shared by the levels


def _persistent_peak(z: NDArray, excess: NDArray) -> tuple[int, bool]:
    """Index of the largest |z| and whether the excess there persists to the end."""
    k = int(np.argmax(np.abs(z)))
    tail = excess[k:] * np.sign(excess[k])
    return k, bool(excess[k] != 0 and np.all(tail >= 0.5 * abs(excess[k])))


def _path_reason(excess: float, z: float, c0: float | None, r0: float | None, z_rth: float,
                 rth: float, rth_median: float) -> str:
    more = excess > 0
    what = "larger" if more else "smaller"
    where = ("from the junction on (the die itself)" if c0 is None else
             f"beyond ΣC ≈ {c0:.3g} J/K, {r0:.3g} K/W from the junction (the path up to "
             f"there matches the population)")
    text = (f"{what} outer resistance: {excess:+.3g} K/W ({100 * excess / rth_median:+.0f} % "
            f"of the median Rth, {z:+.1f} robust σ) in the heat path {where}")
    if more:
        text += "; a voided die attach or a poor thermal interface looks like this"
    return text + f"; Rth {rth:.4g} K/W ({z_rth:+.1f} σ)"


def envelopes(curves: Sequence[Mapping[str, Any]], points_per_decade: int = 10
              ) -> tuple[NDArray, NDArray, NDArray]:
    """The common time grid and the median and maximum Zth(t) of ``curves`` (each a mapping
    with ``t_s``, ``zth_k_per_w``), interpolated in log time.

    >>> t = [1e-3, 1e-2, 1e-1]
    >>> grid, typ, worst = envelopes([{"t_s": t, "zth_k_per_w": [1, 2, 3]},
    ...                               {"t_s": t, "zth_k_per_w": [2, 2, 4]},
    ...                               {"t_s": t, "zth_k_per_w": [3, 3, 5]}], 1)
    >>> typ.tolist(), worst.tolist()
    ([2.0, 2.0, 4.0], [3.0, 3.0, 5.0])
    """
    if not curves:
        raise DataFormatError("no curve to take the envelope of")
    lo = max(float(c["t_s"][0]) for c in curves)
    hi = min(float(c["t_s"][-1]) for c in curves)
    if not hi > lo:
        raise DataFormatError(f"the curves share no time span (latest start {lo:.3g} s, "
                              f"earliest end {hi:.3g} s)")
    n = max(2, int(round(points_per_decade * math.log10(hi / lo))) + 1)
    grid = np.logspace(math.log10(lo), math.log10(hi), n)
    z = np.array([np.interp(np.log(grid), np.log(np.asarray(c["t_s"], dtype=float)),
                            np.asarray(c["zth_k_per_w"], dtype=float)) for c in curves])
    return grid, np.median(z, axis=0), z.max(axis=0)


def fit_envelope(t_s: NDArray, zth_k_per_w: NDArray, rth_k_per_w: float, label: str
                 ) -> ThermalModel:
    """An envelope curve fitted like any curve: automatic order, ΣR = ``rth_k_per_w``."""
    curve = ZthCurve.from_points(t_s, zth_k_per_w, rth_k_per_w=rth_k_per_w, label=label)
    model, _ = fit_model(curve, rth_k_per_w=rth_k_per_w,
                         provenance={"tool": f"spicethermal {__version__} batch",
                                     "source": label})
    return model


def population_power(powers_w: Sequence[float | None], given_w: float | None = None
                     ) -> tuple[float, str]:
    """The power of the PWM peak table and where it comes from: ``given_w`` (``--power``),
    else the median of the devices' measured powers (the power cut before the fitted cooling
    curve), else 1 W nominal (Zth tables carry no power).

    >>> population_power([0.094, 0.094, 0.3])
    (0.094, "the median of the devices' measured powers")
    >>> population_power([None, None]), population_power([0.094], 2.0)[0]
    ((1.0, '1 W nominal: no input gives a power'), 2.0)
    """
    if given_w is not None:
        return float(given_w), "--power"
    known = [float(p) for p in powers_w if p is not None and p == p and p > 0]
    if not known:
        return 1.0, "1 W nominal: no input gives a power"
    return float(np.median(known)), "the median of the devices' measured powers"


def pwm_peaks(ladders: Sequence[Any], power_w: float, freqs_hz: Sequence[float],
              duties: Sequence[float]) -> list[dict[str, float]]:
    """Percentiles (:data:`PERCENTILES`) and maximum over ``ladders`` of the junction peak
    rise (K) at ``power_w`` for every (frequency, duty), one row each.

    >>> from spicethermal.core.ladder import Foster
    >>> rows = pwm_peaks([Foster.from_tau([r], [1e-3]) for r in (1.0, 2.0, 3.0)], 1.0, [1e6],
    ...                  [0.5])
    >>> round(rows[0]["peak_p50_k"], 3), round(rows[0]["peak_max_k"], 3)  # D·P·R at 1 MHz
    (1.0, 1.5)
    """
    if not ladders:
        raise DataFormatError("no device model for the PWM table")
    rows = []
    for f in freqs_hz:
        for d in duties:
            peaks = np.array([steady_state(lad, power_w, f, d).peak_k for lad in ladders])
            row = {"freq_hz": float(f), "duty": float(d), "power_w": float(power_w),
                   "devices": int(peaks.size)}
            for p in PERCENTILES:
                row[f"peak_p{p}_k"] = round(float(np.percentile(peaks, p)), 6)
            row["peak_max_k"] = round(float(peaks.max()), 6)
            rows.append(row)
    return rows
