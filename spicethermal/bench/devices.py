"""Presets of the simulated bench: the device (its ladder, heater, TSP diode) and the board.

Three presets, chosen by the ``sim://NAME`` URL (``array``: cells of the actuator on a common
substrate, :mod:`.array_devices`):

* ``actuator`` — the paper's thermopneumatic actuator (§2, §7): a signal diode heating a
  methanol-filled brass cavity, junction to ambient. Foster ladder ``r = (6, 20, 50, 70)`` K/W
  (Rth_ja = 146 K/W, the paper's value), ``tau = (2e-4, 5e-3, 0.4, 12)`` s: the die and its
  glass package, the brass, the cavity, the actuator body to the air. Heating power 0.094 W
  (paper), a second power of 0.3 W for the two-power cooling curves (its steady state crosses
  the methanol boiling band at 64.7 °C). Its device effects (``spicethermal/data/sim_bench.json``):
  ``temperature-coefficient`` (Rth falls with temperature, α = −2e-3 /K) and ``phase-change``
  (latent heat on the cavity node).
* ``mur880e`` — the paper's validation device (§5): MUR880E power diode, junction to case,
  Rthjc = 1.51 K/W with the Foster ladder of :func:`spicethermal.core.synthetic.mur880e_foster`
  (matches the datasheet r(t) of Table 1), on a bulky heat sink (0.3 K/W, 300 J/K) whose
  temperature the reference thermocouple reads.

Which effects a ``sim://`` URL can switch on is found through the effect registry
(:mod:`spicethermal.effects`): any catalogued device effect, simulated by the plant through its
plugin with the preset's parameters (or the plugin's defaults), and the catalogued
measurement effects that the front end's hardware artefacts show as (:data:`ARTEFACTS`, mapped
in the same data file). No effect is named here.

>>> p = preset("actuator")
>>> round(p.foster.rth, 6), p.reference
(146.0, 'ambient')
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field, replace
from fractions import Fraction
from functools import lru_cache
from typing import Any

from .. import data
from ..core.errors import DataFormatError, InstrumentError
from ..core.ladder import Foster
from ..core.synthetic import mur880e_foster
from ..effects import DEVICE, MEASUREMENT, Effect, known_names, plugin
from ..io.files import read_json

#: The simulated bench's data: the presets' device effects, the front end's artefacts.
DATA_FILE = "sim_bench.json"

#: The front end's hardware artefacts, in hardware terms: the electrical transient of the
#: heater diode after each power cut (a decaying overshoot of the forward voltage); the sample
#: window (no track-and-hold: the heater is off for the window before each PWM sample, which
#: the TSP sees cooling); the curvature of the TSP diode's forward voltage in temperature.
CUT_TRANSIENT, SAMPLE_WINDOW, CURVED_TSP = "cut_transient", "sample_window", "curved_tsp"
ARTEFACTS = (CUT_TRANSIENT, SAMPLE_WINDOW, CURVED_TSP)

#: ADC: 10 bits over 0..5 V (PIC18F4431 high-speed ADC, AVdd reference).
ADC_BITS = 10
ADC_FULL_V = 5.0
#: LSB in µV as the fraction 78125/16 = 4882.8125 µV (exact for 5 V / 1024).
LSB_NUM, LSB_DEN = 78125, 16


@dataclass(frozen=True)
class Board:
    """Analog front end: gains and offsets from the physical quantities to the ADC pins.

    ``tsp_gain``/``tsp_offset_v``: INA112, pin = offset − gain·(Vd − Vref);
    ``i_sense_v_per_a``: sense resistor × amplifier gain; thermocouple amplifiers give
    ``*_v_per_k`` with ``*_offset_v`` at 0 °C. ``i_full_a`` is the heater current at DAC full
    scale; ``fixture_*_c`` the calibration hot plate's setpoint range.
    """

    name: str
    tsp_gain: float = 40.0
    tsp_offset_v: float = 0.3
    i_sense_v_per_a: float = 10.0
    tamb_v_per_k: float = 0.1
    tamb_offset_v: float = 0.0
    taux_v_per_k: float = 0.05
    taux_offset_v: float = 0.5
    i_full_a: float = 0.5
    dac_max: int = 1023
    vd_nominal_v: float = 0.7
    fixture_min_c: float = -10.0
    fixture_max_c: float = 90.0

    def conversions(self) -> list[tuple[int, int, int]]:
        """Fixed-point ``(num, off, den)`` of each channel, ``value = (code·num + off)/den``,
        as the firmware's ``st_conv_t`` (TSP µV, Vd µV, Id µA, thermocouples m°C)."""
        def linear(gain: float, offset_v: float, sign: int = 1) -> tuple[int, int, int]:
            # value = sign·(code·LSB − offset)/gain, gain = p/q in value units per µV
            g = Fraction(gain).limit_denominator(1000)
            off_uv = round(offset_v * 1e6)
            return (sign * LSB_NUM * g.denominator, -sign * LSB_DEN * off_uv * g.denominator,
                    LSB_DEN * g.numerator)

        return [
            linear(self.tsp_gain, self.tsp_offset_v, -1),   # µV at the INA input
            linear(1.0, 0.0),                               # µV
            linear(self.i_sense_v_per_a, 0.0),              # µV / (V/A) = µA
            linear(self.tamb_v_per_k * 1e3, self.tamb_offset_v),  # µV / (µV/m°C)
            linear(self.taux_v_per_k * 1e3, self.taux_offset_v),
        ]


@dataclass(frozen=True)
class Diode:
    """The heater diode. At the small TSP bias (sense) current ``i_bias_a`` its forward voltage
    is ``Vf(T) = v25 + slope·(T − 25) + quad·(T − 25)²`` (the TSP; ``quad`` only with the front
    end's :data:`CURVED_TSP`); at any current ``I`` it follows the junction-diode law through
    that point, ``Vf(T) + n·(k/q)·T·ln(I/i_bias) + rs·(I − i_bias)`` (SPICE's law with
    ``XTI = 0``, T in kelvin): the heating current's voltage (P = I·V) and the forward-voltage
    points."""

    v25: float = 0.60
    slope_v_per_k: float = -2.0e-3
    quad_v_per_k2: float = -1.5e-6
    n: float = 1.75
    rs_ohm: float = 0.57
    i_bias_a: float = 1e-3


@dataclass(frozen=True)
class Preset:
    """A simulated device with its board and its default measurement parameters."""

    name: str
    description: str
    foster: Foster
    reference: str
    board: Board
    diode: Diode = field(default_factory=Diode)
    heatsink: tuple[float, float] | None = None  # (r K/W, c J/K) from case to ambient
    ambient_c: float = 25.0
    powers_w: tuple[float, float] = (0.094, 0.3)
    pwm_power_w: float = 0.094
    #: its device effects when enabled, as a model file holds them (``name``, ``params``)
    effects: tuple[Mapping[str, Any], ...] = ()
    transient_v: float = 0.3        # the cut transient: heater-diode overshoot at the cut, V
    transient_tau_s: float = 10e-6  # ... decaying with this time constant

    @property
    def effect_params(self) -> dict[str, dict[str, float]]:
        """The parameters of each of its device effects, by name."""
        return {e["name"]: dict(e.get("params", {})) for e in self.effects}

    def device_effects(self, names: Iterable[str]) -> tuple[Effect, ...]:
        """The device effects among the catalogued ``names``, configured with this preset's
        parameters (a device effect it has none for: its plugin's defaults), in the preset's
        order, then the others'.

        Parameters
        ----------
        names : iterable of str
            Catalogued effect names (:func:`spicethermal.effects.known_names`).

        Returns
        -------
        tuple of Effect

        Examples
        --------
        >>> chosen = ["phase-change", "sample-window", "temperature-coefficient"]
        >>> [(e.name, e.params.get("alpha_per_k")) for e in
        ...  preset("actuator").device_effects(chosen)]
        [('temperature-coefficient', -0.002), ('phase-change', None)]
        """
        wanted = [n for n in dict.fromkeys(names) if plugin(n).kind == DEVICE]
        own = {e["name"]: e for e in self.effects}
        ordered = [n for n in own if n in wanted] + [n for n in wanted if n not in own]
        return tuple(Effect.from_dict(own.get(n, {"name": n})) for n in ordered)


def _actuator() -> Preset:
    return Preset(
        name="actuator",
        description="thermopneumatic actuator (methanol cavity), diode heater, junction to ambient",
        foster=Foster.from_tau([6.0, 20.0, 50.0, 70.0], [2e-4, 5e-3, 0.4, 12.0]),
        reference="ambient",
        board=Board(name="actuator"),
        powers_w=(0.094, 0.3),
        pwm_power_w=0.094,
        effects=preset_effects("actuator"),
    )


def _mur880e() -> Preset:
    return Preset(
        name="mur880e",
        description="MUR880E power diode on a bulky heat sink, junction to case",
        foster=mur880e_foster(),
        reference="case",
        board=Board(name="mur880e", i_sense_v_per_a=0.2, i_full_a=25.0, vd_nominal_v=0.95,
                    tamb_v_per_k=0.1),
        diode=Diode(v25=0.55, n=1.5, rs_ohm=0.0125, i_bias_a=10e-3),
        heatsink=(0.3, 300.0),
        powers_w=(10.0, 20.0),
        pwm_power_w=10.0,
        effects=preset_effects("mur880e"),
    )


def _array() -> Preset:
    """The actuator on an array board (its network: :mod:`.array_devices`)."""
    return replace(_actuator(), name="array", board=Board(name="array"),
                   description="array of thermopneumatic actuators on a common substrate, diode "
                               "heaters, junction to ambient")


PRESETS = {"actuator": _actuator, "mur880e": _mur880e, "array": _array}


@lru_cache(maxsize=1)
def bench_data() -> dict[str, Any]:
    """The simulated bench's data file (:data:`DATA_FILE`), checked against the registry:
    every preset's effect a device effect, every artefact of :data:`ARTEFACTS` shown as a
    catalogued measurement effect.

    Returns
    -------
    dict
        ``devices`` (by preset: ``effects``) and ``frontend`` (artefact: effect name).

    Examples
    --------
    >>> sorted(bench_data()["frontend"]) == sorted(ARTEFACTS)
    True
    """
    path = data.path(DATA_FILE)
    doc = read_json(path)
    try:
        for device, entry in doc["devices"].items():
            for e in entry["effects"]:
                if plugin(e["name"]).kind != DEVICE:
                    raise InstrumentError(f"{path}: devices.{device}: {e['name']!r} is not a "
                                          f"device effect")
                Effect.from_dict(e)
        if sorted(doc["frontend"]) != sorted(ARTEFACTS):
            raise InstrumentError(f"{path}: frontend: the artefacts are {', '.join(ARTEFACTS)}")
        for artefact, name in doc["frontend"].items():
            if name not in known_names() or plugin(name).kind != MEASUREMENT:
                raise InstrumentError(f"{path}: frontend.{artefact}: {name!r} is not a "
                                      f"catalogued measurement effect")
    except (KeyError, TypeError, AttributeError) as exc:
        raise InstrumentError(f"{path}: malformed ({exc!r})") from None
    except DataFormatError as exc:  # an effect the registry does not know or refuses
        raise InstrumentError(f"{path}: {exc}") from None
    return doc


def preset_effects(name: str) -> tuple[dict[str, Any], ...]:
    """The device effects of preset ``name`` as the data file holds them (model-file form).

    Parameters
    ----------
    name : str
        A preset.

    Returns
    -------
    tuple of dict

    Examples
    --------
    >>> [sorted(e) for e in preset_effects("actuator")]
    [['name', 'params'], ['name', 'params']]
    """
    return tuple(bench_data()["devices"].get(name, {}).get("effects", ()))


def shown_as() -> dict[str, str]:
    """Each artefact of the front end (:data:`ARTEFACTS`) and the catalogued measurement
    effect it shows as in a bundle.

    Returns
    -------
    dict of str to str

    Examples
    --------
    >>> list(shown_as()) == list(ARTEFACTS)
    True
    """
    frontend = bench_data()["frontend"]
    return {a: frontend[a] for a in ARTEFACTS}


def simulated_effects() -> tuple[str, ...]:
    """The catalogued effects the simulated bench can switch on: every device effect of the
    registry, then the measurement effects its front end shows.

    Returns
    -------
    tuple of str

    Examples
    --------
    >>> set(shown_as().values()) <= set(simulated_effects())
    True
    """
    device = [n for n in known_names() if plugin(n).kind == DEVICE]
    return (*device, *shown_as().values())


def artefacts(names: Iterable[str]) -> frozenset[str]:
    """The front end's artefacts that the effect ``names`` switch on.

    Parameters
    ----------
    names : iterable of str
        Catalogued effect names.

    Returns
    -------
    frozenset of str
        Among :data:`ARTEFACTS`.

    Examples
    --------
    >>> artefacts(shown_as().values()) == frozenset(ARTEFACTS)
    True
    """
    names = set(names)
    return frozenset(a for a, name in shown_as().items() if name in names)


def preset(name: str) -> Preset:
    """The preset called ``name`` (``actuator``, ``mur880e`` or ``array``)."""
    try:
        return PRESETS[name]()
    except KeyError:
        raise InstrumentError(f"sim://{name}: unknown simulated device; known: "
                              f"{', '.join(sorted(PRESETS))}") from None
