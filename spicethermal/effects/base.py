"""The effect plugin interface: what an effect owns, as typed classes.

An effect is one class (:class:`DeviceEffect` or :class:`MeasurementEffect`) in one module. It
owns everything about itself:

* its parameters (:class:`Param`: unit, default, bounds, whether a fit moves them, the scale a
  fit uses) and its forms;
* ``variants(form, evidence)``: the discrete choices a fit tries in turn (a node, a subset of
  layers), and ``guess(form, fixed, evidence)``: starting values from what the model so far
  leaves unexplained (:class:`Evidence`);
* its physics in one place, used by simulation, fitting, diagnosis and export alike: a device
  effect gives the one network simulator (:mod:`spicethermal.engines.network`) a factor on
  each layer's resistance and heat stored at each node beyond its linear capacity; a
  measurement effect turns the true junction temperature into what the bench reads, per kind
  of data set (:meth:`MeasurementEffect.read`);
* its SPICE rendering (dialect-neutral behavioural expressions);
* its traits as data (:class:`Traits`): the data sets that can show it, the data sets without
  which it cannot be told from other effects, its relative cost, and what it can be confused
  with and which measurement tells them apart.

Every hook is vectorised over a batch: parameters arrive as a mapping of arrays of shape
``(B, 1)`` (``B`` parameter sets, fitted side by side), temperatures as ``(B, n)``.

A configured effect (a name, a form and its parameter values, as model files hold it) is an
:class:`~spicethermal.effects.registry.Effect`; the plugin is found from its name in the
registry (:mod:`spicethermal.effects.registry`).
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, ClassVar, Protocol

import numpy as np

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

__all__ = ["CALIBRATION", "COOLING", "DEVICE", "KINDS", "MEASUREMENT", "PWM", "STEADY",
           "CurveEvidence", "DeviceEffect", "EffectPlugin", "Evidence", "MeasurementEffect",
           "Observation", "Param", "Traits", "overrides", "scalar_params"]

DEVICE = "device"
MEASUREMENT = "measurement"

#: Kinds of data set a bundle holds: each cooling curve, the steady reading just before each
#: cut, the PWM grid, the TSP calibration.
COOLING, STEADY, PWM, CALIBRATION = "cooling", "steady", "pwm", "calibration"
KINDS = (COOLING, STEADY, PWM, CALIBRATION)


@dataclass(frozen=True)
class Param:
    """A parameter of an effect.

    Attributes
    ----------
    unit : str
        Its unit.
    default : float
        Its value when none is given.
    low, high : float
        The allowed range.
    doc : str
        What it is.
    forms : tuple of str
        The forms that use it (empty: every form).
    fitted : bool
        Whether a fit moves it (false for a reference such as the temperature a law is
        written at, or a discrete choice such as a node, which
        :meth:`EffectPlugin.variants` enumerates).
    log : bool
        Whether a fit moves it on a log scale (a positive span, a heat).
    typical : float
        Its typical size, which scales a fit's finite-difference steps.
    """

    unit: str
    default: float
    low: float = -math.inf
    high: float = math.inf
    doc: str = ""
    forms: tuple[str, ...] = ()
    fitted: bool = True
    log: bool = False
    typical: float = 1.0

    def used_by(self, form: str) -> bool:
        """Whether form ``form`` uses this parameter."""
        return not self.forms or form in self.forms


@dataclass(frozen=True)
class Traits:
    """What an effect's data look like, as data instead of tables elsewhere.

    Attributes
    ----------
    shown_by : frozenset of str
        The kinds of data set (:data:`KINDS`) in which the effect can show at all (a fit is
        not tried without one of them).
    needs : frozenset of str
        Kinds without which the effect cannot be told from others (a TSP's curvature without
        a calibration reads like a device effect): without them, or when they do not show it
        themselves (the effect does not lower their χ² decisively), it is never named
        alone.
    cost : float
        Relative work of one forward evaluation (1: closed form; an integrated device effect
        more).
    confusable_with : mapping of str to str
        Other effects' names, each with the measurement that tells them apart.
    catalogued : bool
        False for a *rival*: an explanation outside the catalogue that the diagnosis weighs
        but never names (a heating power other than the recorded one).
    shown_alone_by : str
        The measurement that would show the effect where the plugin's ``unshown()`` says the
        data cannot (said with that verdict).
    """

    shown_by: frozenset[str]
    needs: frozenset[str] = frozenset()
    cost: float = 1.0
    confusable_with: Mapping[str, str] = field(default_factory=dict)
    catalogued: bool = True
    shown_alone_by: str = "data over the range where it would act"


@dataclass(frozen=True, eq=False)
class CurveEvidence:
    """One cooling curve as a guess sees it: readings and the model so far (°C) at ``t_s``,
    the power cut, the reference, the model's node temperatures (°C) just before the cut
    (junction first, on the model's Cauer form) and at every reading (``(N, n)``)."""

    t_s: NDArray
    reading_c: NDArray
    model_c: NDArray
    power_w: float
    tref_c: float
    nodes_c: NDArray
    node_paths_c: NDArray | None = None

    @property
    def residual_k(self) -> NDArray:
        return self.reading_c - self.model_c


@dataclass(frozen=True, eq=False)
class Evidence:
    """What the model so far leaves unexplained, for :meth:`EffectPlugin.guess`.

    ``cooling``: every curve; ``pwm``: ``(freq_hz, duty, power_w, reading_c, model_c)`` of the
    grid or None; ``declared_window_s``: the PWM sample window the bundle declares;
    ``calibration``: ``(temp_c, read_c)`` (the thermocouple temperature and what the linear
    calibration reads there) or None; ``rth_k_per_w``: the model's thermal resistance;
    ``n_nodes``: its Cauer nodes (``node_c_j_per_k`` their heat capacities); ``noise_k``: noise
    per data set name.
    """

    cooling: tuple[CurveEvidence, ...] = ()
    pwm: tuple[NDArray, NDArray, NDArray, NDArray, NDArray] | None = None
    declared_window_s: float = 0.0
    calibration: tuple[NDArray, NDArray] | None = None
    rth_k_per_w: float = 1.0
    n_nodes: int = 1
    #: Heat capacity (J/K) of every Cauer node of the model so far, junction first ...
    node_c_j_per_k: tuple[float, ...] = ()
    #: ... and the resistance (K/W) of every Cauer layer.
    layer_r_k_per_w: tuple[float, ...] = ()
    #: Time constants (s) of the model so far (its Foster form), fastest first.
    tau_s: tuple[float, ...] = ()
    #: Whether the cooling readings were converted from TSP voltages through the bundle's
    #: linear calibration (else they came in °C, converted by a law we do not know).
    in_volts: bool = False
    reference_c: float = 25.0
    noise_k: Mapping[str, float] = field(default_factory=dict)


@dataclass(frozen=True, eq=False)
class Observation:
    """One data set as a measurement effect reads it.

    ``kind`` (:data:`KINDS`); ``x``: the time after the cut (cooling), the frequency (PWM) or
    the thermocouple temperature (calibration); ``power_w`` and ``tref_c`` per point; ``duty``
    per PWM row; ``declared_window_s``: the sample window the bundle declares;
    ``line_temps_c``: the calibration points the bench's linear calibration was fitted to
    (None: readings through the tangent at the law's own centre); ``after_off(delay)``:
    for the PWM grid, the true junction temperature (°C, shape ``(B, N)``) at ``delay`` (s,
    shape ``(B, 1)`` or scalar) after an on-phase ends with the power kept off.
    """

    kind: str
    x: NDArray
    power_w: NDArray
    tref_c: NDArray
    duty: NDArray | None = None
    declared_window_s: float = 0.0
    line_temps_c: NDArray | None = None
    after_off: Callable[[NDArray | float], NDArray] | None = None


class Effect(Protocol):
    """A configured effect as the hooks see it (:class:`spicethermal.effects.Effect` is one):
    its name, form and parameter values."""

    name: str
    form: str
    params: Mapping[str, float]

    @property
    def form_params(self) -> dict[str, float]: ...


def scalar_params(effect: Effect) -> dict[str, NDArray]:
    """An effect's parameters as the ``(1, 1)`` arrays the hooks take (a batch of one).

    Parameters
    ----------
    effect : Effect
        A configured effect.

    Returns
    -------
    dict of str to ndarray
    """
    return {k: np.full((1, 1), float(v)) for k, v in effect.params.items()}


def overrides(plugin: EffectPlugin, hook: Callable) -> bool:
    """Whether ``plugin``'s class overrides ``hook``, a hook of the base classes below whose
    default does nothing (the work it needs is then skipped).

    >>> from spicethermal.effects.registry import plugin
    >>> overrides(plugin("phase-change"), DeviceEffect.stored_heat)
    True
    >>> overrides(plugin("phase-change"), DeviceEffect.resistance_scale)
    False
    """
    return getattr(type(plugin), hook.__name__) is not hook


class EffectPlugin(ABC):
    """Base of every effect. Subclasses set the class attributes and the hooks."""

    #: Catalogue name: the registry's key (nobody else spells it).
    name: ClassVar[str]
    #: :data:`DEVICE` or :data:`MEASUREMENT`.
    kind: ClassVar[str]
    #: One line: what it is.
    summary: ClassVar[str]
    #: Parameters by name.
    params: ClassVar[Mapping[str, Param]]
    #: Forms; the first is the default.
    forms: ClassVar[tuple[str, ...]] = ("standard",)
    traits: ClassVar[Traits]

    def check(self, effect: Effect) -> None:  # noqa: B027 - optional hook, none by default
        """Reject parameter values the form cannot use (raise ``DataFormatError``)."""

    def variants(self, form: str, evidence: Evidence) -> Sequence[Mapping[str, float]]:
        """The discrete choices a fit of ``form`` tries (a node, a subset of layers), each
        the values of some parameters that are not fitted (default: one, none)."""
        return ({},)

    @abstractmethod
    def guess(self, form: str, fixed: Mapping[str, float],
              evidence: Evidence) -> Sequence[Mapping[str, float]]:
        """Starting values of the fitted parameters of ``form`` (one mapping per start, a
        few at most, deterministic) given the discrete choice ``fixed`` and what the model
        so far leaves unexplained."""

    def unshown(self, effect: Effect, evidence: Evidence) -> str:
        """Why data such as ``evidence`` (what the model with the fitted ``effect`` leaves)
        cannot show this effect as fitted, or "" when they can (default). A fit may put an
        effect where the data only see its tail (a band outside the temperatures reached),
        which another effect explains as well: no evidence of its physics."""
        return ""

    def describe(self, effect: Effect) -> str:
        """One sentence on what the fitted effect says physically (numbers included)."""
        shown = ", ".join(f"{k} = {v:.4g}" for k, v in effect.form_params.items())
        return f"{self.summary} ({effect.form}: {shown})"

    def fitted_names(self, form: str) -> tuple[str, ...]:
        """The parameters a fit of ``form`` moves."""
        return tuple(k for k, p in self.params.items() if p.fitted and p.used_by(form))


class DeviceEffect(EffectPlugin):
    """An effect of the device itself: part of the model, simulated and exported.

    Its physics are two hooks of the one network simulator, on the Cauer form of the ladder
    (node 0 the junction, layer ``i`` from node ``i`` to node ``i + 1``, the last layer to the
    reference, every node's heat capacity to the thermal ground).

    Attributes
    ----------
    name : str
        Catalogue name (the registry's key).
    kind : str
        :data:`DEVICE`.
    summary : str
        One line: what it is.
    params : mapping of str to Param
        Its parameters.
    forms : tuple of str
        Its forms, the default first.
    traits : Traits
        What its data look like.
    """

    kind = DEVICE

    def resistance_scale(self, form: str, p: Mapping[str, NDArray], t_layer_c: NDArray,
                         t_junction_c: NDArray) -> NDArray | None:
        """Factor on each layer's resistance, shape ``(B, n)``, given each layer's mean
        temperature ``t_layer_c`` ``(B, n)`` and the junction's ``(B, 1)`` (°C); None when
        the effect leaves every resistance alone."""
        return None

    def stored_heat(self, form: str, p: Mapping[str, NDArray], t_node_c: NDArray,
                    c_node: NDArray) -> tuple[NDArray, NDArray] | None:
        """Heat (J) stored at each node beyond its linear capacity ``c_node`` on the way up
        to ``t_node_c``, and its derivative (J/K), both ``(B, n)``; None when the effect
        stores none."""
        return None

    def physical_nodes(self, effect: Effect) -> bool:
        """Whether the effect needs physical node temperatures (the model is then simulated
        and exported on its ladder's Cauer form)."""
        return False

    def spice_resistance_scale(self, effect: Effect, layer: int, t_layer: str,
                               t_junction: str) -> str | None:
        """:meth:`resistance_scale` of one layer as a SPICE expression of the layer's and the
        junction's temperature expressions (None: the layer is untouched)."""
        return None

    def spice_stored_heat(self, effect: Effect, node: int, t_node: str,
                          c_node: float) -> str | None:
        """:meth:`stored_heat` of one node as a SPICE expression (None: none)."""
        return None


class MeasurementEffect(EffectPlugin):
    """An artefact of the bench: how a true junction temperature becomes a reading.

    Attributes
    ----------
    name : str
        Catalogue name (the registry's key).
    kind : str
        :data:`MEASUREMENT`.
    summary : str
        One line: what it is.
    params : mapping of str to Param
        Its parameters.
    forms : tuple of str
        Its forms, the default first.
    traits : Traits
        What its data look like.
    stage : float
        Where it acts on a reading (see the class attribute).
    """

    kind = MEASUREMENT
    #: Order in which readings pass through measurement effects: what is sampled (0), what
    #: scales the rise (0.5), the sensor's law (1), what is added to the reading (2).
    stage: ClassVar[float] = 2.0

    @abstractmethod
    def read(self, form: str, p: Mapping[str, NDArray], obs: Observation,
             values: NDArray) -> NDArray:
        """The readings ``(B, N)`` of data set ``obs`` given ``values``, what the effects of
        earlier stages made of the true temperature (°C); return ``values`` unchanged for a
        kind of data set the effect does not touch."""
