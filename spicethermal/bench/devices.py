"""Presets of the simulated bench: the device (its ladder, heater, TSP diode) and the board.

Two presets, chosen by the ``sim://NAME`` URL:

* ``actuator`` — the paper's thermopneumatic actuator (§2, §7): a signal diode heating a
  methanol-filled brass cavity, junction to ambient. Foster ladder ``r = (6, 20, 50, 70)`` K/W
  (Rth_ja = 146 K/W, the paper's value), ``tau = (2e-4, 5e-3, 0.4, 12)`` s: the die and its
  glass package, the brass, the cavity, the actuator body to the air. Heating power 0.094 W
  (paper), a second power of 0.3 W for the two-power cooling curves (its steady state crosses
  the methanol boiling band at 64.7 °C). Device effects available: ``temperature-coefficient``
  (Rth falls with temperature, α = −2e-3 /K) and ``phase-change`` (latent heat on the cavity
  node).
* ``mur880e`` — the paper's validation device (§5): MUR880E power diode, junction to case,
  Rthjc = 1.51 K/W with the Foster ladder of :func:`spicethermal.core.synthetic.mur880e_foster`
  (matches the datasheet r(t) of Table 1), on a bulky heat sink (0.3 K/W, 300 J/K) whose
  temperature the reference thermocouple reads.

>>> p = preset("actuator")
>>> round(p.foster.rth, 6), p.reference
(146.0, 'ambient')
"""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction

from ..core.errors import InstrumentError
from ..core.ladder import Foster
from ..core.synthetic import mur880e_foster

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
    is ``Vf(T) = v25 + slope·(T − 25) + quad·(T − 25)²`` (the TSP; ``quad`` only with
    ``tsp-nonlinearity``); at any current ``I`` it follows the junction-diode law through that
    point, ``Vf(T) + n·(k/q)·T·ln(I/i_bias) + rs·(I − i_bias)`` (SPICE's law with ``XTI = 0``,
    T in kelvin): the heating current's voltage (P = I·V) and the forward-voltage points."""

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
    #: parameters of the device effects when enabled (effects.py names and parameters)
    effect_params: dict = field(default_factory=dict)
    transient_v: float = 0.3        # electrical transient: heater-diode overshoot at the cut, V
    transient_tau_s: float = 10e-6  # ... decaying with this time constant


def _actuator() -> Preset:
    return Preset(
        name="actuator",
        description="thermopneumatic actuator (methanol cavity), diode heater, junction to ambient",
        foster=Foster.from_tau([6.0, 20.0, 50.0, 70.0], [2e-4, 5e-3, 0.4, 12.0]),
        reference="ambient",
        board=Board(name="actuator"),
        powers_w=(0.094, 0.3),
        pwm_power_w=0.094,
        effect_params={
            "temperature-coefficient": {"alpha_per_k": -2e-3, "t0_c": 25.0},
            "phase-change": {"t_c": 64.7, "width_k": 1.5, "latent_j": 1.0, "node": 1},
        },
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
        effect_params={
            "temperature-coefficient": {"alpha_per_k": -1e-3, "t0_c": 25.0},
            "phase-change": {"t_c": 64.7, "width_k": 1.5, "latent_j": 0.5, "node": 3},
        },
    )


PRESETS = {"actuator": _actuator, "mur880e": _mur880e}


def preset(name: str) -> Preset:
    """The preset called ``name`` (``actuator`` or ``mur880e``)."""
    try:
        return PRESETS[name]()
    except KeyError:
        raise InstrumentError(f"sim://{name}: unknown simulated device; known: "
                              f"{', '.join(sorted(PRESETS))}") from None
