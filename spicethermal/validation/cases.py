"""Device classes, validation cases with their truth, and the fixed catalogue.

Device classes (:data:`DEVICES`, Cauer layers junction first), each with its own bench
(powers, sampling, PWM grid, sample window, noise levels, TSP):

* ``actuator`` — the paper's thermopneumatic actuator, ambient reference, Rth = 146 K/W, a
  slow cavity (node 2 holds the fluid), τ from ~80 µs to ~30 s, 0.1–0.3 W;
* ``mosfet`` — a power MOSFET measured junction-to-case on a cold plate, Rth ≈ 0.45 K/W,
  40–90 W;
* ``diode`` — a power diode measured junction-to-case, Rth = 2 K/W, 9–22 W;
* ``mems`` — a MEMS micro-heater on its membrane, ambient reference, Rth = 5000 K/W, τ from
  ~10 µs to ~0.6 s, 6–18 mW, read through the heater's own resistance (a TSP rising with
  temperature), PWM from 20 Hz to 50 kHz;
* ``igbt`` — an IGBT module junction-to-heatsink, Rth = 0.1 K/W, τ from ~1 ms to ~60 s,
  200–500 W, PWM from 1 Hz to 1 kHz, a 100 µs sample window.

A :class:`Case` is a network on a bench with its truth and the verdicts a diagnosis may give
(:attr:`Case.acceptable`; :data:`ACCEPTABLE` lists them, with their reasons, for physics that
is in no catalogue). :func:`catalogue` is the fixed set on the first three classes: every
catalogued effect in several *forms* (:data:`FORMS`), each weak, medium and strong; then
pairs, clean bundles and physics that is in no catalogue. Bench variants (noise, sampling,
missing ``tj_steady_c``, curves in volts, one to three cooling curves) rotate over the cases.
Seeds are fixed: the same case is the same bundle on every run. Random draws over every class
and kind of physics are in :mod:`.draws`, linear devices of other shapes in :mod:`.linear`.

>>> cases = catalogue()
>>> len(cases) >= 60, len({c.name for c in cases}) == len(cases)
(True, True)
>>> case(cases[0].name).acceptable == cases[0].expected
True
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any

from .measure import Bench, Record, Transient, Tsp, measure
from .network import LatentHeat, Network, ResistanceLaw

__all__ = ["ACCEPTABLE", "CATALOGUE_NAMES", "DEVICES", "FAST", "FORMS", "STRENGTHS", "Case",
           "Device", "acceptable_for", "bench_for", "bench_variant", "case", "catalogue", "laws_on"]

#: The names a diagnosis may give (the package's catalogue, spelt here on their own).
CATALOGUE_NAMES = ("temperature-coefficient", "phase-change", "electrical-transient",
                   "tsp-nonlinearity", "sample-window")
NONE = "none"

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
    noise_levels: tuple[float, float] = (0.01, 0.05)  # K: a quiet and a noisy bench
    transient_tau_s: float = 2e-5  # how long its electrical transient lasts

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
    Device("mems", (400.0, 2200.0, 1800.0, 600.0), (2.5e-8, 2e-7, 1e-5, 1e-3),
           Bench((6e-3, 18e-3, 12e-3), 15e-3, "ambient", t_max_s=3.0, window_s=5e-6,
                 declared_window_s=5e-6, tsp=Tsp(0.50, 1.6e-3), cal_step_k=10.0,
                 freqs_hz=(20.0, 100.0, 500.0, 2e3, 1e4, 5e4)), 2,
           noise_levels=(0.02, 0.1), transient_tau_s=2e-6),
    Device("igbt", (0.012, 0.025, 0.035, 0.028), (0.083, 2.0, 57.0, 2100.0),
           Bench((200.0, 500.0, 350.0), 400.0, "case", t_min_s=1e-5, t_max_s=200.0,
                 window_s=1e-4, declared_window_s=1e-4, tsp=Tsp(0.62, -2.4e-3),
                 freqs_hz=(1.0, 5.0, 20.0, 50.0, 200.0, 1e3)), 2,
           noise_levels=(0.03, 0.1), transient_tau_s=5e-5),
)}
#: The classes of the fixed catalogue (its cases keep their devices and seeds).
CATALOGUE_DEVICES = ("actuator", "mosfet", "diode")

#: Physics that is in no catalogue: the verdicts a diagnosis may give (``"none"``: no effect
#: named; the first name of a verdict must be one of them, and any name outside them is a
#: wrong name) and why. The names given besides ``"none"`` are the defensible near-catalogue
#: names; where ``"none"`` is absent, a null verdict on a detectable case is a miss (the
#: closest catalogued form lowers the error decisively, and naming it is the user's next step).
ACCEPTABLE: dict[str, tuple[tuple[str, ...], str]] = {
    "linear": ((NONE,), "a linear network of any shape is not an effect"),
    "exp": (("temperature-coefficient",), "an exponential R(T): a temperature coefficient "
            "whose form the catalogue's linear and power laws only approximate"),
    "quadratic": (("temperature-coefficient",), "a quadratic R(T): an approximate form of "
                  "the catalogue's coefficient"),
    "saturating": (("temperature-coefficient",), "an R(T) that levels off within the range: "
                   "an approximate form of the catalogue's coefficient"),
    "kmin": ((NONE, "temperature-coefficient"), "a conductivity with a minimum inside the "
             "range: R(T) rises then falls, which no monotone catalogued form follows; the "
             "coefficient is the closest, and a null verdict is acceptable too"),
    "hysteresis": (("phase-change",), "melting and solidifying at different temperatures: a "
                   "latent heat whose cooling band is not its heating band"),
    "skewed": (("phase-change",), "a band with a sharp upper edge and a long tail below: a "
               "latent heat of a shape the catalogue only approximates"),
    "two-bands": (("phase-change",), "two latent heats (two transitions): the catalogue "
                  "holds one band per effect"),
    "trigger-delay": ((NONE, "electrical-transient"), "the cooling curves' time axis starts "
                      "late: the first readings lack the drop the delay hides, as readings "
                      "an electrical transient spoils"),
    "adc-gain-offset": ((NONE,), "every reading but the calibration's scaled and shifted: no "
                        "catalogued form (a TSP non-linearity is a curvature, which the "
                        "calibration refutes)"),
    "reference-drift": ((NONE,), "the reference warms or cools during each cooling curve, "
                        "unrecorded: no catalogued form"),
    "heater-sag": ((NONE, "temperature-coefficient"), "a heating power that falls with the "
                   "junction temperature gives the steady and PWM readings of a junction "
                   "coefficient; only the cooling curves' shape tells them apart"),
    "remount": ((NONE,), "the outer resistance changed between cooling curves whose powers are "
                "not in the order of mounting: no temperature law gives it"),
    "remount-two": ((NONE, "temperature-coefficient"), "with two cooling curves, an outer "
                    "resistance changed between them is what an outer layer's coefficient "
                    "gives at their two temperatures"),
    "convection-switch": ((NONE, "temperature-coefficient"), "a resistance that steps down "
                          "above a temperature is a temperature dependence; a coefficient is "
                          "its approximate form"),
}


def acceptable_for(form: str) -> tuple[str, ...]:
    """The acceptable verdicts of physics ``form`` that is in no catalogue (:data:`ACCEPTABLE`).

    >>> acceptable_for("trigger-delay")
    ('electrical-transient', 'none')
    """
    return tuple(sorted(ACCEPTABLE[form][0]))


@dataclass(frozen=True)
class Case:
    """One validation case: a network on a bench, and the truth the diagnosis should find.

    ``expected`` holds the catalogue names that should be named (empty: none); ``truth``
    the form and parameters; ``family`` is ``"effect"``, ``"pair"``, ``"clean"``,
    ``"linear"`` or ``"uncatalogued"``, and ``kind`` a finer grouping for reports (default
    the family); a pair's ``parts`` are its two effects, each alone on the same device, bench
    and seed (is each detectable alone?). ``acceptable`` holds the verdicts that are not
    wrong, sorted (``"none"``: no effect named): by default the expected effects, or ``none``
    when nothing is expected.
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
    acceptable: tuple[str, ...] = ()
    kind: str = ""

    def __post_init__(self) -> None:
        accept = self.acceptable or self.expected or (NONE,)
        unknown = set(accept) - set(CATALOGUE_NAMES) - {NONE}
        if unknown:
            raise ValueError(f"case {self.name}: unknown verdicts {sorted(unknown)}")
        object.__setattr__(self, "acceptable", tuple(sorted(accept)))
        object.__setattr__(self, "kind", self.kind or self.family)

    def record(self) -> Record:
        """Simulate the bench (noise seeded by :attr:`seed`). The bundle says nothing of the
        truth (a held-out bundle would not): it lives in :meth:`describe`."""
        return measure(self.network, self.bench, self.seed,
                       device=f"validation {self.device} #{self.seed}")

    def describe(self) -> dict[str, Any]:
        """The truth and the bench variant, as JSON-ready data."""
        b = self.bench
        return {"case": self.name, "family": self.family, "kind": self.kind,
                "expected": list(self.expected), "acceptable": list(self.acceptable),
                "device": self.device, "form": self.form, "strength": self.strength,
                "truth": self.truth, "seed": self.seed,
                "bench": {"noise_k": b.noise_k, "cooling_powers_w": list(b.cooling_powers_w),
                          "per_decade": b.per_decade, "dense_pwm": b.dense_pwm,
                          "tj_steady_c": b.steady, "volts": b.volts}}


# --------------------------------------------------------------------------------------------
# the forms: each maps (device, strength index) to (network changes, bench changes, truth)
# --------------------------------------------------------------------------------------------
Form = Callable[[Device, int], tuple[dict, dict, dict]]


def laws_on(dev: Device, law: ResistanceLaw, layers: range | None = None) -> tuple:
    """``law`` on the layers ``layers`` of ``dev`` (all by default), None elsewhere."""
    n = len(dev.r_k_per_w)
    layers = range(n) if layers is None else layers
    return tuple(law if i in layers else None for i in range(n))


def _tc_junction(dev: Device, s: int) -> tuple[dict, dict, dict]:
    alpha = (-3e-4, -2e-3, -6e-3)[s]
    return ({"laws": laws_on(dev, ResistanceLaw("linear", alpha)), "control": "junction"}, {},
            {"alpha_per_k": alpha, "t0_c": 25.0, "layers": "all", "control": "junction"})


def _tc_local(dev: Device, s: int) -> tuple[dict, dict, dict]:
    alpha = (4e-4, 2e-3, 6e-3)[s]
    return ({"laws": laws_on(dev, ResistanceLaw("linear", alpha))}, {},
            {"alpha_per_k": alpha, "t0_c": 25.0, "layers": "all", "control": "local"})


def _tc_power(dev: Device, s: int) -> tuple[dict, dict, dict]:
    n_exp, beta = (0.2, 1.3, 2.5)[s], (3e-4, 1.5e-3, 3e-3)[s]
    nodes = len(dev.r_k_per_w)
    return ({"laws": laws_on(dev, ResistanceLaw("power", exponent=n_exp)),
             "c_slope_per_k": (beta,) * nodes}, {},
            {"exponent": n_exp, "c_slope_per_k": beta, "t0_c": 25.0, "layers": "all",
             "control": "local"})


def _tc_outer(dev: Device, s: int) -> tuple[dict, dict, dict]:
    alpha = (-6e-4, -3e-3, -1e-2)[s]
    n = len(dev.r_k_per_w)
    return ({"laws": laws_on(dev, ResistanceLaw("linear", alpha), range(n - 2, n))}, {},
            {"alpha_per_k": alpha, "t0_c": 25.0, "layers": f"{n - 2}..{n - 1}",
             "control": "local"})


def _tc_inner(dev: Device, s: int) -> tuple[dict, dict, dict]:
    """The die and its attach (the first two layers) on their own temperatures: silicon's
    conductivity falls as it warms (k ∝ T^-1.3 is +4e-3 /K of resistance near 300 K)."""
    alpha = (6e-4, 3e-3, 8e-3)[s]
    return ({"laws": laws_on(dev, ResistanceLaw("linear", alpha), range(0, 2))}, {},
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


def bench_variant(i: int) -> dict[str, Any]:
    """Bench variant number ``i``: noise, sampling, steady reading, volts, cooling curves."""
    return {"noise_k": (0.01, 0.05)[i % 2], "per_decade": (10, 5, 20)[i % 3],
            "dense_pwm": i % 4 != 1, "steady": i % 4 != 2, "volts": i % 5 == 3,
            "n_curves": (2, 3, 2, 1, 3)[i % 5]}


def bench_for(dev: Device, variant: dict[str, Any], **changes: Any) -> Bench:
    """``dev``'s bench in ``variant`` (:func:`bench_variant`'s keys; ``n_curves`` 1 takes the
    highest-power curve, else the first ``n_curves``), with ``changes`` (which may give the
    cooling powers themselves)."""
    v = dict(variant)
    n = v.pop("n_curves")
    powers = dev.bench.cooling_powers_w
    powers = powers[1:2] if n == 1 else powers[:n]
    return replace(dev.bench, **{"cooling_powers_w": powers, **v, **changes})


#: The earlier names, kept for the scripts and tests that still import them.
_bench, _laws, _variant = bench_for, laws_on, bench_variant


def _single(dev: Device, effect: str, form: str, s: int, i: int) -> Case:
    net_changes, bench_changes, truth = FORMS[effect][form](dev, s)
    variant = bench_variant(i)
    if effect == "temperature-coefficient" or effect == "phase-change":
        variant["n_curves"] = max(variant["n_curves"], 2)
    return Case(f"{effect}/{form}/{STRENGTHS[s]}", "effect", (effect,), dev.name,
                dev.network(**net_changes), bench_for(dev, variant, **bench_changes), 1000 + i,
                form, STRENGTHS[s], truth, kind=f"effect/{effect}")


def _uncatalogued(i: int) -> list[Case]:
    act, mos, dio = DEVICES["actuator"], DEVICES["mosfet"], DEVICES["diode"]
    var = {**bench_variant(i), "n_curves": 2, "noise_k": 0.02}
    out = [
        ("ambient-drift", act, act.network(), bench_for(act, var, drift_k_per_s=0.015),
         {"drift_k_per_s": 0.015, "note": "ambient warms during each cooling curve, unrecorded"}),
        ("cold-plate-drift", mos, mos.network(), bench_for(mos, var, drift_k_per_s=0.5),
         {"drift_k_per_s": 0.5, "note": "case (cold plate) warms during each cooling curve"}),
        ("heater-sag", act, act.network(power_slope_per_k=4e-3), bench_for(act, var),
         {"power_slope_per_k": 4e-3, "note": "heater power falls 0.4 %/K, nominal recorded"}),
        ("remounted-contact", mos, mos.network(), bench_for(mos, var, contact_k_per_w=0.05),
         {"contact_k_per_w": 0.05, "note": "second cooling curve after remounting"}),
        ("remounted-contact-diode", dio, dio.network(), bench_for(dio, var, contact_k_per_w=0.2),
         {"contact_k_per_w": 0.2, "note": "second cooling curve after remounting"}),
        ("convection-switch", act,
         act.network(laws=laws_on(act, ResistanceLaw("switch", t0_c=34.0, drop=0.3, width_k=1.5),
                                range(3, 4))), bench_for(act, var),
         {"drop": 0.3, "t_switch_c": 34.0, "width_k": 1.5,
          "note": "outer convection resistance drops 30 % above 34 degC (layer mean)"}),
    ]
    because = {"ambient-drift": "reference-drift", "cold-plate-drift": "reference-drift",
               "remounted-contact": "remount-two", "remounted-contact-diode": "remount-two"}
    return [Case(f"uncatalogued/{name}", "uncatalogued", (), dev.name, net, bench, 3000 + i + k,
                 name, "", truth, acceptable=acceptable_for(because.get(name, name)),
                 kind=f"uncatalogued/{name}")
            for k, (name, dev, net, bench, truth) in enumerate(out)]


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
    variant = {**bench_variant(k), "n_curves": 2, "steady": True, "volts": False}
    parts = tuple(Case(f"{e}/{f}/strong", "effect", (e,), dev.name, dev.network(**n),
                       bench_for(dev, variant, **b), 2000 + k, f, "strong", t)
                  for e, f, n, b, t in ((e1, f1, n1, b1, t1), (e2, f2, n2, b2, t2)))
    return Case(f"pair/{e1}+{e2}", "pair", (e1, e2), dev.name, dev.network(**n1, **n2),
                bench_for(dev, variant, **b1, **b2), 2000 + k, f"{f1}+{f2}", "strong",
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
    names = list(CATALOGUE_DEVICES)
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
        variant = bench_variant(k + 1)
        out.append(Case(f"clean/{dev.name}-{k + 1}", "clean", (), dev.name, dev.network(),
                        bench_for(dev, variant), 4000 + k, "linear", "", {"variant": variant}))
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
