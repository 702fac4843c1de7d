"""The data sets of a measurement bundle, one immutable table each: :class:`CalibrationTable`,
:class:`CoolingTable`, :class:`PwmTable`, :class:`ZthTable`, :class:`ForwardTable` (the heater's
forward voltage, ``spicethermal-bundle/3``); a calibration declared as a law rather than points
is a :class:`KFactorLaw` (``docs/bundle-format.md``).

They hold what was read, checked: numbers, never an interpretation of them. The converters
that turn TSP voltages into temperatures are built from them in
:mod:`spicethermal.identify.calibration` (:func:`~spicethermal.identify.calibration.converter`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from ..core.errors import DataFormatError, where

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

from .columns import (
    check_column,
    check_range,
    check_temperatures,
    check_times,
    frozen,
    scalar,
    set_fields,
)


# --------------------------------------------------------------------------------------------
# the sections
# --------------------------------------------------------------------------------------------
def check_coefficients(coefficients: Sequence[float]) -> tuple[float, ...]:
    """The coefficients of a declared polynomial calibration ``V(T) = Σ c[k] · T^k`` (V, T in
    degC, ascending), checked: 2 or 3 finite numbers, a zero quadratic term dropped.

    Parameters
    ----------
    coefficients : sequence of float
        The coefficients as given.

    Returns
    -------
    tuple of float

    Examples
    --------
    >>> check_coefficients([0.65, -0.002, 0.0])
    (0.65, -0.002)
    """
    try:
        coef = tuple(float(c) for c in coefficients)
    except (TypeError, ValueError):
        raise DataFormatError("calibration, coefficients_v: must be numbers") from None
    if len(coef) not in (2, 3) or not all(math.isfinite(c) for c in coef):
        raise DataFormatError(f"calibration, coefficients_v: {list(coefficients)!r} must be "
                              f"2 or 3 finite numbers (a line or a quadratic, ascending)")
    return coef[:2] if len(coef) == 3 and coef[2] == 0.0 else coef


def check_monotonic(coefficients: tuple[float, ...], t_range_c: tuple[float, float]
                    ) -> tuple[float, ...]:
    """``coefficients`` (:func:`check_coefficients`), checked to give a monotonic ``V(T)``
    over the calibrated range: a TSP that turns cannot be read back as one temperature.

    Parameters
    ----------
    coefficients : tuple of float
        Checked coefficients, ascending.
    t_range_c : (float, float)
        The calibrated range, degC.

    Returns
    -------
    tuple of float
        ``coefficients`` unchanged.

    Examples
    --------
    >>> check_monotonic((0.65, -0.002), (25.0, 75.0))
    (0.65, -0.002)
    """
    c = coefficients
    slopes = [c[1] + (2 * c[2] * t if len(c) == 3 else 0.0) for t in t_range_c]
    if slopes[0] == 0 or np.sign(slopes[0]) != np.sign(slopes[1]):
        raise DataFormatError("calibration, coefficients_v: the polynomial is not monotonic "
                              "over the calibrated range")
    return coefficients


@dataclass(frozen=True, eq=False)
class CalibrationTable:
    """TSP calibration points: ``temp_c`` (degC) and ``v_tsp_v`` (V), one row per point.

    Kind ``table`` (a polynomial is fitted to the points,
    :func:`spicethermal.identify.calibration.converter`) or, with ``coefficients`` (V per
    degC^k, ascending), kind ``polynomial``: a fit made elsewhere, the points kept for its
    residuals. The other kind, a K-factor, is :class:`KFactorLaw`.

    Attributes
    ----------
    temp_c, v_tsp_v : NDArray
        The points: temperatures (degC) and TSP voltages (V).
    file : str or None
        The CSV file's name.
    rows : NDArray or None
        The file row of each point.
    extra : Mapping
        Unknown keys of the section, kept and written back.
    coefficients : tuple of float or None
        The declared polynomial (kind ``polynomial``), checked (:func:`check_coefficients`,
        :func:`check_monotonic`).
    """

    temp_c: NDArray
    v_tsp_v: NDArray
    file: str | None = None
    rows: NDArray | None = field(default=None, repr=False)
    extra: Mapping[str, Any] = field(default_factory=dict, repr=False)
    coefficients: tuple[float, ...] | None = None

    def __post_init__(self) -> None:
        f = self.file or "calibration.csv"
        t = check_column("temp_c", self.temp_c, f, self.rows)
        v = check_column("v_tsp_v", self.v_tsp_v, f, self.rows, t.size)
        check_temperatures(t, f, self.rows, "temp_c")
        if t.size < 2:
            raise DataFormatError(f"{where(f)}a calibration needs at least 2 points")
        set_fields(self, temp_c=t, v_tsp_v=v)
        if self.coefficients is not None:
            coef = check_coefficients(self.coefficients)
            set_fields(self, coefficients=check_monotonic(coef, (float(t.min()),
                                                                 float(t.max()))))

    @property
    def kind(self) -> str:
        """``"table"`` or ``"polynomial"`` (``docs/bundle-format.md``)."""
        return "table" if self.coefficients is None else "polynomial"

    def columns(self) -> dict[str, NDArray]:
        return {"temp_c": self.temp_c, "v_tsp_v": self.v_tsp_v}

    def manifest(self) -> dict[str, Any]:
        if self.coefficients is None:
            return {}
        return {"kind": self.kind, "coefficients_v": list(self.coefficients)}


@dataclass(frozen=True, eq=False)
class KFactorLaw:
    """A K-factor calibration as declared (JESD51-14 practice, PyRth's):
    ``V(T) = v_ref_v + K (T - t_ref_c)``, kind ``k-factor`` of ``docs/bundle-format.md``.

    Only the slope ``K`` (V/K) transfers from the calibration oven to the transient: the sensor
    voltage's absolute level depends on the sense current and the amplifier's offset, so the
    voltage at a known temperature (``v_ref_v`` at ``t_ref_c``, e.g. the end of a cooling record
    when the device is back at the reference) anchors it. The law's numbers only; its converter
    is :class:`spicethermal.identify.calibration.KFactor`. Immutable; raises
    :class:`DataFormatError` naming the bad parameter. Two laws with the same numbers are equal.

    Attributes
    ----------
    k_v_per_k : float
        The slope K, V/K.
    v_ref_v, t_ref_c : float
        The anchor: the voltage (V) at the reference temperature (degC).
    label : str
        How messages name the calibration.

    >>> law = KFactorLaw.from_mv_per_k(-2.0, v_ref_v=0.6, t_ref_c=25.0)
    >>> law.kind, law.manifest()["k_mv_per_k"]
    ('k-factor', -2.0)
    """

    k_v_per_k: float
    v_ref_v: float
    t_ref_c: float
    label: str = "calibration"

    def __post_init__(self) -> None:
        for name in ("k_v_per_k", "v_ref_v", "t_ref_c"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float, np.floating,
                                                                 np.integer)):
                raise DataFormatError(f"{self.label}, {name}: {value!r} is not a number")
            if not math.isfinite(float(value)):
                raise DataFormatError(f"{self.label}, {name}: {value!r} is not a finite number")
            object.__setattr__(self, name, float(value))
        if self.k_v_per_k == 0:
            raise DataFormatError(f"{self.label}, k_v_per_k: zero, the TSP does not depend on T")
        if self.t_ref_c < -273.15:
            raise DataFormatError(f"{self.label}, t_ref_c: below absolute zero")

    def _numbers(self) -> tuple[float, float, float]:
        return self.k_v_per_k, self.v_ref_v, self.t_ref_c

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, KFactorLaw):
            return NotImplemented
        return self._numbers() == other._numbers()

    def __hash__(self) -> int:
        return hash(self._numbers())

    @classmethod
    def from_mv_per_k(cls, k_mv_per_k: float, v_ref_v: float, t_ref_c: float,
                      label: str = "calibration") -> KFactorLaw:
        """The K-factor given in mV/K (the usual datasheet and T3Ster unit).

        Parameters
        ----------
        k_mv_per_k : float
            K, mV/K.
        v_ref_v, t_ref_c : float
            The anchor: the voltage (V) at the reference temperature (degC).
        label : str
            How messages name the calibration.

        Returns
        -------
        KFactorLaw
            Of the class it is called on.
        """
        if isinstance(k_mv_per_k, bool) or not isinstance(k_mv_per_k, (int, float, np.floating,
                                                                       np.integer)):
            raise DataFormatError(f"{label}, k_mv_per_k: {k_mv_per_k!r} is not a number")
        return cls(float(k_mv_per_k) * 1e-3, v_ref_v, t_ref_c, label)

    @property
    def kind(self) -> str:
        return "k-factor"

    @property
    def k_factor_mv_per_k(self) -> float:
        """K in mV/K."""
        return self.k_v_per_k * 1e3

    def manifest(self) -> dict[str, float | str]:
        """The ``calibration`` entry of ``bundle.json`` (see ``docs/bundle-format.md``)."""
        return {"kind": self.kind, "k_mv_per_k": self.k_factor_mv_per_k,
                "v_ref_v": self.v_ref_v, "t_ref_c": self.t_ref_c}

    def __str__(self) -> str:
        return (f"K-factor calibration: K = {self.k_factor_mv_per_k:.4g} mV/K, "
                f"{self.v_ref_v:.6g} V at {self.t_ref_c:g} degC")


@dataclass(frozen=True, eq=False)
class CoolingTable:
    """One cooling curve: ``t_s`` from the instant power is removed, ``tj_c`` or raw
    ``v_tsp_v``, optional ``tref_c``; ``power_w`` before the cut and the steady state just
    before it (``tj_steady_c``, ``tref_steady_c``, either may be unknown)."""

    t_s: NDArray
    power_w: float
    tj_c: NDArray | None = None
    v_tsp_v: NDArray | None = None
    tref_c: NDArray | None = None
    tj_steady_c: float | None = None
    tref_steady_c: float | None = None
    file: str | None = None
    rows: NDArray | None = field(default=None, repr=False)
    extra: Mapping[str, Any] = field(default_factory=dict, repr=False)

    def __post_init__(self) -> None:
        f = self.file or "cooling.csv"
        t = check_column("t_s", self.t_s, f, self.rows)
        check_times(t, f, self.rows)
        tj = check_column("tj_c", self.tj_c, f, self.rows, t.size)
        v = check_column("v_tsp_v", self.v_tsp_v, f, self.rows, t.size)
        if tj is None and v is None:
            raise DataFormatError(f"{where(f)}a cooling curve needs column tj_c or v_tsp_v")
        if tj is not None:
            check_temperatures(tj, f, self.rows, "tj_c")
        tref = check_column("tref_c", self.tref_c, f, self.rows, t.size)
        if tref is not None:
            check_temperatures(tref, f, self.rows, "tref_c")
        set_fields(self, t_s=t, tj_c=tj, v_tsp_v=v, tref_c=tref,
             power_w=scalar(self.power_w, f"{f}: power_w", positive=True, optional=False),
             tj_steady_c=scalar(self.tj_steady_c, f"{f}: tj_steady_c", temperature=True),
             tref_steady_c=scalar(self.tref_steady_c, f"{f}: tref_steady_c",
                                   temperature=True))

    def columns(self) -> dict[str, NDArray]:
        cols = {"t_s": self.t_s}
        for name in ("tj_c", "v_tsp_v", "tref_c"):
            if getattr(self, name) is not None:
                cols[name] = getattr(self, name)
        return cols

    def manifest(self) -> dict[str, Any]:
        entry: dict[str, Any] = {"power_w": self.power_w}
        if self.tj_steady_c is not None:
            entry["tj_steady_c"] = self.tj_steady_c
        if self.tref_steady_c is not None:
            entry["tref_steady_c"] = self.tref_steady_c
        return entry


@dataclass(frozen=True, eq=False)
class PwmTable:
    """PWM readings in the periodic steady state: ``freq_hz``, ``duty``, ``tj_c`` (what the
    bench reads at the end of the sample window), optional ``tref_c`` and per-row
    ``row_power_w`` (column ``power_w``, overrides the section's ``power_w``)."""

    freq_hz: NDArray
    duty: NDArray
    tj_c: NDArray
    power_w: float | None = None
    tref_c: NDArray | None = None
    row_power_w: NDArray | None = None
    sample_window_s: float = 0.0
    file: str | None = None
    rows: NDArray | None = field(default=None, repr=False)
    extra: Mapping[str, Any] = field(default_factory=dict, repr=False)

    def __post_init__(self) -> None:
        f = self.file or "pwm.csv"
        fr = check_column("freq_hz", self.freq_hz, f, self.rows)
        n = fr.size
        check_range(fr, f, self.rows, "freq_hz", low=0, low_open=True, what="must be > 0")
        d = check_column("duty", self.duty, f, self.rows, n)
        check_range(d, f, self.rows, "duty", low=0, high=1, what="must lie in [0, 1]")
        tj = check_column("tj_c", self.tj_c, f, self.rows, n)
        check_temperatures(tj, f, self.rows, "tj_c")
        tref = check_column("tref_c", self.tref_c, f, self.rows, n)
        if tref is not None:
            check_temperatures(tref, f, self.rows, "tref_c")
        pw = check_column("power_w", self.row_power_w, f, self.rows, n)
        if pw is not None:
            check_range(pw, f, self.rows, "power_w", low=0, low_open=True, what="must be > 0")
        power = scalar(self.power_w, f"{f}: power_w", positive=True)
        if power is None and pw is None:
            raise DataFormatError(f"{where(f)}no power: give the section's power_w or a "
                                  f"power_w column")
        window = scalar(self.sample_window_s, f"{f}: sample_window_s", nonnegative=True)
        set_fields(self, freq_hz=fr, duty=d, tj_c=tj, tref_c=tref, row_power_w=pw, power_w=power,
             sample_window_s=0.0 if window is None else window)

    @property
    def powers_w(self) -> NDArray:
        """Power of every row: the row's own ``power_w`` or else the section's."""
        if self.row_power_w is not None:
            return self.row_power_w
        return frozen(np.full(self.freq_hz.size, self.power_w))

    def columns(self) -> dict[str, NDArray]:
        cols = {"freq_hz": self.freq_hz, "duty": self.duty, "tj_c": self.tj_c}
        if self.tref_c is not None:
            cols["tref_c"] = self.tref_c
        if self.row_power_w is not None:
            cols["power_w"] = self.row_power_w
        return cols

    def manifest(self) -> dict[str, Any]:
        entry: dict[str, Any] = {}
        if self.power_w is not None:
            entry["power_w"] = self.power_w
        entry["sample_window_s"] = self.sample_window_s
        return entry


@dataclass(frozen=True, eq=False)
class ZthTable:
    """A thermal impedance curve: ``t_s`` and ``zth_k_per_w`` (absolute) or ``r``
    (normalized, Zth/Rth, then ``rth_k_per_w`` is needed for absolute values)."""

    t_s: NDArray
    zth_k_per_w: NDArray | None = None
    r: NDArray | None = None
    rth_k_per_w: float | None = None
    file: str | None = None
    rows: NDArray | None = field(default=None, repr=False)
    extra: Mapping[str, Any] = field(default_factory=dict, repr=False)

    def __post_init__(self) -> None:
        f = self.file or "zth.csv"
        t = check_column("t_s", self.t_s, f, self.rows)
        check_times(t, f, self.rows)
        z = check_column("zth_k_per_w", self.zth_k_per_w, f, self.rows, t.size)
        r = check_column("r", self.r, f, self.rows, t.size)
        if (z is None) == (r is None):
            raise DataFormatError(f"{where(f)}give exactly one of the columns zth_k_per_w "
                                  f"(absolute) or r (normalized)")
        set_fields(self, t_s=t, zth_k_per_w=z, r=r,
             rth_k_per_w=scalar(self.rth_k_per_w, f"{f}: rth_k_per_w", positive=True))

    @property
    def normalized(self) -> bool:
        """True when the file holds r(t) rather than Zth(t)."""
        return self.r is not None

    def columns(self) -> dict[str, NDArray]:
        key = "r" if self.normalized else "zth_k_per_w"
        return {"t_s": self.t_s, key: self.r if self.normalized else self.zth_k_per_w}

    def manifest(self) -> dict[str, Any]:
        entry: dict[str, Any] = {"normalized": self.normalized}
        if self.rth_k_per_w is not None:
            entry["rth_k_per_w"] = self.rth_k_per_w
        return entry


@dataclass(frozen=True, eq=False)
class ForwardTable:
    """The heater's forward voltage at a few currents and temperatures (the points of its law
    Vf(I, T), ``spicethermal-bundle/3``): ``temp_c`` the fixture's temperature (°C), ``i_a``
    the current (A), ``vf_v`` the voltage (V), optional ``t_pulse_s`` the time from the start
    of the current pulse to the reading (s; 0 or absent: a steady reading), and
    ``sense_current_a`` the bench's sense current, at which the TSP calibration was taken."""

    temp_c: NDArray
    i_a: NDArray
    vf_v: NDArray
    t_pulse_s: NDArray | None = None
    sense_current_a: float | None = None
    file: str | None = None
    rows: NDArray | None = field(default=None, repr=False)
    extra: Mapping[str, Any] = field(default_factory=dict, repr=False)

    def __post_init__(self) -> None:
        f = self.file or "forward.csv"
        t = check_column("temp_c", self.temp_c, f, self.rows)
        check_temperatures(t, f, self.rows, "temp_c")
        i = check_column("i_a", self.i_a, f, self.rows, t.size)
        check_range(i, f, self.rows, "i_a", low=0, low_open=True, what="must be > 0")
        v = check_column("vf_v", self.vf_v, f, self.rows, t.size)
        check_range(v, f, self.rows, "vf_v", low=0, low_open=True, what="must be > 0")
        tp = check_column("t_pulse_s", self.t_pulse_s, f, self.rows, t.size)
        if tp is not None:
            check_range(tp, f, self.rows, "t_pulse_s", low=0, what="must be >= 0")
        set_fields(self, temp_c=t, i_a=i, vf_v=v, t_pulse_s=tp,
                   sense_current_a=scalar(self.sense_current_a, f"{f}: sense_current_a",
                                          positive=True))

    def columns(self) -> dict[str, NDArray]:
        cols = {"temp_c": self.temp_c, "i_a": self.i_a, "vf_v": self.vf_v}
        if self.t_pulse_s is not None:
            cols["t_pulse_s"] = self.t_pulse_s
        return cols

    def manifest(self) -> dict[str, Any]:
        entry: dict[str, Any] = {}
        if self.sense_current_a is not None:
            entry["sense_current_a"] = self.sense_current_a
        return entry
