"""The catalogue of physical effects and measurement artefacts (names are part of the contract).

An :class:`Effect` is a name and its parameters, validated against the catalogue. *Device*
effects change the thermal network itself and are simulated (and exported to SPICE) as part of
the model; *measurement* effects belong to the measurement model used for comparison.

Device physics, in terms of absolute temperatures (°C):

* ``temperature-coefficient``: every resistance of the ladder scales with the junction
  temperature, ``R(T) = R0 · (1 + alpha_per_k · (Tj − t0_c))`` (clipped at 5 % of R0).
* ``phase-change``: latent heat ``latent_j`` absorbed across a band centred at ``t_c`` adds
  heat capacity from node ``node`` (index into the ladder, 0 = junction) to the reference.
  The band is logistic with standard deviation ``width_k``: the heat absorbed up to T is
  ``latent_j / (1 + exp(−(T − t_c)/s))`` with ``s = width_k·√3/π``, and the extra capacity is
  its derivative. (A logistic band rather than a Gaussian one: SPICE has no erf, and writing
  the element as ``ddt`` of this charge keeps ngspice stable where ``C(V)·ddt(V)`` is not.)

Measurement models (applied to a model temperature ``T`` to get what the bench reads):

* ``sample-window``: the PWM reading is the junction temperature at the end of a power-off
  window of ``window_s`` that starts when an on-phase ends (``ThermalModel.pwm(window_s=)``);
* ``electrical-transient``: a cooling reading at ``t`` after the cut is off by
  ``amplitude_k · exp(−5 t / masked_s)`` (the fix is masking and √t extrapolation,
  :mod:`spicethermal.curves`);
* ``tsp-nonlinearity``: readings through a linear calibration are ``T + q (T − t_cal_c)²``
  (``q = quad_k_per_k2``); the calibration's own residuals bow accordingly.

Fast exact forward models of every effect, the fit of each effect's parameters from a bundle
and ``fit_with_effects`` live in :mod:`spicethermal.effectfit`; the ranking of candidate
effects in :mod:`spicethermal.diagnose`; the SPICE export of device effects in
:mod:`spicethermal.spice`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType

from .errors import DataFormatError

DEVICE = "device"
MEASUREMENT = "measurement"


@dataclass(frozen=True)
class Param:
    """A parameter of an effect: unit, default and allowed range."""

    unit: str
    default: float
    low: float = -math.inf
    high: float = math.inf
    doc: str = ""


@dataclass(frozen=True)
class EffectSpec:
    """What the catalogue knows about one effect."""

    name: str
    kind: str
    summary: str
    params: Mapping[str, Param]


def _spec(name: str, kind: str, summary: str, **params: Param) -> EffectSpec:
    return EffectSpec(name, kind, summary, MappingProxyType(params))


CATALOGUE: Mapping[str, EffectSpec] = MappingProxyType({s.name: s for s in (
    _spec("temperature-coefficient", DEVICE,
          "Rth changes with temperature, R(T) = R0·(1 + α·(T − T0))",
          alpha_per_k=Param("1/K", 0.0, -0.02, 0.02, "relative change of every R per kelvin"),
          t0_c=Param("°C", 25.0, -273.15, 1000.0, "temperature at which R = R0")),
    _spec("phase-change", DEVICE,
          "latent heat of the cavity fluid: extra heat capacity over a temperature band",
          t_c=Param("°C", 64.7, -273.15, 1000.0, "centre of the band (methanol boils at 64.7 °C)"),
          width_k=Param("K", 2.0, 0.05, 100.0, "standard deviation of the band"),
          latent_j=Param("J", 0.0, 0.0, 1e6, "latent heat absorbed across the band"),
          node=Param("", 0, 0, 1000, "ladder node holding the fluid (0 = junction)")),
    _spec("sample-window", MEASUREMENT,
          "power is interrupted for a window before each PWM temperature sample",
          window_s=Param("s", 1e-4, 0.0, 1.0, "length of the power-off sample window")),
    _spec("electrical-transient", MEASUREMENT,
          "the electrical transient after power cut-off masks the first part of a cooling curve",
          masked_s=Param("s", 1e-4, 0.0, 1.0, "span after the cut during which readings are wrong"),
          amplitude_k=Param("K", 0.0, -1e3, 1e3, "error of the reading at the cut, decaying"
                            " over the masked span")),
    _spec("tsp-nonlinearity", MEASUREMENT,
          "the TSP (diode forward voltage) is not linear in T",
          quad_k_per_k2=Param("1/K", 0.0, -1.0, 1.0, "reading error per (T − T_cal)², K/K²"),
          t_cal_c=Param("°C", 25.0, -273.15, 1000.0, "centre of the linear calibration")),
)})


def known_names() -> list[str]:
    """Effect names of the catalogue, sorted."""
    return sorted(CATALOGUE)


def spec(name: str) -> EffectSpec:
    """Catalogue entry of ``name``; a clear error for an unknown name."""
    try:
        return CATALOGUE[name]
    except KeyError:
        raise DataFormatError(
            f"unknown effect {name!r}; known effects: {', '.join(known_names())}") from None


@dataclass(frozen=True)
class Effect:
    """One effect with validated parameters (defaults filled from the catalogue).

    >>> Effect.create("temperature-coefficient", alpha_per_k=-0.003).params["t0_c"]
    25.0
    """

    name: str
    params: Mapping[str, float] = field(default_factory=dict)

    def __post_init__(self) -> None:
        s = spec(self.name)
        values = {}
        for key, value in self.params.items():
            if key not in s.params:
                raise DataFormatError(f"effect {self.name}: unknown parameter {key!r}; "
                                      f"expected {', '.join(s.params)}")
            p = s.params[key]
            try:
                v = float(value)
            except (TypeError, ValueError):
                raise DataFormatError(
                    f"effect {self.name}: parameter {key} = {value!r} is not a number") from None
            if not (math.isfinite(v) and p.low <= v <= p.high):
                raise DataFormatError(f"effect {self.name}: parameter {key} = {value!r} "
                                      f"outside [{p.low}, {p.high}] {p.unit}".rstrip())
            values[key] = v
        for key, p in s.params.items():
            values.setdefault(key, float(p.default))
        object.__setattr__(self, "params", MappingProxyType(values))

    @classmethod
    def create(cls, name: str, **params: float) -> Effect:
        """Named constructor: ``Effect.create("sample-window", window_s=1e-4)``."""
        return cls(name, params)

    @classmethod
    def from_dict(cls, data: Mapping) -> Effect:
        """From the model-file form ``{"name": ..., "params": {...}}``."""
        if not isinstance(data, Mapping) or "name" not in data:
            raise DataFormatError("effect entry needs a 'name'")
        params = data.get("params", {})
        if not isinstance(params, Mapping):
            raise DataFormatError(f"effect {data['name']}: 'params' must be an object")
        return cls(str(data["name"]), dict(params))

    def to_dict(self) -> dict:
        return {"name": self.name, "params": dict(self.params)}

    @property
    def kind(self) -> str:
        """``"device"`` or ``"measurement"``."""
        return spec(self.name).kind

    # -- device physics ------------------------------------------------------------------
    def resistance_scale(self, tj_c: float) -> float:
        """Factor on every resistance at junction temperature ``tj_c`` (1 if not applicable)."""
        if self.name != "temperature-coefficient":
            return 1.0
        p = self.params
        return max(0.05, 1.0 + p["alpha_per_k"] * (tj_c - p["t0_c"]))

    def latent_heat(self, node: int, t_c: float) -> float:
        """Latent heat (J) absorbed at ``node`` on the way up to ``t_c`` (0 if not applicable)."""
        if self.name != "phase-change" or node != int(self.params["node"]):
            return 0.0
        z = (t_c - self.params["t_c"]) / self.logistic_scale_k
        return self.params["latent_j"] * 0.5 * (1.0 + math.tanh(0.5 * z))

    @property
    def logistic_scale_k(self) -> float:
        """Scale ``s`` of the logistic phase-change band, ``width_k·√3/π``."""
        return self.params["width_k"] * math.sqrt(3.0) / math.pi

    def extra_capacitance(self, node: int, t_c: float) -> float:
        """Extra heat capacity (J/K) at ``node`` and temperature ``t_c`` (0 if not applicable).

        >>> e = Effect.create("phase-change", t_c=64.7, width_k=2.0, latent_j=1.0, node=0)
        >>> round(e.extra_capacitance(0, 64.7) * 4 * e.logistic_scale_k, 12)
        1.0
        """
        if self.name != "phase-change" or node != int(self.params["node"]):
            return 0.0
        s = self.logistic_scale_k
        z = (t_c - self.params["t_c"]) / s
        return self.params["latent_j"] / (4.0 * s * math.cosh(0.5 * z) ** 2)
