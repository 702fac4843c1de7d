"""A bundle's data sets as the fits see them (:class:`BundleData`).

Data sets, by name:

* ``cooling_1``, ``cooling_2``, … — every reading of each cooling curve (°C) at ``t_s`` after
  the cut (``t > 0``), with the reference at every reading, the power cut and the reference
  just before the cut;
* ``steady`` — the reading just before each cut, for the curves that record one
  (``tj_steady_c``);
* ``pwm`` — each PWM reading (the periodic steady state read after the declared window);
* ``calibration`` — the temperature the bundle's least-squares *linear* calibration reads at
  each calibration point, against the thermocouple's.

Cooling curves recorded in volts are converted through that same linear calibration, so a
curvature of the TSP shows the same way in every data set and is never absorbed twice. The
calibration points are kept (``line_temps_c``) so the measurement model can read through
their least-squares line: the conversion of readings in volts, and the most likely one of
readings a bench converted to °C itself (which may also have followed the TSP's law;
:mod:`spicethermal.effects.tsp_nonlinearity` tries both).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from ..core.errors import DataFormatError
from ..effects.base import CALIBRATION, COOLING, DEVICE, PWM, STEADY
from ..identify.readings import converter

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

    from ..effects import Effect
    from ..io.bundle import Bundle

__all__ = ["BundleData", "CalData", "CurveData", "PwmData", "kind_of"]


def kind_of(name: str) -> str:
    """The kind of data set ``name`` (``cooling_2`` is a cooling curve).

    >>> kind_of("cooling_2"), kind_of("pwm")
    ('cooling', 'pwm')
    """
    return COOLING if name.startswith(COOLING) else name


@dataclass(frozen=True, eq=False)
class CurveData:
    """One cooling curve: readings ``tj_c`` at ``t_s`` (t > 0 only), the reference at every
    reading, the power before the cut, the reference just before it and the steady reading
    just before it (None when not recorded)."""

    name: str
    t_s: NDArray
    tj_c: NDArray
    tref_c: NDArray
    power_w: float
    tref_steady_c: float
    tj_steady_c: float | None
    has_tref_column: bool


@dataclass(frozen=True, eq=False)
class PwmData:
    """The PWM grid: one reading per row, and the bundle's declared sample window.

    ``correction_k`` is no data: the departure of a nonlinear model's exact periodic state
    from the closed form the fits evaluate, computed at one model (a deferred correction:
    :func:`~spicethermal.fit.search.settle`) and added to the closed form of every model
    whose device effects include those of that model, ``corrected_for`` (their names and
    forms): a further effect changes the correction by a fraction of what it adds, where
    leaving the correction out would err by all of it.
    """

    freq_hz: NDArray
    duty: NDArray
    power_w: NDArray
    tref_c: NDArray
    tj_c: NDArray
    window_s: float
    correction_k: NDArray | None = None
    corrected_for: frozenset[tuple[str, str]] = frozenset()


@dataclass(frozen=True, eq=False)
class CalData:
    """Calibration points: thermocouple ``temp_c`` and the temperature ``read_c`` that the
    least-squares straight line gives for the measured voltage."""

    temp_c: NDArray
    read_c: NDArray


@dataclass(frozen=True, eq=False)
class BundleData:
    """The arrays of a bundle the fits and the diagnosis compare against.

    >>> from spicethermal.io.bundle import Bundle, PwmTable
    >>> d = BundleData.from_bundle(Bundle(ambient_c=25.0,
    ...                            pwm=PwmTable([1e3], [0.5], [30.0], power_w=0.1)))
    >>> d.datasets
    ('pwm',)
    """

    cooling: tuple[CurveData, ...] = ()
    pwm: PwmData | None = None
    calibration: CalData | None = None
    ambient_c: float = 25.0
    source: str = "bundle"
    #: The calibration points (their least-squares line converts readings); None without
    #: calibration points (readings through the TSP's tangent).
    line_temps_c: NDArray | None = None
    #: Whether the cooling curves came in volts (converted here through that line).
    in_volts: bool = False

    @classmethod
    def from_bundle(cls, bundle: Bundle) -> BundleData:
        """The data sets of ``bundle``."""
        ambient = bundle.ambient_c if bundle.ambient_c is not None else 25.0
        # the points' least-squares line (a polynomial as given; a K-factor is linear already)
        line = None if bundle.calibration is None else converter(bundle.calibration, 1)
        curves = []
        for i, c in enumerate(bundle.cooling):
            tj = np.asarray(c.tj_c if c.tj_c is not None else line.temperature(c.v_tsp_v),
                            dtype=float)
            rows, steady = bundle.cooling_reference_c(i)
            if steady is None:
                steady = float(rows[0]) if rows is not None else ambient
            tref = (np.asarray(rows, dtype=float) if rows is not None
                    else np.full(tj.size, float(steady)))
            keep = np.asarray(c.t_s) > 0
            curves.append(CurveData(f"{COOLING}_{i + 1}", np.asarray(c.t_s, float)[keep],
                                    tj[keep], tref[keep], float(c.power_w), float(steady),
                                    c.tj_steady_c, rows is not None))
        pwm = None
        if bundle.pwm is not None:
            p = bundle.pwm
            tref = (np.asarray(p.tref_c, dtype=float) if p.tref_c is not None
                    else np.full(p.freq_hz.size, ambient))
            pwm = PwmData(np.asarray(p.freq_hz, float), np.asarray(p.duty, float),
                          np.asarray(p.powers_w, float), tref, np.asarray(p.tj_c, float),
                          float(p.sample_window_s))
        cal = None
        points = getattr(bundle.calibration, "temp_c", None)  # a K-factor has no points
        if line is not None and points is not None and np.unique(points).size >= 3:
            cal = CalData(np.asarray(bundle.calibration.temp_c, float),
                          np.asarray(line.temperature(bundle.calibration.v_tsp_v), float))
        in_volts = bool(bundle.cooling) and all(c.tj_c is None for c in bundle.cooling)
        return cls(tuple(curves), pwm, cal, float(ambient), bundle.source or "bundle",
                   np.asarray(points, float) if cal is not None else None, in_volts)

    # -- views -------------------------------------------------------------------------------
    @property
    def steady_curves(self) -> tuple[CurveData, ...]:
        """The curves that record their steady reading."""
        return tuple(c for c in self.cooling if c.tj_steady_c is not None)

    @property
    def datasets(self) -> tuple[str, ...]:
        """Names of the data sets, in report order."""
        names = [c.name for c in self.cooling]
        if self.steady_curves:
            names.append(STEADY)
        if self.pwm is not None:
            names.append(PWM)
        if self.calibration is not None:
            names.append(CALIBRATION)
        return tuple(names)

    @property
    def kinds(self) -> frozenset[str]:
        """The kinds of data set present."""
        return frozenset(kind_of(n) for n in self.datasets)

    def curve(self, name: str) -> CurveData:
        """The cooling curve called ``name``."""
        return next(c for c in self.cooling if c.name == name)

    def measured(self, name: str) -> NDArray:
        """Readings (°C) of data set ``name``."""
        if name == PWM:
            return self.pwm.tj_c
        if name == CALIBRATION:
            return self.calibration.read_c
        if name == STEADY:
            return np.array([c.tj_steady_c for c in self.steady_curves], dtype=float)
        return self.curve(name).tj_c

    def coordinates(self, name: str) -> list[dict[str, float]]:
        """``at`` of every point of data set ``name``."""
        if name == PWM:
            return [{"freq_hz": float(f), "duty": float(d)}
                    for f, d in zip(self.pwm.freq_hz, self.pwm.duty, strict=True)]
        if name == CALIBRATION:
            return [{"temp_c": float(t)} for t in self.calibration.temp_c]
        if name == STEADY:
            return [{"power_w": c.power_w} for c in self.steady_curves]
        return [{"t_s": float(t)} for t in self.curve(name).t_s]

    def sizes(self) -> dict[str, int]:
        """Number of points of every data set."""
        return {n: int(self.measured(n).size) for n in self.datasets}

    def subset(self, names: Iterable[str]) -> BundleData:
        """The data sets ``names`` only (``steady`` follows its curves)."""
        keep = set(names)
        return replace(self, cooling=tuple(c for c in self.cooling if c.name in keep),
                       pwm=self.pwm if PWM in keep else None,
                       calibration=self.calibration if CALIBRATION in keep else None)

    def with_pwm_correction(self, correction_k: NDArray | None,
                            effects: Sequence[Effect] = ()) -> BundleData:
        """These data with ``correction_k``, the PWM readings' correction computed at a model
        with ``effects``, held for the models whose device effects include them (names and
        forms; see :class:`PwmData`); None removes it."""
        if self.pwm is None:
            return self
        key = frozenset((e.name, e.form) for e in effects if e.kind == DEVICE)
        return replace(self, pwm=replace(self.pwm, correction_k=correction_k,
                                         corrected_for=key))

    @property
    def reference_curve(self) -> CurveData:
        """The lowest-power cooling curve (the least heated, as the paper measured)."""
        if not self.cooling:
            raise DataFormatError(f"{self.source}: no cooling curve to fit a ladder from")
        return min(self.cooling, key=lambda c: c.power_w)

    @property
    def reference_c(self) -> float:
        """The reference temperature laws are written at (the first curve's, else the
        ambient)."""
        return self.cooling[0].tref_steady_c if self.cooling else self.ambient_c


def stack(parts: Mapping[str, NDArray], names: Iterable[str]) -> NDArray:
    """The arrays ``parts[n]`` (``(B, N_n)``) of ``names`` side by side."""
    return np.concatenate([parts[n] for n in names], axis=-1)
