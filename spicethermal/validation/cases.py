"""The validation catalogue: cases with their truth, built from three device classes.

Device classes (:data:`DEVICES`, Cauer layers junction first):

* ``actuator`` — the paper's thermopneumatic actuator, ambient reference, Rth = 146 K/W, a
  slow cavity (node 2 holds the fluid), τ from ~80 µs to ~30 s, 0.1–0.3 W;
* ``mosfet`` — a power MOSFET measured junction-to-case on a cold plate, Rth ≈ 0.45 K/W,
  40–90 W;
* ``diode`` — a power diode measured junction-to-case, Rth = 2 K/W, 9–22 W.

Every catalogued effect comes in several *forms* (:data:`FORMS`), each weak, medium and
strong; then clean bundles, pairs of effects and physical effects that are in no catalogue
(expected verdict: none). Bench variants (noise, sampling, missing ``tj_steady_c``, curves
in volts, one to three cooling curves) rotate over the cases. Seeds are fixed: the same
case is the same bundle on every run.

>>> cases = catalogue()
>>> len(cases) >= 60, len({c.name for c in cases}) == len(cases)
(True, True)
>>> case("tsp-nonlinearity/quadratic/strong").expected
('tsp-nonlinearity',)
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any

from .measure import Bench, Record, Transient, Tsp, measure
from .network import LatentHeat, Network, ResistanceLaw

__all__ = ["DEVICES", "FAST", "FORMS", "STRENGTHS", "Case", "Device", "case", "catalogue"]

STRENGTHS = ("weak", "medium", "strong")
#: A fast subset (seconds to simulate): a clean bundle, one strong case per effect and some
#: that once got a wrong name (tests/test_validation.py runs it).
FAST = ("clean/mosfet-2", "temperature-coefficient/local-linear/strong",
        "phase-change/gaussian-junction/strong", "electrical-transient/fixed/strong",
        "tsp-nonlinearity/quadratic/strong", "sample-window/average/strong",
        "electrical-transient/fixed/medium", "tsp-nonlinearity/cubic/strong",
        "pair/temperature-coefficient+tsp-nonlinearity", "uncatalogued/convection-switch",
        "phase-change/plateau-crossed/weak", "temperature-coefficient/inner-layers/medium",
        "electrical-transient/power/weak")


@dataclass(frozen=True)
class Device:
    """A device class: its linear ladder and how its bench measures it."""

    name: str
    r_k_per_w: tuple[float, ...]
    c_j_per_k: tuple[float, ...]
    bench: Bench
    cavity_node: int  # where latent heat sits in "outer" forms

    def network(self, **changes: Any) -> Network:
        return Network(self.r_k_per_w, self.c_j_per_k, **changes)

    @property
    def top_power_w(self) -> float:
        return max(self.bench.cooling_powers_w)

    def node_rise_k(self, node: int) -> float:
        """Steady rise of ``node`` (K) at the top cooling power (linear ladder)."""
        return self.top_power_w * sum(self.r_k_per_w[node:])


DEVICES: dict[str, Device] = {d.name: d for d in (
    Device("actuator", (4.0, 12.0, 40.0, 90.0), (2e-5, 4e-4, 8e-3, 0.3),
           Bench((0.12, 0.30, 0.20), 0.10, "ambient", t_max_s=100.0, window_s=1e-4,
                 declared_window_s=1e-4, tsp=Tsp(0.65, -2.0e-3)), 2),
    Device("mosfet", (0.03, 0.08, 0.15, 0.19), (4e-4, 3e-3, 0.03, 0.3),
           Bench((40.0, 90.0, 65.0), 60.0, "case", t_max_s=3.0, window_s=2e-5,
                 declared_window_s=2e-5, tsp=Tsp(0.60, -2.2e-3)), 2),
    Device("diode", (0.15, 0.45, 0.7, 0.7), (1e-4, 1.5e-3, 0.012, 0.12),
           Bench((9.0, 22.0, 15.0), 15.0, "case", t_max_s=5.0, window_s=5e-5,
                 declared_window_s=5e-5, tsp=Tsp(0.55, -1.8e-3)), 3),
)}


@dataclass(frozen=True)
class Case:
    """One validation case: a network on a bench, and the truth the diagnosis should find.

    ``expected`` holds the catalogue names that should be named (empty: none); ``truth``
    the form and parameters; ``family`` is ``"effect"``, ``"pair"``, ``"clean"`` or
    ``"uncatalogued"``; a pair's ``parts`` are its two effects, each alone on the same device,
    bench and seed (is each detectable alone?).
    """

    name: str
    family: str
    expected: tuple[str, ...]
    device: str
    network: Network
    bench: Bench
    seed: int
    form: str = ""
    strength: str = ""
    truth: dict[str, Any] = field(default_factory=dict)
    parts: tuple[Case, ...] = ()

    def record(self) -> Record:
        """Simulate the bench (noise seeded by :attr:`seed`). The bundle says nothing of the
        truth (a held-out bundle would not): it lives in :meth:`describe`."""
        return measure(self.network, self.bench, self.seed,
                       device=f"validation {self.device} #{self.seed}")

    def describe(self) -> dict[str, Any]:
        """The truth and the bench variant, as JSON-ready data."""
        b = self.bench
        return {"case": self.name, "family": self.family, "expected": list(self.expected),
                "device": self.device, "form": self.form, "strength": self.strength,
                "truth": self.truth, "seed": self.seed,
                "bench": {"noise_k": b.noise_k, "cooling_powers_w": list(b.cooling_powers_w),
                          "per_decade": b.per_decade, "dense_pwm": b.dense_pwm,
                          "tj_steady_c": b.steady, "volts": b.volts}}


# --------------------------------------------------------------------------------------------
# the forms: each maps (device, strength index) to (network changes, bench changes, truth)
# --------------------------------------------------------------------------------------------
Form = Callable[[Device, int], tuple[dict, dict, dict]]


def _laws(dev: Device, law: ResistanceLaw, layers: range | None = None) -> tuple:
    n = len(dev.r_k_per_w)
    layers = range(n) if layers is None else layers
    return tuple(law if i in layers else None for i in range(n))


def _tc_junction(dev: Device, s: int) -> tuple[dict, dict, dict]:
    alpha = (-3e-4, -2e-3, -6e-3)[s]
    return ({"laws": _laws(dev, ResistanceLaw("linear", alpha)), "control": "junction"}, {},
            {"alpha_per_k": alpha, "t0_c": 25.0, "layers": "all", "control": "junction"})


def _tc_local(dev: Device, s: int) -> tuple[dict, dict, dict]:
    alpha = (4e-4, 2e-3, 6e-3)[s]
    return ({"laws": _laws(dev, ResistanceLaw("linear", alpha))}, {},
            {"alpha_per_k": alpha, "t0_c": 25.0, "layers": "all", "control": "local"})


def _tc_power(dev: Device, s: int) -> tuple[dict, dict, dict]:
    n_exp, beta = (0.2, 1.3, 2.5)[s], (3e-4, 1.5e-3, 3e-3)[s]
    nodes = len(dev.r_k_per_w)
    return ({"laws": _laws(dev, ResistanceLaw("power", exponent=n_exp)),
             "c_slope_per_k": (beta,) * nodes}, {},
            {"exponent": n_exp, "c_slope_per_k": beta, "t0_c": 25.0, "layers": "all",
             "control": "local"})


def _tc_outer(dev: Device, s: int) -> tuple[dict, dict, dict]:
    alpha = (-6e-4, -3e-3, -1e-2)[s]
    n = len(dev.r_k_per_w)
    return ({"laws": _laws(dev, ResistanceLaw("linear", alpha), range(n - 2, n))}, {},
            {"alpha_per_k": alpha, "t0_c": 25.0, "layers": f"{n - 2}..{n - 1}",
             "control": "local"})


def _tc_inner(dev: Device, s: int) -> tuple[dict, dict, dict]:
    """The die and its attach (the first two layers) on their own temperatures: silicon's
    conductivity falls as it warms (k ∝ T^-1.3 is +4e-3 /K of resistance near 300 K)."""
    alpha = (6e-4, 3e-3, 8e-3)[s]
    return ({"laws": _laws(dev, ResistanceLaw("linear", alpha), range(0, 2))}, {},
            {"alpha_per_k": alpha, "t0_c": 25.0, "layers": "0..1", "control": "local"})


def _latent(shape: str, where: str, share: float = 0.6) -> Form:
    """A latent heat at the junction, the inner node or the cavity node, centred at ``share``
    of that node's rise on the hottest curve (0.6: above what the lowest-power curve reaches;
    0.3: a band that every curve crosses)."""
    def form(dev: Device, s: int) -> tuple[dict, dict, dict]:
        node = {"junction": 0, "inner": 1, "outer": dev.cavity_node}[where]
        rise = dev.node_rise_k(node)
        t_c = dev.bench.tref_c + share * rise
        width = {"gaussian": 0.04, "logistic": 0.05, "plateau": 0.15}[shape] * rise
        frac = (0.015, 0.1, 0.4)[s]
        # latent heat as a fraction of the heat the node and the next two store over the rise
        sensible = sum(dev.c_j_per_k[node:node + 3]) * rise
        latent = LatentHeat(node, frac * sensible, t_c, width, shape)
        return ({"latent": (latent,)}, {},
                {"node": node, "latent_j": latent.latent_j, "t_c": round(t_c, 3),
                 "width_k": round(width, 3), "shape": shape})
    return form


def _window(mode: str) -> Form:
    def form(dev: Device, s: int) -> tuple[dict, dict, dict]:
        w = dev.bench.declared_window_s * (0.3, 1.0, 3.0)[s] * (2.0 if mode == "average" else 1.0)
        return ({}, {"window_s": w, "window_mode": mode, "declared_window_s": 0.0},
                {"window_s": w, "mode": mode, "declared_window_s": 0.0})
    return form


def _transient(kind: str) -> Form:
    def form(dev: Device, s: int) -> tuple[dict, dict, dict]:
        amp = (-0.5, -2.0, -6.0)[s]
        if kind == "power":
            amp = amp / dev.top_power_w
        tr = Transient(kind, amp, tau_s=2e-5, ring_hz=5e4)
        return ({}, {"transient": tr},
                {"kind": kind, "amplitude_k" if kind != "power" else "k_per_w": amp,
                 "tau_s": tr.tau_s, **({"ring_hz": tr.ring_hz} if kind == "ringing" else {})})
    return form


def _tsp(order: str) -> Form:
    def form(dev: Device, s: int) -> tuple[dict, dict, dict]:
        key = "quad" if order == "quadratic" else "cubic"
        value = ((1e-4, 3e-4, 8e-4) if order == "quadratic" else (2e-6, 6e-6, 1.5e-5))[s]
        tsp = replace(dev.bench.tsp, **{key: value})
        return ({}, {"tsp": tsp}, {"order": order, f"{key}_per_k{2 if key == 'quad' else 3}":
                                   value})
    return form


#: Forms added after the set was first published: their cases come after every other form's,
#: so that each earlier case keeps its seed, device and bench variant.
ADDED: tuple[tuple[str, str], ...] = (("phase-change", "plateau-crossed"),
                                      ("temperature-coefficient", "inner-layers"))

#: effect -> form -> builder.
FORMS: dict[str, dict[str, Form]] = {
    "temperature-coefficient": {"junction-linear": _tc_junction, "local-linear": _tc_local,
                                "power-law": _tc_power, "outer-layers": _tc_outer,
                                "inner-layers": _tc_inner},
    "phase-change": {"gaussian-junction": _latent("gaussian", "junction"),
                     "gaussian-outer": _latent("gaussian", "outer"),
                     "logistic-inner": _latent("logistic", "inner"),
                     "plateau-outer": _latent("plateau", "outer"),
                     "plateau-crossed": _latent("plateau", "outer", 0.3)},
    "electrical-transient": {"fixed": _transient("fixed"), "power": _transient("power"),
                             "ringing": _transient("ringing")},
    "tsp-nonlinearity": {"quadratic": _tsp("quadratic"), "cubic": _tsp("cubic")},
    "sample-window": {"end": _window("end"), "average": _window("average")},
}


def _variant(i: int) -> dict[str, Any]:
    """Bench variant number ``i``: noise, sampling, steady reading, volts, cooling curves."""
    return {"noise_k": (0.01, 0.05)[i % 2], "per_decade": (10, 5, 20)[i % 3],
            "dense_pwm": i % 4 != 1, "steady": i % 4 != 2, "volts": i % 5 == 3,
            "n_curves": (2, 3, 2, 1, 3)[i % 5]}


def _bench(dev: Device, variant: dict[str, Any], **changes: Any) -> Bench:
    v = dict(variant)
    n = v.pop("n_curves")
    powers = dev.bench.cooling_powers_w
    powers = powers[1:2] if n == 1 else powers[:n]
    return replace(dev.bench, cooling_powers_w=powers, **v, **changes)


def _single(dev: Device, effect: str, form: str, s: int, i: int) -> Case:
    net_changes, bench_changes, truth = FORMS[effect][form](dev, s)
    variant = _variant(i)
    if effect == "temperature-coefficient" or effect == "phase-change":
        variant["n_curves"] = max(variant["n_curves"], 2)
    return Case(f"{effect}/{form}/{STRENGTHS[s]}", "effect", (effect,), dev.name,
                dev.network(**net_changes), _bench(dev, variant, **bench_changes), 1000 + i,
                form, STRENGTHS[s], truth)


def _uncatalogued(i: int) -> list[Case]:
    act, mos, dio = DEVICES["actuator"], DEVICES["mosfet"], DEVICES["diode"]
    var = {**_variant(i), "n_curves": 2, "noise_k": 0.02}
    out = [
        ("ambient-drift", act, act.network(), _bench(act, var, drift_k_per_s=0.015),
         {"drift_k_per_s": 0.015, "note": "ambient warms during each cooling curve, unrecorded"}),
        ("cold-plate-drift", mos, mos.network(), _bench(mos, var, drift_k_per_s=0.5),
         {"drift_k_per_s": 0.5, "note": "case (cold plate) warms during each cooling curve"}),
        ("heater-sag", act, act.network(power_slope_per_k=4e-3), _bench(act, var),
         {"power_slope_per_k": 4e-3, "note": "heater power falls 0.4 %/K, nominal recorded"}),
        ("remounted-contact", mos, mos.network(), _bench(mos, var, contact_k_per_w=0.05),
         {"contact_k_per_w": 0.05, "note": "second cooling curve after remounting"}),
        ("remounted-contact-diode", dio, dio.network(), _bench(dio, var, contact_k_per_w=0.2),
         {"contact_k_per_w": 0.2, "note": "second cooling curve after remounting"}),
        ("convection-switch", act,
         act.network(laws=_laws(act, ResistanceLaw("switch", t0_c=34.0, drop=0.3, width_k=1.5),
                                range(3, 4))), _bench(act, var),
         {"drop": 0.3, "t_switch_c": 34.0, "width_k": 1.5,
          "note": "outer convection resistance drops 30 % above 34 degC (layer mean)"}),
    ]
    return [Case(f"uncatalogued/{name}", "uncatalogued", (), dev.name, net, bench, 3000 + i + k,
                 name, "", truth) for k, (name, dev, net, bench, truth) in enumerate(out)]


_PAIRS = (
    (("temperature-coefficient", "junction-linear"), ("sample-window", "end"), "actuator"),
    (("phase-change", "gaussian-outer"), ("electrical-transient", "fixed"), "actuator"),
    (("temperature-coefficient", "local-linear"), ("tsp-nonlinearity", "quadratic"), "diode"),
    (("phase-change", "plateau-outer"), ("sample-window", "average"), "diode"),
    (("tsp-nonlinearity", "cubic"), ("electrical-transient", "power"), "mosfet"),
    (("temperature-coefficient", "power-law"), ("electrical-transient", "ringing"), "mosfet"),
)


def _pair(k: int) -> Case:
    (e1, f1), (e2, f2), name = _PAIRS[k]
    dev = DEVICES[name]
    n1, b1, t1 = FORMS[e1][f1](dev, 2)
    n2, b2, t2 = FORMS[e2][f2](dev, 2)
    variant = {**_variant(k), "n_curves": 2, "steady": True, "volts": False}
    parts = tuple(Case(f"{e}/{f}/strong", "effect", (e,), dev.name, dev.network(**n),
                       _bench(dev, variant, **b), 2000 + k, f, "strong", t)
                  for e, f, n, b, t in ((e1, f1, n1, b1, t1), (e2, f2, n2, b2, t2)))
    return Case(f"pair/{e1}+{e2}", "pair", (e1, e2), dev.name, dev.network(**n1, **n2),
                _bench(dev, variant, **b1, **b2), 2000 + k, f"{f1}+{f2}", "strong",
                {e1: {"form": f1, **t1}, e2: {"form": f2, **t2}}, parts)


def catalogue() -> list[Case]:
    """Every case, in a fixed order: effects (form × strength), pairs, clean, uncatalogued.

    Returns
    -------
    list of Case
        Built afresh (cheap: nothing is simulated until :meth:`Case.record`).
    """
    out: list[Case] = []
    i = 0
    names = list(DEVICES)
    order = [(e, f) for e, forms in FORMS.items() for f in forms if (e, f) not in ADDED]
    for effect, form in order + list(ADDED):
        j = list(FORMS[effect]).index(form)
        for s in range(len(STRENGTHS)):
            dev = DEVICES["actuator" if effect == "phase-change" and s == 1
                          else names[(i + j) % 3]]
            out.append(_single(dev, effect, form, s, i))
            i += 1
    out += [_pair(k) for k in range(len(_PAIRS))]
    for k in range(6):
        dev = DEVICES[names[k % 3]]
        variant = _variant(k + 1)
        out.append(Case(f"clean/{dev.name}-{k + 1}", "clean", (), dev.name, dev.network(),
                        _bench(dev, variant), 4000 + k, "linear", "", {"variant": variant}))
    out += _uncatalogued(0)
    return out


def case(name: str) -> Case:
    """The case called ``name``.

    Parameters
    ----------
    name : ``effect/form/strength``, ``pair/e1+e2``, ``clean/...`` or ``uncatalogued/...``.

    Returns
    -------
    Case
        Raises KeyError for an unknown name.
    """
    for c in catalogue():
        if c.name == name:
            return c
    raise KeyError(f"no validation case {name!r}")
