"""The effect registry: :class:`Param`, :class:`EffectSpec`, :class:`Effect` and the catalogue.

An :class:`Effect` is a catalogue name, a *form* (one of the forms its spec lists; the first
is the default) and its parameters, validated against the spec. *Device* effects change the
thermal network itself and are simulated (and exported to SPICE) as part of the model;
*measurement* effects belong to the measurement model used for comparison. A device effect's
spec carries its physics as hooks (``resistance_scale``, ``extra_capacitance``,
``latent_heat``); the effect modules of this package hold them and document each form.

Fast forward models of every effect and the fit of each effect's parameters from a bundle
live in :mod:`spicethermal.fit.effectfit`; the ranking of candidate effects in
:mod:`spicethermal.analysis.diagnose`; the SPICE export of device effects in
:mod:`spicethermal.spice.lib`.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from types import MappingProxyType

from ..core.errors import DataFormatError

DEVICE = "device"
MEASUREMENT = "measurement"
#: Entry-point group through which other packages register effects.
ENTRY_POINT_GROUP = "spicethermal.effects"


@dataclass(frozen=True)
class Param:
    """A parameter of an effect: unit, default, allowed range, the forms that use it (empty:
    every form), and whether a fit moves it (``fitted``; false for a reference such as a
    temperature at which the law is written, or a discrete choice such as a node, which the
    effect's own fit chooses and the joint refit of a model's effects holds,
    :mod:`spicethermal.fit.backfit`)."""

    unit: str
    default: float
    low: float = -math.inf
    high: float = math.inf
    doc: str = ""
    forms: tuple[str, ...] = ()
    fitted: bool = True


@dataclass(frozen=True)
class EffectSpec:
    """What the catalogue knows about one effect.

    ``forms`` lists the forms the effect takes (the first is the default). Device physics
    hooks take the :class:`Effect` first: ``resistance_scale(effect, layer, t_layer_c, tj_c)``
    (factor on the resistance of ladder layer ``layer``, 0 = the one at the junction, given
    that layer's mean temperature and the junction temperature, °C),
    ``extra_capacitance(effect, node, t_c, c_node)`` (J/K at ``node``, whose linear heat
    capacity is ``c_node``) and ``latent_heat(effect, node, t_c, c_node)`` (heat, J, stored
    beyond the linear capacity on the way up to ``t_c``: the integral of
    ``extra_capacitance``). ``physical_nodes(effect)`` is true when the physics needs
    physical node temperatures: the model is then simulated (and exported) on its ladder's
    Cauer equivalent. ``check(effect)`` may reject parameters that do not fit the form
    (raise :class:`~spicethermal.core.errors.DataFormatError`). ``fit`` names the function that
    fits the effect to a bundle, ``"module:function"`` (imported when first used, as an entry
    point is; see :mod:`spicethermal.fit.effectfit`).

    Their SPICE renderings are the same physics as dialect-neutral behavioural expressions
    (``+ - * /``, ``EXP``, ``LOG``, ``MAX``, ``MIN``, ``PWR``; temperatures in °C):
    ``spice_resistance_scale(effect, layer, t_layer, t_junction)`` returns the factor on the
    resistance of ladder layer ``layer`` (0 = the one at the junction) given the expressions
    of that layer's temperature and the junction temperature, or ``None`` when the layer is
    untouched; ``spice_stored_heat(effect, node, t_node, c_node)`` returns the heat (J)
    stored at
    ``node`` beyond its linear capacity as a function of the node's temperature expression
    (the integral of ``extra_capacitance``), or ``None``. The SPICE writer asks every device
    effect for these and knows no effect by name.
    """

    name: str
    kind: str
    summary: str
    params: Mapping[str, Param]
    forms: tuple[str, ...] = ("standard",)
    resistance_scale: Callable[..., float] | None = None
    extra_capacitance: Callable[..., float] | None = None
    latent_heat: Callable[..., float] | None = None
    spice_resistance_scale: Callable[..., str | None] | None = None
    spice_stored_heat: Callable[..., str | None] | None = None
    physical_nodes: Callable[..., bool] | None = None
    check: Callable[..., None] | None = None
    fit: str = ""

    @classmethod
    def create(cls, name: str, kind: str, summary: str, forms: tuple[str, ...] = ("standard",),
               **params: Param) -> EffectSpec:
        """Named constructor with the parameters as keywords.

        >>> EffectSpec.create("toy", MEASUREMENT, "a toy", gain=Param("", 1.0)).forms
        ('standard',)
        """
        return cls(name, kind, summary, MappingProxyType(params), tuple(forms))


_REGISTRY: dict[str, EffectSpec] = {}
_PLUGINS_LOADED = False


def register(effect_spec: EffectSpec) -> EffectSpec:
    """Add ``effect_spec`` to the catalogue (replacing one of the same name); returns it.

    Parameters
    ----------
    effect_spec : EffectSpec
        The effect's specification.

    Returns
    -------
    EffectSpec
        ``effect_spec`` itself (usable as a decorator-style call).
    """
    if effect_spec.kind not in (DEVICE, MEASUREMENT):
        raise DataFormatError(f"effect {effect_spec.name}: kind {effect_spec.kind!r} must be "
                              f"{DEVICE} or {MEASUREMENT}")
    _REGISTRY[effect_spec.name] = effect_spec
    return effect_spec


def _load_plugins() -> None:
    """Load the entry points of :data:`ENTRY_POINT_GROUP` once (a module registers itself on
    import; an entry point that names an :class:`EffectSpec` is registered here)."""
    global _PLUGINS_LOADED
    if _PLUGINS_LOADED:
        return
    _PLUGINS_LOADED = True
    from importlib.metadata import entry_points

    for ep in entry_points(group=ENTRY_POINT_GROUP):
        obj = ep.load()
        if isinstance(obj, EffectSpec):
            register(obj)


class _Catalogue(Mapping):
    """Read-only view of the registry that loads the plugins on first use."""

    def __getitem__(self, name: str) -> EffectSpec:
        _load_plugins()
        return _REGISTRY[name]

    def __iter__(self) -> Iterator[str]:
        _load_plugins()
        return iter(sorted(_REGISTRY))

    def __len__(self) -> int:
        _load_plugins()
        return len(_REGISTRY)


#: Every registered effect by name (built-in ones and plugins).
CATALOGUE: Mapping[str, EffectSpec] = _Catalogue()


def known_names() -> list[str]:
    """Effect names of the catalogue, sorted.

    Returns
    -------
    list of str
        The registered effect names.
    """
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
    """One effect with validated parameters (defaults filled from the catalogue) and form.

    >>> Effect.create("temperature-coefficient", alpha_per_k=-0.003).params["t0_c"]
    25.0
    >>> Effect.create("electrical-transient", form="ringing").to_dict()["form"]
    'ringing'
    """

    name: str
    params: Mapping[str, float] = field(default_factory=dict)
    form: str = ""

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
        form = self.form or s.forms[0]
        if form not in s.forms:
            raise DataFormatError(f"effect {self.name}: form {form!r}; expected one of "
                                  f"{', '.join(s.forms)}")
        object.__setattr__(self, "params", MappingProxyType(values))
        object.__setattr__(self, "form", form)
        if s.check is not None:
            s.check(self)

    @classmethod
    def create(cls, name: str, form: str = "", **params: float) -> Effect:
        """Named constructor: ``Effect.create("sample-window", window_s=1e-4)``."""
        return cls(name, params, form)

    @classmethod
    def from_dict(cls, data: Mapping) -> Effect:
        """From the model-file form ``{"name": ..., "params": {...}, "form": ...}`` (form
        optional)."""
        if not isinstance(data, Mapping) or "name" not in data:
            raise DataFormatError("effect entry needs a 'name'")
        params = data.get("params", {})
        if not isinstance(params, Mapping):
            raise DataFormatError(f"effect {data['name']}: 'params' must be an object")
        form = data.get("form", "")
        if not isinstance(form, str):
            raise DataFormatError(f"effect {data['name']}: 'form' must be a string")
        return cls(str(data["name"]), dict(params), form)

    def to_dict(self) -> dict:
        """The model-file form; ``form`` only when it is not the default (older readers and
        golden files keep working)."""
        out: dict = {"name": self.name, "params": self.form_params}
        if self.form != self.default_form:
            out["form"] = self.form
        return out

    @property
    def default_form(self) -> str:
        """The first form of the effect's spec (files leave it out)."""
        return spec(self.name).forms[0]

    @property
    def form_params(self) -> dict[str, float]:
        """The parameters that the effect's form uses (what files and headers show).

        >>> Effect.create("temperature-coefficient", alpha_per_k=1e-3).form_params
        {'alpha_per_k': 0.001, 't0_c': 25.0}
        """
        specs = spec(self.name).params
        return {k: v for k, v in self.params.items()
                if not specs[k].forms or self.form in specs[k].forms}

    @property
    def kind(self) -> str:
        """``"device"`` or ``"measurement"``."""
        return spec(self.name).kind

    # -- device physics (the spec's hooks; neutral when the effect has none) -------------
    def resistance_scale(self, layer: int, t_layer_c: float, tj_c: float) -> float:
        """Factor on layer ``layer``'s resistance when the layer's mean temperature is
        ``t_layer_c`` and the junction's ``tj_c`` (1 if not applicable)."""
        hook = spec(self.name).resistance_scale
        return 1.0 if hook is None else float(hook(self, layer, t_layer_c, tj_c))

    @property
    def physical_nodes(self) -> bool:
        """True when the effect needs physical node temperatures (a Cauer ladder)."""
        hook = spec(self.name).physical_nodes
        return False if hook is None else bool(hook(self))

    def latent_heat(self, node: int, t_c: float, c_node: float = 0.0) -> float:
        """Heat (J) stored at ``node`` beyond its linear capacity ``c_node`` on the way up to
        ``t_c`` (0 if not applicable)."""
        hook = spec(self.name).latent_heat
        return 0.0 if hook is None else float(hook(self, node, t_c, c_node))

    def extra_capacitance(self, node: int, t_c: float, c_node: float = 0.0) -> float:
        """Extra heat capacity (J/K) at ``node`` (linear capacity ``c_node``) and temperature
        ``t_c`` (0 if not applicable).

        >>> e = Effect.create("phase-change", t_c=64.7, width_k=2.0, latent_j=1.0, node=0)
        >>> round(e.extra_capacitance(0, 64.7) * 4 * e.logistic_scale_k, 12)
        1.0
        >>> e.extra_capacitance(0, 1e6)  # far from the band: zero, not an overflow
        0.0
        """
        hook = spec(self.name).extra_capacitance
        return 0.0 if hook is None else float(hook(self, node, t_c, c_node))

    # -- SPICE renderings of the same physics (``None`` where the effect does not apply) ------
    def spice_resistance_scale(self, layer: int, t_layer: str, t_junction: str) -> str | None:
        """SPICE expression of the factor on layer ``layer``'s resistance, or ``None``.

        >>> e = Effect.create("temperature-coefficient", alpha_per_k=-3e-3)
        >>> e.spice_resistance_scale(0, "V(N1)", "V(TJ)")
        'MAX(0.05,1+(-0.003)*(V(TJ)-(25.0)))'
        >>> Effect.create("sample-window").spice_resistance_scale(0, "V(N1)", "V(TJ)") is None
        True
        """
        hook = spec(self.name).spice_resistance_scale
        return None if hook is None else hook(self, layer, t_layer, t_junction)

    def spice_stored_heat(self, node: int, t_node: str, c_node: float = 0.0) -> str | None:
        """SPICE expression of the heat (J) stored at ``node`` beyond its linear capacity
        ``c_node``.

        >>> e = Effect.create("phase-change", t_c=60.0, width_k=1.0, latent_j=2.0, node=1)
        >>> e.spice_stored_heat(0, "V(TJ)") is None
        True
        """
        hook = spec(self.name).spice_stored_heat
        return None if hook is None else hook(self, node, t_node, c_node)

    @property
    def logistic_scale_k(self) -> float:
        """Scale ``s`` of a logistic band of standard deviation ``width_k``: ``width_k·√3/π``."""
        return self.params.get("width_k", 0.0) * math.sqrt(3.0) / math.pi
