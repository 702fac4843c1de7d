"""The effect registry and :class:`Effect`, a configured effect (name, form, parameter values).

Every effect, built-in or third-party, is found through the entry-point group
``spicethermal.effects`` (:data:`ENTRY_POINT_GROUP`): each entry point names an
:class:`~spicethermal.effects.base.EffectPlugin` subclass (or instance). The built-in effects
are declared in the package's own ``pyproject.toml`` exactly as another package declares its
own. :func:`register` adds one at run time (tests, notebooks).
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from types import MappingProxyType

import numpy as np

from ..core.errors import DataFormatError
from .base import DEVICE, EffectPlugin, scalar_params

__all__ = ["CATALOGUE", "ENTRY_POINT_GROUP", "Effect", "known_names", "own_kinds", "plugin",
           "register", "rival_names"]

#: Entry-point group through which every effect is registered.
ENTRY_POINT_GROUP = "spicethermal.effects"

_REGISTRY: dict[str, EffectPlugin] = {}
_LOADED = False


def register(effect: EffectPlugin | type[EffectPlugin]) -> EffectPlugin:
    """Add an effect (a plugin class or instance) to the registry, replacing one of the same
    name; returns the instance.

    Parameters
    ----------
    effect : EffectPlugin subclass or instance

    Returns
    -------
    EffectPlugin
    """
    instance = effect() if isinstance(effect, type) else effect
    if not isinstance(instance, EffectPlugin):
        raise DataFormatError(f"{effect!r} is not an effect plugin (spicethermal.effects."
                              f"base.EffectPlugin)")
    _REGISTRY[instance.name] = instance
    return instance


def _load() -> None:
    """Register every entry point of :data:`ENTRY_POINT_GROUP` once."""
    global _LOADED
    if _LOADED:
        return
    _LOADED = True
    from importlib.metadata import entry_points

    for ep in entry_points(group=ENTRY_POINT_GROUP):
        obj = ep.load()
        if isinstance(obj, EffectPlugin) or (isinstance(obj, type)
                                             and issubclass(obj, EffectPlugin)):
            register(obj)


class _Catalogue(Mapping):
    """Read-only view of the registry (plugins loaded on first use), catalogued effects and
    rivals alike."""

    def __getitem__(self, name: str) -> EffectPlugin:
        _load()
        return _REGISTRY[name]

    def __iter__(self) -> Iterator[str]:
        _load()
        return iter(sorted(_REGISTRY))

    def __len__(self) -> int:
        _load()
        return len(_REGISTRY)


#: Every registered plugin by name.
CATALOGUE: Mapping[str, EffectPlugin] = _Catalogue()


def known_names() -> list[str]:
    """Names of the catalogued effects (those a diagnosis may name and ``--effect`` takes).

    Returns
    -------
    list of str
        Sorted.

    >>> "sample-window" in known_names()
    True
    """
    return sorted(n for n, p in CATALOGUE.items() if p.traits.catalogued)


def rival_names() -> list[str]:
    """Names of the registered rivals (explanations the diagnosis weighs, never names).

    Returns
    -------
    list of str
    """
    return sorted(n for n, p in CATALOGUE.items() if not p.traits.catalogued)


def own_kinds(name: str) -> frozenset[str]:
    """The kinds of data set that effect ``name`` needs (``traits.needs``) and no other
    registered plugin can show (``traits.shown_by``): data only it changes, whatever else a
    model holds, so what it explains there no other effect can explain.

    >>> sorted(own_kinds("tsp-nonlinearity")), sorted(own_kinds("phase-change"))
    (['calibration'], [])
    """
    others = [p.traits.shown_by for n, p in CATALOGUE.items() if n != name]
    return frozenset(k for k in plugin(name).traits.needs if not any(k in o for o in others))


def plugin(name: str) -> EffectPlugin:
    """The plugin registered as ``name``; a clear error for an unknown name.

    Parameters
    ----------
    name : str

    Returns
    -------
    EffectPlugin
    """
    try:
        return CATALOGUE[name]
    except KeyError:
        raise DataFormatError(
            f"unknown effect {name!r}; known effects: {', '.join(known_names())}") from None


@dataclass(frozen=True)
class Effect:
    """One effect with validated parameters (defaults filled in) and form: what a model file
    holds. Its physics are its plugin's (:attr:`plugin`).

    >>> Effect.create("temperature-coefficient", alpha_per_k=-0.003).params["t0_c"]
    25.0
    >>> Effect.create("electrical-transient", form="ringing").to_dict()["form"]
    'ringing'
    """

    name: str
    params: Mapping[str, float] = field(default_factory=dict)
    form: str = ""

    def __post_init__(self) -> None:
        p = plugin(self.name)
        values = {}
        for key, value in self.params.items():
            if key not in p.params:
                raise DataFormatError(f"effect {self.name}: unknown parameter {key!r}; "
                                      f"expected {', '.join(p.params)}")
            spec = p.params[key]
            try:
                v = float(value)
            except (TypeError, ValueError):
                raise DataFormatError(
                    f"effect {self.name}: parameter {key} = {value!r} is not a number") from None
            if not (math.isfinite(v) and spec.low <= v <= spec.high):
                raise DataFormatError(f"effect {self.name}: parameter {key} = {value!r} "
                                      f"outside [{spec.low}, {spec.high}] {spec.unit}".rstrip())
            values[key] = v
        for key, spec in p.params.items():
            values.setdefault(key, float(spec.default))
        form = self.form or p.forms[0]
        if form not in p.forms:
            raise DataFormatError(f"effect {self.name}: form {form!r}; expected one of "
                                  f"{', '.join(p.forms)}")
        object.__setattr__(self, "params", MappingProxyType(values))
        object.__setattr__(self, "form", form)
        p.check(self)

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
        """The model-file form; ``form`` only when it is not the default."""
        out: dict = {"name": self.name, "params": self.form_params}
        if self.form != self.plugin.forms[0]:
            out["form"] = self.form
        return out

    def with_params(self, **params: float) -> Effect:
        """The same effect with some parameters changed."""
        return Effect(self.name, {**self.params, **params}, self.form)

    @property
    def default_form(self) -> str:
        """The first form of the effect's plugin (model files leave it out)."""
        return self.plugin.forms[0]

    @property
    def plugin(self) -> EffectPlugin:
        """The effect's plugin (its physics)."""
        return plugin(self.name)

    @property
    def form_params(self) -> dict[str, float]:
        """The parameters that the effect's form uses (what files and headers show).

        >>> Effect.create("temperature-coefficient", alpha_per_k=1e-3).form_params
        {'alpha_per_k': 0.001, 't0_c': 25.0}
        """
        specs = self.plugin.params
        return {k: v for k, v in self.params.items() if specs[k].used_by(self.form)}

    @property
    def kind(self) -> str:
        """``"device"`` or ``"measurement"``."""
        return self.plugin.kind

    @property
    def physical_nodes(self) -> bool:
        """True when the effect needs physical node temperatures (a Cauer ladder)."""
        p = self.plugin
        return p.kind == DEVICE and p.physical_nodes(self)  # type: ignore[attr-defined]

    def describe(self) -> str:
        """One sentence: what the effect says physically."""
        return self.plugin.describe(self)

    # -- a device effect's physics for one model (its plugin's hooks; none for the others) --
    def resistance_scales(self, t_layer_c: Sequence[float], tj_c: float) -> list[float]:
        """Factor on each layer's resistance of one ladder, given each layer's mean
        temperature and the junction's (°C); ones for an effect that changes none.

        >>> Effect.create("temperature-coefficient", alpha_per_k=0.01).resistance_scales(
        ...     [30.0, 28.0], 35.0)
        [1.1, 1.1]
        """
        t = np.asarray(t_layer_c, dtype=float)[None, :]
        p = self.plugin
        got = p.resistance_scale(self.form, scalar_params(self), t,  # type: ignore[attr-defined]
                                 np.full((1, 1), float(tj_c))) if self.kind == DEVICE else None
        return [1.0] * t.shape[1] if got is None else [float(x) for x in np.asarray(got)[0]]

    def extra_capacities(self, t_node_c: Sequence[float],
                         c_node: Sequence[float]) -> list[float]:
        """Heat capacity (J/K) the effect adds at each node of one ladder (the derivative of
        the heat it stores), given the nodes' temperatures (°C) and linear capacities.

        >>> e = Effect.create("phase-change", "gaussian", t_c=60.0, width_k=1.0, latent_j=2.0)
        >>> [round(x, 6) for x in e.extra_capacities([60.0, 40.0], [1.0, 1.0])]
        [0.797885, 0.0]
        """
        t = np.asarray(t_node_c, dtype=float)[None, :]
        got = self.plugin.stored_heat(  # type: ignore[attr-defined]
            self.form, scalar_params(self), t, np.asarray(c_node, dtype=float)[None, :]) \
            if self.kind == DEVICE else None
        return [0.0] * t.shape[1] if got is None else [float(x) for x in np.asarray(got[1])[0]]

    def spice_resistance_scale(self, layer: int, t_layer: str, t_junction: str) -> str | None:
        """The factor on layer ``layer``'s resistance as a SPICE expression, or None."""
        if self.kind != DEVICE:
            return None
        return self.plugin.spice_resistance_scale(self, layer, t_layer,  # type: ignore
                                                  t_junction)

    def spice_stored_heat(self, node: int, t_node: str, c_node: float = 0.0) -> str | None:
        """The heat stored at ``node`` beyond its linear capacity as a SPICE expression, or
        None."""
        if self.kind != DEVICE:
            return None
        return self.plugin.spice_stored_heat(self, node, t_node, c_node)  # type: ignore
