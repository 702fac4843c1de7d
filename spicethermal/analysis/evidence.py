"""Evidence sentences: what the data show, each effect's fitted size in sensible units, and
whether it explains the misfit, all from checked numbers (an improvement below the decision
thresholds never "explains").
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from ..effects import Effect
from ..fit.effectfit import BundleData, EffectFit
from .compare import Comparison
from .residuals import fmt_number, fmt_time
from .verdict import MIN_EXPLAINED, MIN_IMPROVEMENT, explained_fraction
from .verdict import improvement as gain_of

__all__ = ["evidence", "neutral"]


def _most_improved(base: Comparison, cand: Comparison) -> tuple[str, float, float]:
    rows = [(n, b.rms_k, cand.dataset(n).rms_k) for n, b in base.by_dataset().items()]
    return max(rows, key=lambda r: r[1] - r[2])


def _offset(t_c: float) -> str:
    """``T − 25 °C`` / ``T + 24.9 °C``: the difference written with its true sign."""
    return f"T − {fmt_number(t_c, 4)} °C" if t_c >= 0 else f"T + {fmt_number(-t_c, 4)} °C"


def _signed(x: float, unit: str, gap: str = " ") -> str:
    """``+ 0.3 %/K`` inside a formula (``gap=""``: ``−5.99 K`` on its own)."""
    return f"{'+' if x >= 0 else '−'}{gap}{fmt_number(abs(x))} {unit}"


def neutral(effect: Effect) -> bool:
    """True when ``effect`` has no size (no latent heat, no α, no error, no curvature)."""
    p = effect.params
    sizes = {"temperature-coefficient": ("alpha_per_k",), "phase-change": ("latent_j",),
             "electrical-transient": ("k_per_w",) if effect.form == "power" else ("amplitude_k",),
             "tsp-nonlinearity": ("quad_k_per_k2", "cub_k_per_k3") if effect.form == "cubic"
             else ("quad_k_per_k2",)}.get(effect.name)
    return sizes is not None and all(p[k] == 0 for k in sizes)


def evidence(fit: EffectFit, data: BundleData, base: Comparison, cand: Comparison,
              noise: Mapping[str, float]) -> str:
    """One sentence from checked numbers: what the data show, the effect's fitted size in
    sensible units (times in s/ms/µs/ns, differences with their true sign), and whether it
    explains the misfit: only when the improvement and the explained fraction pass the
    decision thresholds (:data:`MIN_IMPROVEMENT`, :data:`MIN_EXPLAINED`).

    Parameters
    ----------
    fit : the fitted effect (``facts["no_gain"]``: it could not improve on the model).
    data : the bundle's arrays.
    base, cand : comparisons before and with the effect.
    noise : noise estimate (K) per data set.

    Returns
    -------
    str
    """
    e, p = fit.effect, fit.effect.params
    name, before, after = _most_improved(base, cand)
    improvement = base.rms_k / cand.rms_k if cand.rms_k > 0 else math.inf
    frac = explained_fraction(base, cand, noise)
    no_gain = bool(fit.facts.get("no_gain")) or neutral(e)
    explains = (not no_gain and gain_of(base, cand, noise) >= MIN_IMPROVEMENT
                and frac >= MIN_EXPLAINED)
    verdict = (f"explains {100 * frac:.0f} % of the misfit" if explains else
               f"does not explain the misfit (RMS {fmt_number(improvement)}× lower, "
               f"{100 * max(frac, 0):.0f} % of the misfit)")
    gain = f"{name} RMS {fmt_number(before)} → {fmt_number(after)} K"
    if no_gain:
        return f"no {e.name} ({e.form}) improves on the model without it ({gain})"
    if e.name == "temperature-coefficient":
        pw, rth = fit.facts.get("powers_w", []), fit.facts.get("rth_k_per_w", [])
        meas = ", ".join(f"{fmt_number(r, 4)} K/W at {fmt_number(q)} W"
                         for q, r in zip(pw, rth, strict=True))
        return ((f"Rth measured {meas}; " if meas else "")
                + f"R(T) = R0·(1 {_signed(100 * p['alpha_per_k'], '%/K')}·"
                f"({_offset(p['t0_c'])})) {verdict} ({gain})")
    if e.name == "phase-change":
        hot = [c.name for c in data.cooling if float(np.max(c.tj_c)) > p["t_c"] - p["width_k"]]
        node = int(p["node"])
        cross = f"{', '.join(hot)} cross" if len(hot) > 1 else f"{hot[0]} crosses" if hot \
            else "no curve crosses"
        if e.form == "plateau":
            band = (f"{fmt_number(p['t_c'] - p['width_k'] / 2, 4)} to "
                    f"{fmt_number(p['t_c'] + p['width_k'] / 2, 4)} °C (a flat band, edges of "
                    f"{fmt_number(p['edge_k'], 2)} K)")
        else:
            band = (f"{fmt_number(p['t_c'], 4)} ± {fmt_number(p['width_k'], 2)} °C (a {e.form} "
                    f"band)")
        return (f"{cross} {band}; a latent heat of {fmt_number(p['latent_j'] * 1e3)} mJ at "
                f"ladder node {node}{' (the junction)' if node == 0 else ''} {verdict} ({gain})")
    if e.name == "sample-window":
        mean = float(np.mean(base.dataset("pwm").residuals_k)) if data.pwm is not None else 0.0
        declared = fit.facts.get("declared_s", 0.0)
        how = "averaged over" if e.form == "average" else "at the end of"
        return (f"PWM readings are {_signed(mean, 'K', '')} off on average; a reading {how} a "
                f"{fmt_time(p['window_s'])} power-off window before each sample (declared "
                f"{fmt_time(declared) if declared > 0 else 'none'}) {verdict} ({gain})")
    if e.name == "electrical-transient":
        if e.form == "power":
            size = f"{_signed(p['k_per_w'], 'K', '')} per watt cut off"
        elif e.form == "ringing":
            size = (f"{_signed(p['amplitude_k'], 'K', '')}, ringing at "
                    f"{fmt_number(p['ring_hz'] / 1e3)} kHz,")
        else:
            size = _signed(p["amplitude_k"], "K", "")
        return (f"cooling readings after the cut are off by {size} and recover within "
                f"{fmt_time(p['masked_s'])}; the transient {verdict} ({gain})")
    if e.name == "tsp-nonlinearity":
        cal = base.dataset("calibration").residuals_k if data.calibration is not None else \
            np.zeros(1)
        cubic = (f" {_signed(1e6 * p['cub_k_per_k3'], 'µK/K³')}·({_offset(p['t_cal_c'])})³"
                 if e.form == "cubic" else "")
        scatter = (f" (noise {fmt_number(noise['calibration'], 2)} K)" if "calibration" in noise
                   else "")
        return (f"the linear calibration's residuals span {fmt_number(np.ptp(cal))} K{scatter}; a "
                f"TSP error {_signed(1e3 * p['quad_k_per_k2'], 'mK/K²')}·"
                f"({_offset(p['t_cal_c'])})²{cubic} {verdict} ({gain})")
    return f"{e.name} ({e.form}) {verdict} ({gain})"
