"""Random validation draws over every device class and kind of physics: the generator of the
held-out sets (a fresh seed for each report, recorded before it is scored).

Every case draws its device class (:data:`~.cases.DEVICES`: actuator, MOSFET, diode, MEMS
micro-heater, IGBT module), a power scale, a bench variant (noise level, samples per decade,
dense or sparse PWM grid, with or without ``tj_steady_c``, °C or volts, one to three cooling
curves) and its physics, with magnitudes relative to the device's own rise and noise. The kinds
(:data:`KINDS`, with their shares of a draw):

* ``effect`` — one catalogued effect in any of its forms, at a strength drawn over a range
  that runs from below detection to strong;
* ``pair`` — two catalogued effects of different kinds (not two device effects);
* ``clean`` — the device's own linear ladder;
* ``linear`` — a linear device of another shape (:func:`~.linear.shape_network`: distributed
  and tapered lines, continuous spectra, parallel paths, short and long ladders);
* ``smooth`` — a resistance that follows temperature by a law that is in no catalogue
  (exponential, quadratic, saturating, a conductivity with a minimum), on all layers or some;
* ``phase`` — latent heat outside the catalogue's bands: melting and solidifying at different
  temperatures, a skewed band, two bands;
* ``artefact`` — a measurement artefact that is in no catalogue: a trigger delay of the
  cooling curves, an acquisition gain and offset error, a reference drifting during the
  curves, a heater whose power sags with temperature, a device remounted between curves, a
  convection that switches regime.

Each case carries its acceptable verdicts (:attr:`~.cases.Case.acceptable`; for physics that is
in no catalogue :data:`~.cases.ACCEPTABLE` gives them and why). Case ``i`` of a seed is the same
bundle whatever ``n`` (each case has its own random stream); ``only`` draws every case of one
kind. Bump :data:`GENERATOR` whenever a draw changes: a seed's cases are those of a version.

>>> cases = draw(12, 1)
>>> len(cases), len({c.name for c in cases}) == 12, draw(3, 1)[2] == cases[2]
(12, True, True)
"""

from __future__ import annotations

import math
import random
from dataclasses import replace
from typing import Any

from .cases import DEVICES, Case, Device, acceptable_for, bench_for, laws_on
from .linear import SHAPES, shape_network
from .measure import Transient
from .network import LatentHeat, ResistanceLaw
from .periodic import ripple_bound

__all__ = ["EFFECTS", "GENERATOR", "KINDS", "draw"]

#: Version of the draws: the same seed gives the same cases within a version.
GENERATOR = 1
#: Share of each kind in a draw.
KINDS = {"effect": 0.34, "pair": 0.10, "clean": 0.08, "linear": 0.12, "smooth": 0.12,
         "phase": 0.08, "artefact": 0.16}
EFFECTS = ("temperature-coefficient", "phase-change", "electrical-transient",
           "tsp-nonlinearity", "sample-window")
DEVICE_EFFECTS = EFFECTS[:2]
ARTEFACTS = ("trigger-delay", "adc-gain-offset", "reference-drift", "heater-sag", "remount",
             "convection-switch")

Draw = tuple[str, dict, dict, str, dict]  # form, network changes, bench changes, label, truth


def _logu(rng: random.Random, lo: float, hi: float) -> float:
    return math.exp(rng.uniform(math.log(lo), math.log(hi)))


def _sign(rng: random.Random) -> float:
    return rng.choice((-1.0, 1.0))


def _scaled(dev: Device, rng: random.Random) -> Device:
    """``dev`` with its powers scaled by a factor drawn from 0.7 to 1.3."""
    k = _logu(rng, 0.7, 1.3)
    b = dev.bench
    return replace(dev, bench=replace(b, cooling_powers_w=tuple(p * k for p in
                                                                b.cooling_powers_w),
                                      pwm_power_w=b.pwm_power_w * k))


def _variant(rng: random.Random, dev: Device, min_curves: int = 1) -> dict[str, Any]:
    return {"noise_k": rng.choice(dev.noise_levels), "per_decade": rng.choice((5, 10, 20)),
            "dense_pwm": rng.random() < 0.6, "steady": rng.random() < 0.6,
            "volts": rng.random() < 0.25, "n_curves": max(min_curves, rng.choice((1, 2, 3)))}


def _tau_fast(dev: Device) -> float:
    return float(dev.network().foster()[1].min())


def _band(rng: random.Random, dev: Device, shape: str, lo: float, hi: float,
          frac: tuple[float, float], node: int | None = None) -> LatentHeat:
    """A band at ``node`` (drawn: the junction, the next node or the cavity) centred from
    ``lo`` to ``hi`` of the node's rise, its latent heat ``frac`` of the heat that the node and
    the next one store over that rise."""
    node = rng.choice((0, 1, dev.cavity_node)) if node is None else node
    rise = dev.node_rise_k(node)
    t_c = dev.bench.tref_c + rng.uniform(lo, hi) * rise
    width = rng.uniform(0.03, 0.2 if shape != "skewed" else 0.1) * rise
    latent = _logu(rng, *frac) * sum(dev.c_j_per_k[node:node + 2]) * rise
    return LatentHeat(node, latent, t_c, width, shape)


def _effect(rng: random.Random, effect: str, dev: Device, noise_k: float) -> Draw:
    """One catalogued effect in a random form and strength."""
    rise = dev.node_rise_k(0)
    n = len(dev.r_k_per_w)
    if effect == "temperature-coefficient":
        form = rng.choice(("junction", "local", "power", "outer", "inner"))
        delta = _logu(rng, 0.002, 0.4)  # relative change of R over the rise
        if form == "power":
            n_exp, beta = delta * (dev.bench.tref_c + 273.15) / rise, _logu(rng, 1e-4, 3e-3)
            return form, {"laws": laws_on(dev, ResistanceLaw("power", exponent=n_exp)),
                          "c_slope_per_k": (beta,) * n}, {}, f"n={n_exp:.2g}", \
                {"exponent": n_exp, "c_slope_per_k": beta}
        alpha = _sign(rng) * delta / rise * (2.0 if form in ("outer", "inner") else 1.0)
        layers = {"outer": range(n - 2, n), "inner": range(0, 2)}.get(form)
        changes: dict[str, Any] = {"laws": laws_on(dev, ResistanceLaw("linear", alpha), layers)}
        if form == "junction":
            changes["control"] = "junction"
        return form, changes, {}, f"{alpha:.2g}/K", {"alpha_per_k": alpha}
    if effect == "phase-change":
        shape = rng.choice(("gaussian", "logistic", "plateau"))
        band = _band(rng, dev, shape, 0.35, 0.8, (0.005, 3.0))
        return f"{shape}@{band.node}", {"latent": (band,)}, {}, f"{band.latent_j:.2g}J", \
            {"band": repr(band)}
    if effect == "electrical-transient":
        kind = rng.choice(("fixed", "power", "ringing"))
        amp = -_logu(rng, 0.05, 8.0) * max(1.0, noise_k / 0.05)
        if kind == "power":
            amp /= dev.top_power_w
        tau = dev.transient_tau_s * _logu(rng, 0.3, 3.0)
        tr = Transient(kind, amp, tau_s=tau, ring_hz=_logu(rng, 0.5, 5.0) / tau)
        return kind, {}, {"transient": tr}, f"{amp:.2g}", {"transient": repr(tr)}
    if effect == "tsp-nonlinearity":
        order = rng.choice(("quadratic", "cubic"))
        span = rise + 10.0
        bow = _sign(rng) * _logu(rng, 2e-3, 0.05)  # relative bow over the calibrated span
        key, value = ("quad", bow / span) if order == "quadratic" else ("cubic", bow / span ** 2)
        return order, {}, {"tsp": replace(dev.bench.tsp, **{key: value})}, f"{value:.2g}", \
            {key: value}
    mode = rng.choice(("end", "average"))
    w = dev.bench.declared_window_s * _logu(rng, 0.05, 4.0) * (2.0 if mode == "average" else 1.0)
    return mode, {}, {"window_s": w, "window_mode": mode, "declared_window_s": 0.0}, \
        f"{w:.2g}s", {"window_s": w, "mode": mode}


def _smooth(rng: random.Random, dev: Device) -> Draw:
    """A resistance law that is in no catalogue."""
    rise, n, tref = dev.node_rise_k(0), len(dev.r_k_per_w), dev.bench.tref_c
    law_kind = rng.choice(("exp", "quadratic", "saturating", "kmin"))
    delta = _logu(rng, 0.01, 0.4)
    if law_kind == "exp":
        law = ResistanceLaw("exp", alpha_per_k=math.log(1.0 + _sign(rng) * delta) / rise)
    elif law_kind == "quadratic":
        law = ResistanceLaw("quadratic", alpha_per_k=_sign(rng) * rng.uniform(0.0, 0.5) * delta
                            / rise, beta_per_k2=_sign(rng) * delta / rise ** 2)
    elif law_kind == "saturating":
        law = ResistanceLaw("saturating", amp=_sign(rng) * delta,
                            width_k=rng.uniform(0.1, 0.35) * rise)
    else:
        t1 = tref + rng.uniform(0.35, 0.7) * rise
        law = ResistanceLaw("kmin", beta_per_k2=delta / (t1 - 25.0) ** 2, t1_c=t1)
    where = rng.choice(("all", "all", "outer", "inner"))
    layers = {"outer": range(n - 2, n), "inner": range(0, 2)}.get(where)
    changes: dict[str, Any] = {"laws": laws_on(dev, law, layers)}
    if rng.random() < 0.25:
        changes["control"] = "junction"
    return law_kind, changes, {}, f"{delta:.2g}@{where}", \
        {"law": repr(law), "layers": where, "control": changes.get("control", "local")}


def _phase(rng: random.Random, dev: Device, variant: dict) -> Draw:
    """Latent heat outside the catalogue's bands."""
    form = rng.choice(("hysteresis", "skewed", "two-bands"))
    if form == "hysteresis":
        found = _hysteresis(rng, dev, variant)
        if found is not None:
            return found
        form = "skewed"  # no node leaves room for a gap beyond the ripple
    if form == "skewed":
        band = _band(rng, dev, "skewed", 0.4, 0.8, (0.05, 3.0))
        return form, {"latent": (band,)}, {}, f"{band.latent_j:.2g}J", {"bands": [repr(band)]}
    if form == "two-bands":
        bands = (_band(rng, dev, rng.choice(("gaussian", "logistic", "plateau")), 0.3, 0.5,
                       (0.05, 2.0)),
                 _band(rng, dev, rng.choice(("gaussian", "logistic", "plateau")), 0.6, 0.85,
                       (0.05, 2.0)))
        return form, {"latent": bands}, {}, "+".join(f"{b.latent_j:.2g}J" for b in bands), \
            {"bands": [repr(b) for b in bands]}
    raise AssertionError(form)


def _hysteresis(rng: random.Random, dev: Device, variant: dict) -> Draw | None:
    """A band melting around ``t_m`` on the way up and solidifying a gap lower; the gap exceeds
    the PWM ripple at its node (the periodic states then exchange no latent heat) and the
    hottest curve melts it whole. None when no node leaves room for it."""
    bench = bench_for(dev, variant)
    freqs, duties = bench.grid()
    for node in (rng.choice((0, 1, dev.cavity_node)), dev.cavity_node, len(dev.r_k_per_w) - 1):
        rise = dev.node_rise_k(node)
        top = dev.bench.tref_c + rise * max(bench.cooling_powers_w) / dev.top_power_w
        width = rng.uniform(0.02, 0.05) * rise
        ripple = ripple_bound(dev.network(), bench.pwm_power_w, freqs, duties, node)
        gap = max(1.5 * ripple, 4.0 * width, rng.uniform(0.1, 0.3) * rise)
        t_s = dev.bench.tref_c + rng.uniform(0.25, 0.5) * rise
        t_s = min(t_s, top - 3.0 * width - gap)
        if t_s > dev.bench.tref_c + 0.1 * rise + 3.0 * width:
            latent = _logu(rng, 0.1, 3.0) * sum(dev.c_j_per_k[node:node + 2]) * rise
            band = LatentHeat(node, latent, t_s + gap, width, rng.choice(("gaussian",
                                                                          "logistic")), gap)
            return "hysteresis", {"latent": (band,)}, {}, f"{latent:.2g}J gap {gap:.2g}K", \
                {"bands": [repr(band)]}
    return None


def _artefact(rng: random.Random, dev: Device, variant: dict) -> tuple[Draw, str]:
    """A measurement artefact that is in no catalogue, and its acceptable-verdict key."""
    kind = rng.choice(ARTEFACTS)
    rise, n, rth = dev.node_rise_k(0), len(dev.r_k_per_w), sum(dev.r_k_per_w)
    if kind == "trigger-delay":
        d = _tau_fast(dev) * _logu(rng, 0.1, 2.0)
        return (kind, {}, {"time_offset_s": d}, f"{d:.2g}s", {"time_offset_s": d}), kind
    if kind == "adc-gain-offset":
        gain = _sign(rng) * _logu(rng, 5e-4, 5e-3)
        off = _sign(rng) * abs(dev.bench.tsp.k_v_per_k) * _logu(rng, 0.05, 1.0)
        return (kind, {}, {"adc_gain": gain, "adc_offset_v": off}, f"{gain:.2g},{off:.2g}V",
                {"adc_gain": gain, "adc_offset_v": off}), kind
    if kind == "reference-drift":
        rate = _sign(rng) * _logu(rng, 3.0, 60.0) * variant["noise_k"] / dev.bench.t_max_s
        return (kind, {}, {"drift_k_per_s": rate}, f"{rate:.2g}K/s",
                {"drift_k_per_s": rate}), "reference-drift"
    if kind == "heater-sag":
        g = _logu(rng, 0.01, 0.3) / rise
        return (kind, {"power_slope_per_k": g}, {}, f"{g:.2g}/K",
                {"power_slope_per_k": g}), kind
    if kind == "remount":
        c = _sign(rng) * rth * _logu(rng, 0.01, 0.1)
        c = max(c, -0.5 * dev.r_k_per_w[-1])
        variant["n_curves"] = rng.choice((2, 3))
        changes: dict[str, Any] = {"contact_k_per_w": c}
        if variant["n_curves"] == 3:  # mounted at the middle power, remounted for the others
            low, mid, high = sorted(dev.bench.cooling_powers_w)
            changes["cooling_powers_w"] = (mid, low, high)
        return (kind, {}, changes, f"{c:.2g}K/W", {"contact_k_per_w": c}), \
            "remount" if variant["n_curves"] == 3 else "remount-two"
    t0 = dev.bench.tref_c + rng.uniform(0.2, 0.6) * dev.node_rise_k(n - 1)
    law = ResistanceLaw("switch", t0_c=t0, drop=rng.uniform(0.1, 0.4),
                        width_k=max(0.5, rng.uniform(0.02, 0.06) * rise))
    return (kind, {"laws": laws_on(dev, law, range(n - 1, n))}, {}, f"{law.drop:.2g}@{t0:.3g}C",
            {"law": repr(law)}), kind


def _kind(u: float) -> str:
    total = 0.0
    for kind, share in KINDS.items():
        total += share
        if u < total:
            return kind
    return kind


def _one(i: int, seed: int, only: str | None) -> Case:
    rng = random.Random(f"spicethermal-validation/{GENERATOR}:{seed}:{i}")
    dev = _scaled(DEVICES[rng.choice(sorted(DEVICES))], rng)
    kind = only or _kind(rng.random())
    sid = seed * 100_000 + i
    head = f"{i:03d} {kind}"
    if kind == "effect":
        effect = rng.choice(EFFECTS)
        variant = _variant(rng, dev, 2 if effect in DEVICE_EFFECTS else 1)
        form, net, bench, label, truth = _effect(rng, effect, dev, variant["noise_k"])
        return Case(f"{head}/{effect}/{form}", "effect", (effect,), dev.name,
                    dev.network(**net), bench_for(dev, variant, **bench), sid, form, label,
                    truth, kind=f"effect/{effect}")
    if kind == "pair":
        e1, e2 = rng.sample(EFFECTS, 2)
        if e1 in DEVICE_EFFECTS and e2 in DEVICE_EFFECTS:
            e2 = rng.choice(EFFECTS[2:])
        variant = _variant(rng, dev, 2)
        d1 = _effect(rng, e1, dev, variant["noise_k"])
        d2 = _effect(rng, e2, dev, variant["noise_k"])
        parts = tuple(Case(f"{head} part {e}/{d[0]}", "effect", (e,), dev.name,
                           dev.network(**d[1]), bench_for(dev, variant, **d[2]), sid, d[0],
                           d[3], d[4]) for e, d in ((e1, d1), (e2, d2)))
        return Case(f"{head}/{e1}+{e2}", "pair", (e1, e2), dev.name,
                    dev.network(**d1[1], **d2[1]), bench_for(dev, variant, **d1[2], **d2[2]),
                    sid, f"{d1[0]}+{d2[0]}", f"{d1[3]},{d2[3]}", {e1: d1[4], e2: d2[4]}, parts)
    if kind in ("clean", "linear"):
        variant = _variant(rng, dev)
        shape = rng.choice(SHAPES) if kind == "linear" else "ladder"
        net = (shape_network(dev.r_k_per_w, dev.c_j_per_k, shape, rng) if kind == "linear"
               else dev.network())
        return Case(f"{head}/{shape}", kind, (), dev.name, net, bench_for(dev, variant), sid,
                    shape, "", {"shape": shape}, kind=kind)
    variant = _variant(rng, dev, 1 if kind == "artefact" else 2)
    if kind == "smooth":
        (form, net, bench, label, truth), key = _smooth(rng, dev), ""
    elif kind == "phase":
        (form, net, bench, label, truth), key = _phase(rng, dev, variant), ""
    else:
        (form, net, bench, label, truth), key = _artefact(rng, dev, variant)
    key = key or form
    return Case(f"{head}/{form}", "uncatalogued", (), dev.name, dev.network(**net),
                bench_for(dev, variant, **bench), sid, form, label,
                {**truth, "acceptable_because": key}, acceptable=acceptable_for(key),
                kind=f"{kind}/{form}")


def draw(n: int, seed: int, only: str | None = None) -> list[Case]:
    """``n`` random cases of ``seed`` (module docstring); ``only`` one kind of :data:`KINDS`.

    Parameters
    ----------
    n : number of cases.
    seed : the draw's seed (a fresh one for each report).
    only : draw only cases of this kind (``"effect"``, ``"pair"``, ...), or None.

    Returns
    -------
    list of Case
        Built afresh (nothing is simulated until :meth:`~.cases.Case.record`).
    """
    if only is not None and only not in KINDS:
        raise ValueError(f"kind {only!r}: expected one of {sorted(KINDS)}")
    return [_one(i, seed, only) for i in range(n)]
