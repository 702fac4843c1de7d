"""Diagnosis on the earlier random draws of the validation physics (actuator, MOSFET and diode
only), kept so that the figures recorded on them reproduce; new reports use a fresh seed of
``bench/bench_validation.py --seed S`` (:mod:`spicethermal.validation.draws`).

Every case draws its strength log-uniformly from a range that runs from below the fixed set's
weak value to above its strong one, its device class and its bench variant at random, pairs of
any two effects of different kinds, and uncatalogued physics (ambient drift, heater sag, a
remounted contact, convection switching) at random magnitudes. Scored by
``bench/bench_validation.py`` (its scorer, ``--set earlier``).

Plain script (not a test)::

    .venv/bin/python bench/bench_validation_random.py [N] [--seed S] [--only KIND] [...]

``--only pair`` (or ``effect``, ``clean``, ``uncatalogued``) draws ``N`` cases of that kind;
other options are passed to ``bench/bench_validation.py``.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse  # noqa: E402
import math  # noqa: E402
import random  # noqa: E402
import sys  # noqa: E402
from dataclasses import replace  # noqa: E402
from pathlib import Path  # noqa: E402

from spicethermal.validation.cases import DEVICES as ALL_DEVICES  # noqa: E402
from spicethermal.validation.cases import Case  # noqa: E402
from spicethermal.validation.cases import bench_for as _bench  # noqa: E402
from spicethermal.validation.cases import bench_variant as _variant  # noqa: E402
from spicethermal.validation.cases import laws_on as _laws  # noqa: E402
from spicethermal.validation.measure import Transient  # noqa: E402
from spicethermal.validation.network import LatentHeat, ResistanceLaw  # noqa: E402

#: The device classes these draws knew (the later ones would change every draw).
DEVICES = {name: ALL_DEVICES[name] for name in ("actuator", "mosfet", "diode")}


def _log(rng: random.Random, lo: float, hi: float) -> float:
    return math.exp(rng.uniform(math.log(lo), math.log(hi)))


def _draw_effect(rng: random.Random, effect: str, dev) -> tuple[str, dict, dict, str]:
    """(form, network changes, bench changes, strength label) for one random draw."""
    n = len(dev.r_k_per_w)
    if effect == "temperature-coefficient":
        form = rng.choice(["junction", "local", "power", "outer", "inner"])
        mag = _log(rng, 2e-4, 1e-2)
        sign = rng.choice([-1.0, 1.0])
        if form == "junction":
            return form, {"laws": _laws(dev, ResistanceLaw("linear", sign * mag)),
                          "control": "junction"}, {}, f"{sign * mag:.2g}/K"
        if form == "local":
            return form, {"laws": _laws(dev, ResistanceLaw("linear", sign * mag))}, {}, \
                f"{sign * mag:.2g}/K"
        if form == "power":
            n_exp = rng.uniform(0.2, 3.0)
            beta = _log(rng, 1e-4, 3e-3)
            return form, {"laws": _laws(dev, ResistanceLaw("power", exponent=n_exp)),
                          "c_slope_per_k": (beta,) * n}, {}, f"n={n_exp:.2g}"
        layers = range(n - 2, n) if form == "outer" else range(0, 2)
        return form, {"laws": _laws(dev, ResistanceLaw("linear", sign * mag * 2), layers)}, {}, \
            f"{sign * mag * 2:.2g}/K"
    if effect == "phase-change":
        shape = rng.choice(["gaussian", "logistic", "plateau"])
        node = rng.choice([0, 1, dev.cavity_node])
        rise = dev.node_rise_k(node)
        t_c = dev.bench.tref_c + rng.uniform(0.35, 0.8) * rise
        width = rng.uniform(0.03, 0.2) * rise
        frac = _log(rng, 0.01, 0.6)
        sensible = sum(dev.c_j_per_k[node:node + 3]) * rise
        return (f"{shape}@{node}",
                {"latent": (LatentHeat(node, frac * sensible, t_c, width, shape),)}, {},
                f"{frac:.2g}")
    if effect == "electrical-transient":
        kind = rng.choice(["fixed", "power", "ringing"])
        amp = -_log(rng, 0.3, 8.0)
        if kind == "power":
            amp = amp / dev.top_power_w
        tau = _log(rng, 5e-6, 6e-5)
        return kind, {}, {"transient": Transient(kind, amp, tau_s=tau,
                                                 ring_hz=_log(rng, 1e4, 2e5))}, f"{amp:.2g}"
    if effect == "tsp-nonlinearity":
        order = rng.choice(["quadratic", "cubic"])
        key = "quad" if order == "quadratic" else "cubic"
        value = _log(rng, 5e-5, 1.2e-3) if key == "quad" else _log(rng, 1e-6, 2.5e-5)
        value *= rng.choice([-1.0, 1.0])
        return order, {}, {"tsp": replace(dev.bench.tsp, **{key: value})}, f"{value:.2g}"
    if effect == "sample-window":
        mode = rng.choice(["end", "average"])
        w = dev.bench.declared_window_s * _log(rng, 0.3, 4.0) * (2.0 if mode == "average" else 1)
        return mode, {}, {"window_s": w, "window_mode": mode, "declared_window_s": 0.0}, \
            f"{w:.2g}s"
    raise ValueError(effect)


EFFECTS = ("temperature-coefficient", "phase-change", "electrical-transient",
           "tsp-nonlinearity", "sample-window")
DEVICE_EFFECTS = ("temperature-coefficient", "phase-change")


def _uncatalogued(rng: random.Random, dev, variant: dict) -> tuple[str, object, object]:
    kind = rng.choice(["ambient-drift", "heater-sag", "remounted-contact", "convection-switch"])
    if kind == "ambient-drift":
        rate = _log(rng, 0.003, 0.03) * (30 if dev.name != "actuator" else 1)
        return f"{kind} {rate:.2g} K/s", dev.network(), _bench(dev, variant, drift_k_per_s=rate)
    if kind == "heater-sag":
        g = _log(rng, 1e-3, 8e-3)
        return f"{kind} {g:.2g}/K", dev.network(power_slope_per_k=g), _bench(dev, variant)
    if kind == "remounted-contact":
        c = _log(rng, 0.03, 0.3) * sum(dev.r_k_per_w) / 2
        return f"{kind} {c:.2g} K/W", dev.network(), _bench(dev, variant, contact_k_per_w=c)
    n = len(dev.r_k_per_w)
    t0 = dev.bench.tref_c + rng.uniform(0.2, 0.6) * dev.node_rise_k(n - 1)
    law = ResistanceLaw("switch", t0_c=t0, drop=rng.uniform(0.1, 0.4), width_k=1.5)
    return f"{kind} at {t0:.3g} degC", dev.network(laws=_laws(dev, law, range(n - 1, n))), \
        _bench(dev, variant)


#: The share of each kind of case in a draw (cumulative bounds of one uniform number).
KINDS = {"effect": (0.0, 0.60), "pair": (0.60, 0.75), "clean": (0.75, 0.85),
         "uncatalogued": (0.85, 1.0)}


def draw(n: int, seed: int, only: str | None = None) -> list[Case]:
    """``n`` random cases: 60 % single effects, 15 % pairs, 10 % clean, 15 % uncatalogued
    (or ``n`` of the one kind ``only``)."""
    rng = random.Random(seed)
    out: list[Case] = []
    for i in range(n):
        dev = DEVICES[rng.choice(list(DEVICES))]
        variant = _variant(rng.randrange(60))
        u = rng.random()
        if only is not None:
            lo, hi = KINDS[only]
            u = lo + (hi - lo) * u
        sid = seed * 100000 + i
        if u < 0.60:
            effect = rng.choice(EFFECTS)
            form, net, bench, label = _draw_effect(rng, effect, dev)
            if effect in DEVICE_EFFECTS:
                variant["n_curves"] = max(variant["n_curves"], 2)
            out.append(Case(f"{i:03d} {effect}/{form}/{label}", "effect", (effect,), dev.name,
                            dev.network(**net), _bench(dev, variant, **bench), sid, form,
                            label, {}))
        elif u < 0.75:
            e1, e2 = rng.sample(EFFECTS, 2)
            if e1 in DEVICE_EFFECTS and e2 in DEVICE_EFFECTS:
                e2 = rng.choice(EFFECTS[2:])
            f1, n1, b1, l1 = _draw_effect(rng, e1, dev)
            f2, n2, b2, l2 = _draw_effect(rng, e2, dev)
            variant = {**variant, "n_curves": 2, "steady": True, "volts": False}
            parts = tuple(Case(f"{i:03d} {e}/{f}/{lab}", "effect", (e,), dev.name,
                               dev.network(**net), _bench(dev, variant, **b), sid, f, lab, {})
                          for e, f, net, b, lab in ((e1, f1, n1, b1, l1), (e2, f2, n2, b2, l2)))
            out.append(Case(f"{i:03d} pair/{e1}:{f1}+{e2}:{f2}", "pair", (e1, e2), dev.name,
                            dev.network(**n1, **n2), _bench(dev, variant, **b1, **b2), sid,
                            f"{f1}+{f2}", f"{l1},{l2}", {}, parts))
        elif u < 0.85:
            out.append(Case(f"{i:03d} clean/{dev.name}", "clean", (), dev.name, dev.network(),
                            _bench(dev, variant), sid, "linear", "", {}))
        else:
            variant = {**variant, "n_curves": 2}
            label, net, bench = _uncatalogued(rng, dev, variant)
            out.append(Case(f"{i:03d} uncatalogued/{label}", "uncatalogued", (), dev.name, net,
                            bench, sid, label.split()[0], "", {}))
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("n", nargs="?", type=int, default=40, help="number of cases (default 40)")
    ap.add_argument("--seed", type=int, default=1)
    args, rest = ap.parse_known_args(argv)
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from bench_validation import main as scorer

    return scorer(["--set", "earlier", "--seed", str(args.seed), "--n", str(args.n), *rest])


if __name__ == "__main__":
    raise SystemExit(main())
