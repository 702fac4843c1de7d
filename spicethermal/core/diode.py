"""The diode's forward characteristic Vf(I, T): SPICE's junction-diode law with series resistance.

The one implementation of the heater diode's electrical physics (the fit, the electrothermal
``.lib`` and the bench circuit all use it)::

    V(I, T) = N·Vt(T)·ln(I / Is(T) + 1) + RS·I              Vt = k·T/q, T in kelvin
    Is(T)   = IS·(T/T0)^(XTI/N)·exp((T/T0 − 1)·EG / (N·Vt(T)))

with SPICE's parameter names (``IS`` the saturation current at ``T0``, ``N`` the ideality,
``RS`` the series resistance, ``XTI`` and ``EG`` the saturation current's temperature
dependence). Over I ≫ IS it is linear in five combinations of them,
``V = a·T·ln I + b·T + c + d·T·ln(T/T0) + RS·I`` with ``a = N·k/q``,
``b = −a·ln IS − EG/T0``, ``c = EG``, ``d = −XTI·k/q`` (:func:`linear_terms`), which is how
:mod:`spicethermal.fit.diode` fits it.

The bench's sense current flows through the diode all the time, also while it is calibrated:
the calibration's temperatures are those of a junction warmed by ``I_sense·V·Rth`` above the
fixture. :meth:`DiodeLaw.bench_temperature` is that convention read backwards, as the bench
reads a TSP voltage.

>>> law = DiodeLaw(n=1.75, is_a=2.5e-9, rs_ohm=0.57)
>>> round(float(law.voltage(1e-3, 25.0)), 4), round(float(law.current(0.58, 25.0)) * 1e3, 3)
(0.5805, 0.988)
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import TYPE_CHECKING

import numpy as np

from .errors import DataFormatError

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import ArrayLike, NDArray

#: Boltzmann's constant over the elementary charge, V/K.
K_OVER_Q = 8.617333262e-5
#: 0 °C in kelvin.
ZERO_C_K = 273.15
#: The SPICE rendering continues the exponential linearly above this many times the largest
#: current of the data (a Newton step from a cold start cannot overflow it).
KNEE_FACTOR = 100.0
#: Parameters of the law as the model file names them, with SPICE's names.
PARAMETERS = {"n": "N", "is_a": "IS", "rs_ohm": "RS", "xti": "XTI", "eg_ev": "EG"}


def linear_terms(i_a: ArrayLike, t_c: ArrayLike, t0_c: float = 25.0) -> NDArray:
    """Columns ``[T·ln I, T, 1, T·ln(T/T0), I]`` (T in kelvin) in which V(I, T) is linear.

    >>> linear_terms([1e-3], [25.0]).round(3).tolist()
    [[-2059.547, 298.15, 1.0, 0.0, 0.001]]
    """
    i = np.asarray(i_a, dtype=float)
    tk = np.asarray(t_c, dtype=float) + ZERO_C_K
    i, tk = np.broadcast_arrays(i, tk)
    return np.column_stack([tk * np.log(i), tk, np.ones_like(tk),
                            tk * np.log(tk / (t0_c + ZERO_C_K)), i])


@dataclass(frozen=True)
class DiodeLaw:
    """A diode's forward voltage Vf(I, T) (see the module's text), with what it was fitted to.

    Attributes
    ----------
    n : float
        Ideality (SPICE ``N``).
    is_a : float
        Saturation current at ``t0_c``, A (``IS``).
    rs_ohm : float
        Series resistance, Ω (``RS``; no temperature coefficient).
    xti : float
        Saturation current's temperature exponent (``XTI``).
    eg_ev : float
        Activation energy, eV (``EG``).
    t0_c : float
        Temperature of ``is_a``, °C (``TNOM``).
    sense_current_a : float or None
        The bench's sense current (the TSP calibration's), A.
    tsp_offset_v : float or None
        The calibration's TSP plus this is V(sense current, T): the reference diode's voltage
        while the calibration was taken.
    valid_i_a, valid_t_c : tuple of float or None
        The currents (A) and junction temperatures (°C) of the data it was fitted to.
    fit : Mapping
        How it was fitted: uncertainties, residuals, points (``docs/model-format.md``).
    """

    n: float
    is_a: float
    rs_ohm: float = 0.0
    xti: float = 3.0
    eg_ev: float = 1.11
    t0_c: float = 25.0
    sense_current_a: float | None = None
    tsp_offset_v: float | None = None
    valid_i_a: tuple[float, float] | None = None
    valid_t_c: tuple[float, float] | None = None
    fit: Mapping = field(default_factory=dict, compare=False)

    def __post_init__(self) -> None:
        for name, low in (("n", 0.0), ("is_a", 0.0), ("rs_ohm", None), ("xti", None),
                          ("eg_ev", 0.0), ("t0_c", -ZERO_C_K)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int | float | np.floating) or \
                    not math.isfinite(value) or (low is not None and value <= low):
                raise DataFormatError(f"diode law: {name} = {value!r} must be a finite number"
                                      + (f" > {low:g}" if low is not None else ""))
            object.__setattr__(self, name, float(value))
        if self.rs_ohm < 0:
            raise DataFormatError(f"diode law: rs_ohm = {self.rs_ohm!r} must be >= 0")
        for name in ("sense_current_a", "tsp_offset_v"):
            value = getattr(self, name)
            if value is None:
                continue
            if isinstance(value, bool) or not isinstance(value, int | float | np.floating) or \
                    not math.isfinite(value) or (name == "sense_current_a" and value <= 0):
                raise DataFormatError(f"diode law: {name} = {value!r} must be a finite number"
                                      + (" > 0" if name == "sense_current_a" else ""))
            object.__setattr__(self, name, float(value))
        for name in ("valid_i_a", "valid_t_c"):
            span = getattr(self, name)
            if span is not None:
                span = tuple(float(x) for x in span)
                if len(span) != 2 or not all(map(math.isfinite, span)) or span[0] > span[1]:
                    raise DataFormatError(f"diode law: {name} must be [low, high]")
                object.__setattr__(self, name, span)
        object.__setattr__(self, "fit", MappingProxyType(dict(self.fit)))

    # -- the law ---------------------------------------------------------------------------
    def thermal_voltage(self, t_c: ArrayLike) -> NDArray:
        """N·Vt(T), V."""
        return self.n * K_OVER_Q * (np.asarray(t_c, dtype=float) + ZERO_C_K)

    def saturation_current(self, t_c: ArrayLike) -> NDArray:
        """Is(T), A.

        >>> law = DiodeLaw(n=1.0, is_a=1e-14)
        >>> float(law.saturation_current(25.0)) == 1e-14
        True
        """
        tk = np.asarray(t_c, dtype=float) + ZERO_C_K
        ratio = tk / (self.t0_c + ZERO_C_K)
        return self.is_a * ratio ** (self.xti / self.n) * np.exp(
            (ratio - 1) * self.eg_ev / self.thermal_voltage(t_c))

    def voltage(self, i_a: ArrayLike, t_c: ArrayLike) -> NDArray:
        """V(I, T), V (I > −Is)."""
        i = np.asarray(i_a, dtype=float)
        return self.thermal_voltage(t_c) * np.log1p(i / self.saturation_current(t_c)) + \
            self.rs_ohm * i

    def current(self, v_a: ArrayLike, t_c: ArrayLike) -> NDArray:
        """The current I at which V(I, T) = ``v_a`` (bisection on the junction voltage)."""
        v, t = np.broadcast_arrays(np.asarray(v_a, dtype=float), np.asarray(t_c, dtype=float))
        nvt, i_s = self.thermal_voltage(t), self.saturation_current(t)
        lo, hi = np.minimum(v, 0.0), np.maximum(v, 0.0)
        for _ in range(200):  # Vj + RS·I(Vj) = v, increasing in Vj, bracketed by 0 and v
            mid = 0.5 * (lo + hi)
            above = mid + self.rs_ohm * i_s * np.expm1(np.minimum(mid / nvt, 700.0)) > v
            hi, lo = np.where(above, mid, hi), np.where(above, lo, mid)
        return i_s * np.expm1(0.5 * (lo + hi) / nvt)

    def temperature(self, v_a: ArrayLike, i_a: ArrayLike, span_c: tuple[float, float] = (
            -150.0, 500.0)) -> NDArray:
        """The junction temperature at which V(I, T) = ``v_a`` at current ``i_a`` (bisection:
        V falls with T at any current the law is fitted over); NaN outside ``span_c``."""
        v, i = np.broadcast_arrays(np.asarray(v_a, dtype=float), np.asarray(i_a, dtype=float))
        lo, hi = np.full(v.shape, span_c[0]), np.full(v.shape, span_c[1])
        inside = (self.voltage(i, lo) >= v) & (self.voltage(i, hi) <= v)
        for _ in range(80):
            mid = 0.5 * (lo + hi)
            colder = self.voltage(i, mid) > v
            lo, hi = np.where(colder, mid, lo), np.where(colder, hi, mid)
        return np.where(inside, 0.5 * (lo + hi), np.nan)

    def slope_v_per_k(self, i_a: ArrayLike, t_c: ArrayLike) -> NDArray:
        """dV/dT at constant current, V/K.

        >>> round(float(DiodeLaw(n=1.0, is_a=1e-14, xti=0.0).slope_v_per_k(1e-3, 25.0)), 5)
        -0.00154
        """
        t = np.asarray(t_c, dtype=float)
        return (self.voltage(i_a, t + 0.01) - self.voltage(i_a, t - 0.01)) / 0.02

    # -- the bench ---------------------------------------------------------------------------
    def sense_heating_k(self, v_a: ArrayLike, rth_k_per_w: float) -> NDArray:
        """The junction's steady rise from the sense current at voltage ``v_a``: I·V·Rth, K."""
        if self.sense_current_a is None:
            return np.zeros_like(np.asarray(v_a, dtype=float))
        return self.sense_current_a * np.asarray(v_a, dtype=float) * rth_k_per_w

    def bench_temperature(self, v_a: ArrayLike, rth_k_per_w: float) -> NDArray:
        """What the bench's calibration reads from a sense-current voltage: the junction
        temperature of V(I_sense, T) = ``v_a`` less the sense current's own heating, as the
        calibration (taken under that current, against the fixture's temperature) has it.

        >>> law = DiodeLaw(n=1.75, is_a=2.5e-9, sense_current_a=1e-3)
        >>> v = float(law.voltage(1e-3, 40.0 + 1e-3 * 0.55 * 146.0))
        >>> round(float(law.bench_temperature(v, 146.0)), 3)
        40.0
        """
        if self.sense_current_a is None:
            raise DataFormatError("diode law: no sense current, so no TSP reading")
        v = np.asarray(v_a, dtype=float)
        return self.temperature(v, self.sense_current_a) - self.sense_heating_k(v, rth_k_per_w)

    def bench_voltage(self, t_c: ArrayLike, rth_k_per_w: float) -> NDArray:
        """The sense-current voltage the calibration gives temperature ``t_c``: the diode's
        at its junction, warmed by its own sense current (the inverse of
        :meth:`bench_temperature`).

        >>> law = DiodeLaw(n=1.75, is_a=2.5e-9, sense_current_a=1e-3)
        >>> round(float(law.bench_temperature(law.bench_voltage(40.0, 146.0), 146.0)), 9)
        40.0
        """
        if self.sense_current_a is None:
            raise DataFormatError("diode law: no sense current, so no TSP reading")
        t = np.asarray(t_c, dtype=float)
        v = self.voltage(self.sense_current_a, t)
        for _ in range(30):  # v = V(I, T + I·v·Rth): a contraction (I·Rth·|dV/dT| << 1)
            v = self.voltage(self.sense_current_a, t + self.sense_heating_k(v, rth_k_per_w))
        return v

    def heating_current(self, power_w: float, t_c: float) -> float:
        """The switched current that adds ``power_w`` to the sense current's dissipation at
        junction temperature ``t_c``: ``(I + Is)·V(I + Is) − Is·V(Is) = P`` (the bench's power
        loop, which sets the heating current from an on-phase reading; the sense current, whose
        heating the calibration absorbs, is not heating power).

        >>> law = DiodeLaw(n=1.75, is_a=2.5e-9, rs_ohm=0.57)
        >>> i = law.heating_current(0.094, 25.0)
        >>> round(i * float(law.voltage(i, 25.0)), 12)
        0.094
        """
        i_s = self.sense_current_a or 0.0
        base = i_s * float(self.voltage(i_s, t_c)) if i_s else 0.0

        def added(i: float) -> float:
            return (i + i_s) * float(self.voltage(i + i_s, t_c)) - base

        lo, hi = 0.0, 1.0
        while added(hi) < power_w:
            hi *= 2.0
        for _ in range(200):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if added(mid) < power_w else (lo, mid)
        return 0.5 * (lo + hi)

    # -- SPICE ---------------------------------------------------------------------------------
    @property
    def knee_current_a(self) -> float:
        """Where the SPICE rendering continues the exponential linearly, A."""
        top = self.valid_i_a[1] if self.valid_i_a is not None else 1.0
        return KNEE_FACTOR * max(top, self.is_a * 1e6)

    def spice_exponent(self, vj: str, tk: str) -> str:
        """``y = ln(IS) + x``, the logarithm of the junction current's exponential term
        ``IS·exp(x)``, as a dialect-neutral behavioural expression of the junction voltage
        ``vj`` and the temperature ``tk`` in kelvin (e.g. ``V(DJ,K)`` and ``V(DT)``). Written
        so, the exponential's argument stays small (``ln`` of a current in A): PSPICE, and
        ngspice in its ``ps`` mode, continue ``EXP`` linearly above 14.

        >>> DiodeLaw(n=1.0, is_a=1e-14, xti=0.0, eg_ev=1.2).spice_exponent("V(DJ,K)", "V(DT)")
        '-32.23619130191664+((V(DJ,K))+1.2*(V(DT)/298.15-1))/(1.0*8.617333262e-05*V(DT))'
        """
        t0k = repr(self.t0_c + ZERO_C_K)
        shift = f"{self.eg_ev!r}*({tk}/{t0k}-1)"
        if self.xti:
            shift += f"+{self.xti!r}*{K_OVER_Q!r}*{tk}*LOG({tk}/{t0k})"
        return f"{math.log(self.is_a)!r}+(({vj})+{shift})/({self.n!r}*{K_OVER_Q!r}*{tk})"

    def spice_current(self, y: str, tk: str) -> str:
        """The junction current as a behavioural expression of ``y`` (:meth:`spice_exponent`,
        e.g. held on a node ``V(DX)``) and the temperature ``tk`` in kelvin:
        ``exp(y) − Is(T)``, the exponential continued linearly above :attr:`knee_current_a`
        (``EXP(MIN(y,yk))·(1+MAX(y−yk,0))``; no ``limit()``).

        >>> DiodeLaw(n=1.0, is_a=1e-14, xti=0.0, eg_ev=1.2).spice_current("V(DX)", "V(DT)")[:40]
        'EXP(MIN(V(DX),4.605170185988092))*(1+MAX'
        """
        y0 = self.spice_exponent("0", tk)
        yk = repr(math.log(self.knee_current_a))
        return f"EXP(MIN({y},{yk}))*(1+MAX({y}-{yk},0))-EXP(MIN({y0},{yk}))"

    @staticmethod
    def spice_kelvin(t_c: str) -> str:
        """A temperature expression in °C as kelvin, kept above 1 K (a Newton iterate of a
        cold start may pass through absurd node voltages).

        >>> DiodeLaw.spice_kelvin("V(TJ)+TOFFSET")
        'MAX((V(TJ)+TOFFSET)+273.15,1.0)'
        """
        return f"MAX(({t_c})+{ZERO_C_K!r},1.0)"

    def model_card(self, name: str = "DHEATER") -> str:
        """The SPICE ``.model`` of the same law at one fixed temperature (a diode model's
        temperature is the simulator's, not a node's).

        >>> DiodeLaw(n=1.75, is_a=2.5e-9, rs_ohm=0.57).model_card()
        '.model DHEATER D(IS=2.5e-09 N=1.75 RS=0.57 XTI=3 EG=1.11 TNOM=25)'
        """
        return (f".model {name} D(IS={self.is_a:.6g} N={self.n:.6g} RS={self.rs_ohm:.6g} "
                f"XTI={self.xti:.6g} EG={self.eg_ev:.6g} TNOM={self.t0_c:.6g})")

    # -- text and files --------------------------------------------------------------------------
    def describe(self) -> str:
        """One line: the parameters, with their uncertainties when fitted.

        >>> DiodeLaw(n=1.75, is_a=2.5e-9, rs_ohm=0.57).describe()
        'N = 1.75, IS = 2.5e-09 A, RS = 0.57 ohm, XTI = 3, EG = 1.11 eV (at 25 degC)'
        """
        u = self.fit.get("u", {}) if isinstance(self.fit.get("u"), Mapping) else {}
        units = {"is_a": " A", "rs_ohm": " ohm", "eg_ev": " eV"}
        parts = []
        for key, spice in PARAMETERS.items():
            text = f"{spice} = {getattr(self, key):.4g}"
            if isinstance(u.get(key), int | float):
                text += f" ± {u[key]:.2g}"
            parts.append(text + units.get(key, ""))
        return ", ".join(parts) + f" (at {self.t0_c:g} degC)"

    def to_dict(self) -> dict:
        """The model file's ``electrical`` object (``docs/model-format.md``).

        >>> DiodeLaw(n=1.0, is_a=1e-14).to_dict()["law"]
        'diode'
        """
        out: dict = {"law": "diode", **{k: float(getattr(self, k)) for k in PARAMETERS},
                     "t0_c": float(self.t0_c)}
        for key in ("sense_current_a", "tsp_offset_v"):
            if getattr(self, key) is not None:
                out[key] = float(getattr(self, key))
        for key in ("valid_i_a", "valid_t_c"):
            if getattr(self, key) is not None:
                out[key] = list(getattr(self, key))
        if self.fit:
            out["fit"] = dict(self.fit)
        return out

    @classmethod
    def from_dict(cls, data: object, source: str = "model") -> DiodeLaw:
        """Read the ``electrical`` object; errors name ``source`` and the key.

        >>> DiodeLaw.from_dict({"law": "diode", "n": 1.0, "is_a": 1e-14}).rs_ohm
        0.0
        """
        where = f"{source}, key electrical"
        if not isinstance(data, Mapping):
            raise DataFormatError(f"{where}: must be an object")
        if data.get("law") != "diode":
            raise DataFormatError(f"{where}.law: {data.get('law')!r}, expected 'diode'")
        known = {*PARAMETERS, "t0_c", "sense_current_a", "tsp_offset_v", "valid_i_a",
                 "valid_t_c", "fit"}
        extra = sorted(set(data) - known - {"law"})
        if extra:
            raise DataFormatError(f"{where}.{extra[0]}: not a key of the diode law")
        for key in ("n", "is_a"):
            if key not in data:
                raise DataFormatError(f"{where}.{key}: missing")
        fit = data.get("fit", {})
        if not isinstance(fit, Mapping):
            raise DataFormatError(f"{where}.fit: must be an object")
        try:
            return cls(**{k: data[k] for k in known - {"fit"} if k in data}, fit=fit)
        except TypeError as exc:
            raise DataFormatError(f"{where}: {exc}") from None
        except DataFormatError as exc:
            raise DataFormatError(f"{where}: {str(exc).removeprefix('diode law: ')}") from None
