"""The data sets of a measurement bundle, one immutable table each: :class:`CalibrationTable`,
:class:`CoolingTable`, :class:`PwmTable`, :class:`ZthTable`, :class:`ForwardTable`
(``docs/bundle-format.md``).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from ..core.errors import DataFormatError, where
from ..identify.calibration import Calibration

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
@dataclass(frozen=True, eq=False)
class CalibrationTable:
    """TSP calibration points: ``temp_c`` (degC) and ``v_tsp_v`` (V), one row per point.

    Kind ``table`` (a polynomial is fitted here, :meth:`fit`) or, with ``coefficients`` (V per
    degC^k, ascending), kind ``polynomial``: a fit made elsewhere, the points kept for its
    residuals. The other kind, a K-factor, is :class:`~spicethermal.identify.calibration.KFactor`.
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
            set_fields(self, coefficients=self.fit().coefficients)

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

    def fit(self, degree: int | str = "auto") -> Calibration:
        """The :class:`~spicethermal.identify.calibration.Calibration`: fitted to the points
        (``"auto"``: linear unless its linearity test fails, then quadratic), or the given
        polynomial (``degree`` is then ignored)."""
        if self.coefficients is not None:
            return Calibration.from_coefficients(self.coefficients, self.temp_c, self.v_tsp_v)
        return Calibration.fit(self.temp_c, self.v_tsp_v, degree=degree)


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
