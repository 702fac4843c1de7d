"""Measured versus model, point by point, over every data set of a bundle.

:func:`compare` predicts what the bench would have read for each measured point through the
one forward model (:func:`spicethermal.fit.forward.predict`: the model's device effects in
the network, its measurement effects on the readings) and returns a :class:`Comparison`
(immutable): the ``spicethermal-comparison/1`` document, the paper-style Table 2 text, and
per-data-set views for the diagnosis. Data sets:

* ``cooling_1``, ``cooling_2``, ... — each reading of each cooling curve (``at = {"t_s"}``):
  the model's cooling from its steady state at the curve's power, plus the reference
  (``tref_c`` column, else ``tref_steady_c``, else the bundle's ``ambient_c``); a record of
  more than :data:`MAX_COOLING_POINTS` readings is compared as means over log-time bins;
* ``steady`` — the reading just before each cut, where the bundle records one;
* ``pwm`` — each row of ``pwm.csv`` (``at = {"freq_hz", "duty"}``): the periodic-steady-state
  *reading* (the junction temperature at the end of the power-off sample window that starts
  when an on-phase ends). The engine is ``analytic`` (closed form; with device effects the
  network frozen at the mean temperatures, as the fits use it), ``ngspice`` or ``pyspice``
  (the exported subcircuit from its periodic steady state, :mod:`spicethermal.engines.pwmsim`,
  exact); ``auto`` is analytic;
* ``calibration`` — what the bundle's linear calibration reads at each calibration point.

``residual_k = measured_c − model_c``.

>>> from spicethermal.core.ladder import Foster
>>> from spicethermal.model import ThermalModel
>>> from spicethermal.io.bundle import Bundle, PwmTable
>>> m = ThermalModel(Foster.from_tau([100.0], [10.0]))   # ripple 0.5 mK at 1 kHz
>>> b = Bundle(ambient_c=25.0, pwm=PwmTable([1e3], [0.5], [30.5], power_w=0.1))
>>> c = compare(m, b)
>>> round(c.points[0].model_c, 3), round(c.rms_k, 3)
(30.0, 0.5)
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from types import MappingProxyType
from typing import TYPE_CHECKING, Any

import numpy as np

from ..core.errors import DataFormatError
from ..effects.base import MeasurementEffect, scalar_params
from ..engines.network import NetworkBatch
from ..engines.pwmsim import ENGINES, SpicePwm, run_parallel
from ..fit.forward import MeasurementTerm, predict, pwm_correction
from ..fit.measurement import BundleData, CurveData

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import ArrayLike, NDArray

    from ..io.bundle import Bundle
    from ..model import ThermalModel

COMPARISON_FORMAT = "spicethermal-comparison/1"
#: Reference temperature assumed when a bundle gives none (the paper's Table 2 adds 25 °C).
DEFAULT_REFERENCE_C = 25.0
#: Cooling curves with more samples are compared as means over log-time bins.
MAX_COOLING_POINTS = 2000
#: Log-time bins per decade of a long cooling curve (:func:`log_bin_means`).
COOLING_BINS_PER_DECADE = 100

@dataclass(frozen=True)
class ComparisonPoint:
    """One measured point and the model's prediction of it (°C).

    ``at`` locates the point in its data set (``{"freq_hz", "duty"}`` or ``{"t_s"}``);
    ``info`` carries what the prediction used (power, reference, window) and is not part of
    the JSON document.
    """

    dataset: str
    at: Mapping[str, float]
    measured_c: float
    model_c: float
    info: Mapping[str, float] = field(default_factory=dict, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "at", MappingProxyType(dict(self.at)))
        object.__setattr__(self, "info", MappingProxyType(dict(self.info)))

    @property
    def residual_k(self) -> float:
        """Measured minus model, K."""
        return self.measured_c - self.model_c

    def to_json(self) -> dict[str, Any]:
        return {"dataset": self.dataset, "at": dict(self.at), "measured_c": self.measured_c,
                "model_c": self.model_c, "residual_k": self.residual_k}


@dataclass(frozen=True)
class Comparison:
    """Points of one or more data sets, measured vs model.

    >>> c = Comparison((ComparisonPoint("pwm", {"freq_hz": 1e3, "duty": 0.5}, 30.0, 29.0),
    ...                 ComparisonPoint("cooling_1", {"t_s": 1e-3}, 40.0, 40.5)))
    >>> c.rms_k, c.max_abs_k, c.datasets
    (0.7905694150420949, 1.0, ('pwm', 'cooling_1'))
    """

    points: tuple[ComparisonPoint, ...]
    engine: str = "analytic"
    #: Per cooling curve, the samples fit masks and compare left out: ``{"samples", "before_s"}``
    left_out: Mapping[str, Mapping[str, float]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        object.__setattr__(self, "points", tuple(self.points))
        object.__setattr__(self, "left_out", MappingProxyType(dict(self.left_out)))

    # -- numbers ---------------------------------------------------------------------------
    @property
    def residuals_k(self) -> NDArray:
        """Measured minus model of every point, K."""
        return np.array([p.residual_k for p in self.points], dtype=float)

    @property
    def rms_k(self) -> float:
        """Root mean square residual, K (NaN without points)."""
        r = self.residuals_k
        return float(np.sqrt(np.mean(r * r))) if r.size else math.nan

    @property
    def max_abs_k(self) -> float:
        """Largest absolute residual, K (NaN without points)."""
        r = self.residuals_k
        return float(np.max(np.abs(r))) if r.size else math.nan

    @property
    def datasets(self) -> tuple[str, ...]:
        """Data set names in order of appearance."""
        return tuple(dict.fromkeys(p.dataset for p in self.points))

    def dataset(self, name: str) -> Comparison:
        """The points of one data set (``"pwm"``, ``"cooling_1"``, ...)."""
        return Comparison(tuple(p for p in self.points if p.dataset == name), self.engine,
                          {k: v for k, v in self.left_out.items() if k == name})

    def by_dataset(self) -> dict[str, Comparison]:
        """Every data set's own comparison."""
        return {name: self.dataset(name) for name in self.datasets}

    def worst(self, n: int = 5) -> tuple[ComparisonPoint, ...]:
        """The ``n`` points with the largest absolute residual, worst first."""
        return tuple(sorted(self.points, key=lambda p: -abs(p.residual_k))[:n])

    # -- output ----------------------------------------------------------------------------
    def to_json(self) -> dict[str, Any]:
        """The ``spicethermal-comparison/1`` document."""
        doc = {"format": COMPARISON_FORMAT, "rms_k": _finite(self.rms_k),
               "max_abs_k": _finite(self.max_abs_k),
               "points": [p.to_json() for p in self.points]}
        if self.left_out:
            doc["left_out"] = {k: dict(v) for k, v in self.left_out.items()}
        return doc

    def table(self) -> str:
        """Text, one table per kind of data set: PWM as the paper's Table 2 (the power in a
        column when it varies), the cooling curves one row each, the steady readings and the
        calibration one row each, then all points.

        >>> pts = [ComparisonPoint("pwm", {"freq_hz": f, "duty": d}, 30.0, 29.5,
        ...                        {"power_w": 0.094 + f * 1e-9, "window_s": 1e-4})
        ...        for f in (500.0, 25e3) for d in (0.2, 0.8)]
        >>> print("\\n".join(Comparison(tuple(pts)).table().splitlines()[1:5]))
        Freq (kHz) |            D=20%             |            D=80%             |
                   |   P (W)  T_exp  T_mod      Δ |   P (W)  T_exp  T_mod      Δ |
        --------------------------------------------------------------------------
               0.5 |  0.0940  30.00  29.50   0.50 |  0.0940  30.00  29.50   0.50 |
        """
        lines: list[str] = []
        pwm = self.dataset("pwm")
        if pwm.points:
            lines += _pwm_table(pwm.points, self.engine)
            lines += [_summary("pwm", pwm), ""]
        sets = self.by_dataset()
        cooling = [c for name, c in sets.items() if name.startswith("cooling")]
        if cooling:
            lines += _cooling_table(cooling, self.left_out) + [""]
        for name, what in (("steady", "steady readings just before each cut"),
                           ("calibration", "the linear calibration's reading at each "
                                           "calibration point")):
            if name in sets:
                lines += [f"{what.capitalize()}:", _summary(name, sets[name]), ""]
        lines.append(_summary("all data sets", self))
        return "\n".join(lines)


def _finite(x: float) -> float | None:
    return x if math.isfinite(x) else None


def _summary(name: str, c: Comparison) -> str:
    mean = float(np.mean(c.residuals_k)) if c.points else math.nan
    return (f"{name}: {len(c.points)} points, rms {c.rms_k:.3f} K, max |Δ| {c.max_abs_k:.3f} K, "
            f"mean Δ {mean:.3f} K")


#: PWM conditions shown in the header when constant, else a column: key, head, width, format...
_PWM_CONDITIONS = (("power_w", "P (W)", 8, ".4f", "{:g} W", 1.0),
                   ("window_s", "win (µs)", 9, ".3g", "sample window {:g} µs", 1e6))


def _pwm_table(points: Sequence[ComparisonPoint], engine: str) -> list[str]:
    """The paper's Table 2 layout in one table; a condition that varies between the rows (each
    row's measured power) is a column of each duty's block instead of a header note."""
    freqs = sorted({p.at["freq_hz"] for p in points})
    duties = sorted({p.at["duty"] for p in points})
    cell = {(p.at["freq_hz"], p.at["duty"]): p for p in points}
    notes, columns = [], []
    for key, head, width, fmt, note, scale in _PWM_CONDITIONS:
        values = {p.info.get(key, math.nan) for p in points}
        if len(values) == 1:
            notes.append(note.format(next(iter(values)) * scale))
        else:
            columns.append((head, width, fmt, key, scale))
            notes.append(f"{head.split()[0]} per point")
    lines = [f"PWM (the paper's Table 2): junction temperature, measured (T_exp) vs model "
             f"(T_mod), °C; Δ = T_exp − T_mod, K  [{', '.join(notes)}, engine {engine}]"]
    heads = [f"{h:>{w}}" for h, w, _, _, _ in columns] + \
        [f"{'T_exp':>7}", f"{'T_mod':>7}", f"{'Δ':>7}"]
    block = "".join(heads) + " "
    head = f"{'Freq (kHz)':>10} |" + "".join(f"{'D=' + _pct(d):^{len(block)}}|" for d in duties)
    sub = f"{'':>10} |" + "".join(f"{block}|" for _ in duties)
    lines += [head, sub, "-" * len(sub)]
    for f in freqs:
        row = f"{f / 1e3:>10g} |"
        for d in duties:
            p = cell.get((f, d))
            if p is None:
                row += f"{'':{len(block)}}|"
                continue
            row += "".join(f"{p.info.get(key, math.nan) * scale:{w}{fmt}}"
                           for _, w, fmt, key, scale in columns)
            row += f"{p.measured_c:7.2f}{p.model_c:7.2f}{p.residual_k:7.2f} |"
        lines.append(row)
    return lines


def _cooling_table(curves: Sequence[Comparison], left_out: Mapping[str, Mapping[str, float]]
                   ) -> list[str]:
    """One row per cooling curve: power, points compared, samples left out, rms, max, mean."""
    lines = ["Cooling curves: junction temperature, measured vs model; Δ = measured − model, K"]
    rows = [("curve", "power (W)", "points", "left out", "rms (K)", "max |Δ| (K)", "mean Δ (K)")]
    for c in curves:
        name = c.points[0].dataset
        gone = left_out.get(name, {})
        rows.append((name, f"{c.points[0].info.get('power_w', math.nan):.4g}",
                     str(len(c.points)),
                     f"{gone['samples']:g} before {gone['before_s'] * 1e6:.3g} µs"
                     if gone.get("samples") else "none",
                     f"{c.rms_k:.3f}", f"{c.max_abs_k:.3f}",
                     f"{float(np.mean(c.residuals_k)):.3f}"))
    widths = [max(len(r[k]) for r in rows) for k in range(len(rows[0]))]
    lines += ["  ".join(x.ljust(w) if k == 0 else x.rjust(w)
                        for k, (x, w) in enumerate(zip(r, widths, strict=True))) for r in rows]
    return lines + ["left out: the samples fit masks as the electrical transient"] * any(
        v.get("samples") for v in left_out.values())


def _pct(d: float) -> str:
    return f"{100 * d:g}%"


def log_bin_means(t_s: ArrayLike, *columns: ArrayLike, per_decade: int = COOLING_BINS_PER_DECADE
                  ) -> tuple[NDArray, ...]:
    """Means of ``t_s`` and each column over bins of equal width in log t (``per_decade``).

    A record of 10^6 samples becomes a few hundred points, each the mean of its samples (noise
    averages down; a smooth response is changed only to second order in the bin width).
    Samples at t <= 0 form one bin.

    Parameters
    ----------
    t_s : sample times, ascending.
    columns : arrays of the same length.
    per_decade : bins per decade of t.

    Returns
    -------
    tuple of arrays : the bin means of ``t_s`` and of each column, bins with samples only.

    Examples
    --------
    >>> t, y = log_bin_means([1.0, 1.5, 10.0, 10.5], [1.0, 3.0, 5.0, 7.0], per_decade=2)
    >>> t.tolist(), y.tolist()
    ([1.25, 10.25], [2.0, 6.0])
    """
    t = np.asarray(t_s, dtype=float)
    positive = t[t > 0]
    if positive.size == 0:
        return (t, *(np.asarray(c, dtype=float) for c in columns))
    scaled = np.log10(np.maximum(t, positive[0]) / positive[0]) * per_decade
    key = np.where(t > 0, np.floor(scaled + 1e-9).astype(np.int64) + 1, 0)
    _, inverse, counts = np.unique(key, return_inverse=True, return_counts=True)
    return tuple(np.bincount(inverse, weights=np.asarray(c, dtype=float)) / counts
                 for c in (t, *columns))


def cooling_rise_k(model: ThermalModel, power_w: float, t_s: ArrayLike,
                   tref_c: float = DEFAULT_REFERENCE_C) -> NDArray:
    """Junction rise (K) at ``t_s`` after power ``power_w`` is cut from the steady state
    (closed form for a linear model; the network with its device effects otherwise).

    >>> from spicethermal.core.ladder import Foster
    >>> from spicethermal.model import ThermalModel
    >>> cooling_rise_k(ThermalModel(Foster.from_tau([10.0], [1.0])), 2.0, [0.0]).tolist()
    [20.0]
    """
    t = np.asarray(t_s, dtype=float)
    return NetworkBatch.of(model.ladder, model.effects).cooling(power_w, tref_c, t)[0]


def _binned(data: BundleData) -> BundleData:
    """``data`` with every cooling record longer than :data:`MAX_COOLING_POINTS` replaced by
    its means over log-time bins."""
    curves = []
    for c in data.cooling:
        if c.t_s.size > MAX_COOLING_POINTS:
            t, tj, tref = log_bin_means(c.t_s, c.tj_c, c.tref_c)
            c = CurveData(c.name, t, tj, tref, c.power_w, c.tref_steady_c, c.tj_steady_c,
                          c.has_tref_column)
        curves.append(c)
    return replace(data, cooling=tuple(curves))


def _spice_after_off(model: ThermalModel, data: BundleData, engine: str, dialect: str,
                     quiet: bool):
    """The PWM rows' junction temperature ``delay`` after an on-phase ends, each from the
    exported subcircuit's periodic steady state in ngspice (every delay asked once)."""
    p = data.pwm
    sims = {tref: SpicePwm(model, engine, dialect, tref_c=tref) for tref in set(p.tref_c)}
    cache: dict[float, NDArray] = {}

    def after_off(delay: NDArray | float) -> NDArray:
        d = float(np.asarray(delay).ravel()[0])
        if d not in cache:
            states = run_parallel([(sims[t], w, f, du, d) for w, f, du, t in
                                   zip(p.power_w, p.freq_hz, p.duty, p.tref_c, strict=True)],
                                  quiet=quiet)
            cache[d] = np.array([[t + s.reading_k for s, t in zip(states, p.tref_c,
                                                                   strict=True)]])
        return cache[d]

    return after_off


def compare(model: ThermalModel, bundle: Bundle, engine: str = "auto", *,
            window_s: float | None = None, datasets: Sequence[str] | None = None,
            dialect: str = "ngspice", quiet: bool = True) -> Comparison:
    """Measured vs model over every data set of ``bundle`` (or only the named ``datasets``).

    Parameters
    ----------
    model : ThermalModel
    bundle : Bundle
    engine : ``auto`` (analytic), ``analytic``, ``ngspice`` or ``pyspice``: how PWM
        readings are computed (analytic: the closed form, plus the exact periodic state's
        correction for a model with device effects,
        :func:`~spicethermal.fit.forward.pwm_correction`).
    window_s : sample window overriding the bundle's declared one.
    datasets : e.g. ``["pwm"]`` or ``["cooling_1"]``; default all.
    dialect : ``.lib`` dialect for the ngspice engines.
    quiet : no progress bar for the ngspice runs (shown on a terminal otherwise).

    Returns
    -------
    Comparison

    Examples
    --------
    >>> from spicethermal.core.ladder import Foster
    >>> from spicethermal.model import ThermalModel
    >>> from spicethermal.io.bundle import Bundle, CoolingTable
    >>> m = ThermalModel(Foster.from_tau([10.0], [1.0]))
    >>> b = Bundle(ambient_c=25.0, cooling=(CoolingTable([0.0, 1.0], 2.0,
    ...            tj_c=[45.0, 25.0 + 20 * np.exp(-1)]),))
    >>> compare(m, b).max_abs_k < 1e-12
    True
    """
    if model.reference != bundle.reference:
        raise DataFormatError(f"{bundle.source or 'bundle'}: measured against the "
                              f"{bundle.reference} but the model's reference is "
                              f"{model.reference}")
    engine = "analytic" if engine == "auto" else engine
    if engine not in ENGINES:
        raise DataFormatError(f"engine {engine!r}: expected auto or one of {', '.join(ENGINES)}")
    data = BundleData.from_bundle(bundle)
    available = data.datasets
    wanted = list(available) if datasets is None else list(datasets)
    unknown = [d for d in wanted if d not in available]
    if unknown:
        raise DataFormatError(f"{bundle.source or 'bundle'}: no data set {unknown[0]!r} "
                              f"(available: {', '.join(available) or 'none'})")
    if not wanted:
        raise DataFormatError(f"{bundle.source or 'bundle'}: nothing to compare (no pwm, "
                              f"cooling or calibration data)")
    data = _binned(data.subset(wanted))
    if window_s is not None and data.pwm is not None:
        if not (math.isfinite(window_s) and window_s >= 0):
            raise DataFormatError(f"window_s = {window_s!r}: must be >= 0 and finite")
        data = replace(data, pwm=replace(data.pwm, window_s=float(window_s)))
    spice = (_spice_after_off(model, data, engine, dialect, quiet)
             if engine != "analytic" and data.pwm is not None else None)
    if spice is None:  # the closed form, made exact for a nonlinear model
        data = data.with_pwm_correction(pwm_correction(data, model.ladder, model.effects),
                                        model.effects)
    measures = [MeasurementTerm(e.plugin, e.form, scalar_params(e))  # type: ignore[arg-type]
                for e in model.effects if isinstance(e.plugin, MeasurementEffect)]
    pred = predict(data, NetworkBatch.of(model.ladder, model.effects), measures, spice)
    info = _info(data)
    points: list[ComparisonPoint] = []
    for name in data.datasets:
        for k, (at, meas, mod) in enumerate(zip(data.coordinates(name), data.measured(name),
                                                pred[name][0], strict=True)):
            if not math.isfinite(float(mod)):
                raise DataFormatError(f"{bundle.source or 'bundle'}: the model cannot be "
                                      f"simulated at {name} {at}")
            points.append(ComparisonPoint(name, at, float(meas), float(mod),
                                          info.get(name, [{}] * (k + 1))[k]))
    left_out = {f"cooling_{i + 1}": dict(c.extra["left_out"])
                for i, c in enumerate(bundle.cooling)
                if "left_out" in c.extra and f"cooling_{i + 1}" in wanted}
    return Comparison(tuple(points), engine, left_out)


def _info(data: BundleData) -> dict[str, list[dict[str, float]]]:
    """What each prediction used (power, reference, window), by data set."""
    out = {c.name: [{"power_w": c.power_w, "tref_c": float(t)} for t in c.tref_c]
           for c in data.cooling}
    if data.pwm is not None:
        p = data.pwm
        out["pwm"] = [{"power_w": float(w), "tref_c": float(t), "window_s": p.window_s}
                      for w, t in zip(p.power_w, p.tref_c, strict=True)]
    return out


def comparison_of(data: BundleData, predictions: dict) -> Comparison:
    """Measured vs predicted at every point of every data set."""
    return Comparison(tuple(ComparisonPoint(name, at, float(meas), float(mod))
                            for name in data.datasets for at, meas, mod in zip(
                                data.coordinates(name), data.measured(name), predictions[name],
                                strict=True)))
