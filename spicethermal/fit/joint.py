"""Joint fits of a ladder and its effects to every data set of a bundle.

One problem layout (:class:`Layout`): the ladder's Foster ``log R`` and ``log τ`` (unless the
ladder is held; the network is simulated on the Cauer form of each trial ladder,
:func:`~spicethermal.engines.network.cauer_of_foster`) and the fitted parameters of each
effect (on a log scale where the parameter says so), the other parameters held at each
start's values. Residuals are each data set's readings minus the forward model's
(:func:`~spicethermal.fit.forward.predict`) over the data set's noise, so ``2·cost`` is the
noise-weighted χ². Many starts (and discrete variants such as a node or a layer subset) are
fitted side by side (:func:`~spicethermal.fit.lm.levenberg_marquardt`).

:func:`fit_baseline` is the linear ladder fitted to every data set, its order chosen by the
Bayesian information criterion.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from functools import lru_cache
from typing import TYPE_CHECKING

import numpy as np

from ..core.errors import DataFormatError, FitError
from ..core.ladder import Cauer, Foster
from ..effects.base import DeviceEffect, EffectPlugin
from ..effects.registry import Effect
from ..engines.cauer import as_cauer, cauer_of_foster
from ..engines.network import TOL_REL, DeviceTerm, NetworkBatch
from ..identify.curves import ZthCurve
from .forward import MeasurementTerm, line_error, predict
from .ladder import fit_foster
from .lm import MAX_ROUNDS, levenberg_marquardt
from .measurement import BundleData, CurveData
from .problem import MIN_TAU_RATIO

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

__all__ = ["MAX_ORDER", "Layout", "ModelFit", "Start", "bic", "chi2_by_set", "fit_baseline",
           "fit_starts", "penalty", "reference_order", "stage_more", "start_ladders",
           "tau_range"]

#: The baseline's order is searched up to this many stages (a distributed line or a continuous
#: spectrum, read quietly, needs ten or more) ...
MAX_ORDER = 12
#: ... and stops after this many orders in a row that do not lower the criterion.
ORDER_PATIENCE = 2
#: Bounds of a ladder's ``log R`` and ``log τ`` in a fit.
LOG_BOUND = 60.0
#: A fit's transients need be no more exact than its data: a step is accepted within this
#: fraction of the quietest cooling curve's noise (a model error of a tenth of the noise adds
#: about 1 % to a curve's χ²), when that is looser than the network's own tolerance (a
#: screen's, looser, in proportion). The models a fit returns are evaluated at the network's.
NOISE_FRACTION = 0.1
#: Every start of a fit is rounded to this many significant digits. numpy's and BLAS's
#: vector kernels may round the last bit differently with the memory alignment of their
#: arrays, which changes from run to run; a fit that chains on such a result (a start from a
#: nearly degenerate ladder, a refit from a converged model) would otherwise carry a 1e-16
#: difference into a different local minimum, and the same bundle could get another verdict.
#: Seven digits leave a start where it was (a fit moves it far more) and absorb any
#: difference below about 1e-9 of a value.
START_DIGITS = 7


def settled(values: NDArray) -> NDArray:
    """``values`` rounded to :data:`START_DIGITS` significant digits (correctly rounded
    decimal conversion, the same on every machine whatever the arrays' alignment)."""
    a = np.asarray(values, dtype=float)
    return np.array([float(f"{v:.{START_DIGITS}g}") for v in a.ravel()]).reshape(a.shape)


@dataclass(frozen=True, eq=False)
class ModelFit:
    """A fitted model: its Cauer ladder, its effects, its predictions and residuals by data
    set, the noise-weighted χ² by data set, the number of parameters fitted, and the work
    (forward-model rows) it cost."""

    ladder: Cauer
    effects: tuple[Effect, ...]
    predictions: Mapping[str, NDArray]
    chi2: Mapping[str, float]
    n_params: int
    work: int = 0
    converged: bool = True

    @property
    def chi2_total(self) -> float:
        return float(sum(self.chi2.values()))

    @property
    def foster(self) -> Foster:
        return self.ladder.to_foster()

    def effect(self, name: str) -> Effect | None:
        return next((e for e in self.effects if e.name == name), None)


def bic(fit: ModelFit, n_points: int) -> float:
    """``χ² + k ln N``: the criterion every comparison of models uses.

    Parameters
    ----------
    fit : ModelFit
    n_points : int

    Returns
    -------
    float
    """
    return fit.chi2_total + penalty(fit.n_params, n_points)


def penalty(n_params: int, n_points: int) -> float:
    """``k ln N``: what the criterion (:func:`bic`) charges for ``n_params`` parameters."""
    return n_params * math.log(max(n_points, 2))


def chi2_by_set(data: BundleData, predictions: Mapping[str, NDArray],
                noise: Mapping[str, float]) -> dict[str, float]:
    """Each data set's χ² of ``predictions`` against ``data``, weighed by its noise."""
    return {n: float(np.sum(((p - data.measured(n)) / noise[n]) ** 2))
            for n, p in predictions.items()}


@dataclass(frozen=True)
class Start:
    """One start: a Cauer ladder and the values of every parameter of each effect."""

    ladder: Cauer
    values: tuple[Mapping[str, float], ...] = ()

    def __post_init__(self) -> None:  # every start settled (see START_DIGITS)
        object.__setattr__(self, "ladder", Cauer(settled(np.array(self.ladder.r)),
                                                 settled(np.array(self.ladder.c))))
        object.__setattr__(self, "values", tuple(
            {k: float(settled(np.array(v))) for k, v in vals.items()} for vals in self.values))


@dataclass(frozen=True, eq=False)
class Layout:
    """Which parameters a fit moves: the ladder's (unless ``hold_ladder``), and for each slot
    ``(plugin, form)`` its fitted parameters (``move[i]`` false holds slot ``i``)."""

    slots: tuple[tuple[EffectPlugin, str], ...]
    n_nodes: int
    hold_ladder: bool = False
    move: tuple[bool, ...] = ()
    names: tuple[tuple[str, ...], ...] = field(init=False)

    def __post_init__(self) -> None:
        move = self.move or (True,) * len(self.slots)
        object.__setattr__(self, "move", tuple(move))
        object.__setattr__(self, "names", tuple(
            p.fitted_names(f) if m else () for (p, f), m in zip(self.slots, move, strict=True)))

    @property
    def ladder_size(self) -> int:
        return 0 if self.hold_ladder else 2 * self.n_nodes

    @property
    def size(self) -> int:
        return self.ladder_size + sum(len(n) for n in self.names)

    def pack(self, start: Start) -> NDArray:
        if self.hold_ladder:
            x = []
        else:  # every mode of the Cauer ladder, even one the junction hardly sees
            r, tau = NetworkBatch(np.array([start.ladder.r]), np.array([start.ladder.c])).foster()
            x = [np.log(np.maximum(r[0], 1e-300)), np.log(tau[0])]
        for (p, _f), names, values in zip(self.slots, self.names, start.values, strict=True):
            x.append([_to_fit(p.params[n], values[n]) for n in names])
        return np.concatenate([np.asarray(v, dtype=float) for v in x]) if x else np.zeros(0)

    def bounds(self, tau_s: tuple[float, float] = (0.0, math.inf)
               ) -> tuple[NDArray, NDArray, NDArray]:
        """``(lo, hi, typical)`` in fit space; the ladder's time constants within ``tau_s``."""
        n = self.ladder_size // 2
        t_lo = max(math.log(tau_s[0]), -LOG_BOUND) if tau_s[0] > 0 else -LOG_BOUND
        t_hi = min(math.log(tau_s[1]), LOG_BOUND) if math.isfinite(tau_s[1]) else LOG_BOUND
        lo = [-LOG_BOUND] * n + [t_lo] * n
        hi = [LOG_BOUND] * n + [t_hi] * n
        typ = [1.0] * self.ladder_size
        for (p, _f), names in zip(self.slots, self.names, strict=True):
            for n in names:
                spec = p.params[n]
                a, b = _to_fit(spec, spec.low), _to_fit(spec, spec.high)
                lo.append(a)
                hi.append(b)
                typ.append(1.0 if spec.log else spec.typical)
        return np.array(lo), np.array(hi), np.array(typ)


def _to_fit(spec, value: float) -> float:
    if spec.log:
        return math.log(max(value, 1e-300)) if value > 0 else -700.0
    return float(value)


def _from_fit(spec, x: NDArray) -> NDArray:
    return np.exp(x) if spec.log else x


class _Problem:
    """The residual function of one layout over a set of starts."""

    def __init__(self, data: BundleData, noise: Mapping[str, float], layout: Layout,
                 starts: Sequence[Start], tol_rel: float = TOL_REL) -> None:
        self.data, self.layout, self.tol_rel = data, layout, tol_rel
        cooling = [noise[c.name] for c in data.cooling]
        self.tol_k = NOISE_FRACTION * tol_rel / TOL_REL * min(cooling) if cooling else 0.0
        self.names = data.datasets
        self.measured = np.concatenate([data.measured(n) for n in self.names])
        self.weight = np.concatenate([np.full(data.measured(n).size, 1.0 / noise[n])
                                      for n in self.names])
        self.ladders_r = np.array([s.ladder.r for s in starts])
        self.ladders_c = np.array([s.ladder.c for s in starts])
        self.values = [{k: np.array([s.values[i][k] for s in starts], dtype=float)
                        for k in p.params} for i, (p, _f) in enumerate(layout.slots)]
        self.line = _line_centre(data)
        self.sizes = [data.measured(n).size for n in self.names]
        # the last network simulated (see predict), at the fit's tolerance and at the default
        self.memo: dict = {}
        self.exact_memo: dict = {}

    def _read(self, pred: Mapping[str, NDArray]) -> NDArray:
        """Every data set's predictions side by side, ``(B, N)``, corrected for the error of
        the calibration line when the bundle holds its points."""
        out = np.concatenate([pred[n] for n in self.names], axis=1)
        if self.line is None:
            return out
        return line_error(out, self.measured, self.weight, self.line)

    def network(self, x: NDArray, rows: NDArray) -> tuple[NDArray, NDArray, list, list]:
        lay = self.layout
        if lay.hold_ladder:
            r, c = self.ladders_r[rows], self.ladders_c[rows]
        else:  # the ladder moves in its Foster coordinates, simulated on its Cauer form
            n = lay.n_nodes
            r, c = cauer_of_foster(np.exp(x[:, :n]), np.exp(x[:, n:2 * n]))
        col = lay.ladder_size
        devices, measures = [], []
        for (p, form), names, values in zip(lay.slots, lay.names, self.values, strict=True):
            params = {k: v[rows][:, None] for k, v in values.items()}
            for k in names:
                params[k] = _from_fit(p.params[k], x[:, col:col + 1])
                col += 1
            if isinstance(p, DeviceEffect):
                devices.append(DeviceTerm(p, form, params))
            else:
                measures.append(MeasurementTerm(p, form, params))  # type: ignore[arg-type]
        return r, c, devices, measures

    def residuals(self, x: NDArray, rows: NDArray) -> NDArray:
        r, c, devices, measures = self.network(x, rows)
        with np.errstate(all="ignore"):
            pred = predict(self.data, NetworkBatch(r, c, devices, self.tol_rel, self.tol_k),
                           measures, memo=self.memo)
            out = (self._read(pred) - self.measured) * self.weight
        return np.where(np.isfinite(out), out, np.nan)

    def model(self, x: NDArray, row: int, noise: Mapping[str, float], k: int, work: int,
              converged: bool) -> ModelFit:
        r, c, devices, measures = self.network(x[None, :], np.array([row]))
        pred = predict(self.data, NetworkBatch(r, c, devices), measures,
                       memo=self.exact_memo)
        read = self._read(pred)[0]
        cuts = np.cumsum([0, *self.sizes])
        preds = {n: read[cuts[i]:cuts[i + 1]] for i, n in enumerate(self.names)}
        chi2 = chi2_by_set(self.data, preds, noise)
        effects = []
        for (p, form), values in zip(self.layout.slots, self.values, strict=True):
            term = next(t for t in devices + measures if t.plugin is p)
            effects.append(Effect(p.name, {k: float(np.asarray(term.params[k]).ravel()[0])
                                           if k in term.params else float(values[k][row])
                                           for k in p.params}, form))
        return ModelFit(Cauer(r[0], c[0]), tuple(effects), preds, chi2, k, work, converged)


def _line_centre(data: BundleData) -> float | None:
    """The centre of the calibration line whose error the fits profile out (the calibration
    points' mean), or None when the bundle holds no calibration points (no prior on it)."""
    if data.calibration is None or data.calibration.temp_c.size < 3:
        return None
    return float(np.mean(data.calibration.temp_c))


def tau_range(data: BundleData) -> tuple[float, float]:
    """Time constants a fitted ladder may take: from a thousandth of the shortest time the
    data resolve (the first cooling reading, a PWM period) to a thousand times the longest
    record. A stage outside is invisible to every reading: left free, a fit parks it where no
    gradient brings it back, and a far faster one makes the network uselessly stiff.

    >>> from spicethermal.io.bundle import Bundle, PwmTable
    >>> tau_range(BundleData.from_bundle(Bundle(pwm=PwmTable([1e3], [0.5], [30.0],
    ...                                                       power_w=0.1))))
    (1e-06, inf)
    """
    shortest = [float(c.t_s[0]) for c in data.cooling if c.t_s.size]
    if data.pwm is not None:
        shortest.append(float(np.min(1.0 / data.pwm.freq_hz)))
    longest = [float(c.t_s[-1]) for c in data.cooling if c.t_s.size]
    return (1e-3 * min(shortest) if shortest else 0.0,
            1e3 * max(longest) if longest else math.inf)


def fit_starts(data: BundleData, noise: Mapping[str, float], layout: Layout,
               starts: Sequence[Start], rounds: int = MAX_ROUNDS,
               n_ladder_params: int | None = None,
               tol_rel: float = TOL_REL,
               go_on: Callable[[], bool] | None = None) -> list[ModelFit | None]:
    """Fit ``layout`` from every start, side by side; one :class:`ModelFit` per start (None
    where the model cannot be evaluated; its ``n_params`` counts the ladder's ``2n`` and every
    fitted effect parameter, or ``n_ladder_params`` for the ladder when given).

    Parameters
    ----------
    data : BundleData
    noise : mapping of data set name to its noise (K)
    layout : Layout
    starts : sequence of Start
    rounds : int
        Levenberg–Marquardt rounds at most.
    n_ladder_params : int, optional
    tol_rel : float
        Tolerance of the network's transients (a screen may take a coarser one than the
        default; the models returned are evaluated at the default).
    go_on : callable, optional
        Whether the fit may take another round (:func:`~.lm.levenberg_marquardt`).

    Returns
    -------
    list of ModelFit or None
        In the order of ``starts``.
    """
    if not starts:
        return []
    prob = _Problem(data, noise, layout, starts, tol_rel)
    x0 = settled(np.array([layout.pack(s) for s in starts]))
    lo, hi, typ = layout.bounds(tau_range(data))
    k_ladder = 2 * layout.n_nodes if n_ladder_params is None else n_ladder_params
    k = k_ladder + sum(len(p.fitted_names(f)) for p, f in layout.slots) \
        + (2 if _line_centre(data) is not None else 0)
    if x0.shape[1] == 0:
        res_x, work, conv = x0, 0, np.ones(len(starts), dtype=bool)
    else:
        res = levenberg_marquardt(prob.residuals, x0, lo, hi, typ, rounds, go_on)
        res_x, work, conv = res.x, res.rows, res.converged
    out: list[ModelFit | None] = []
    for i in range(len(starts)):
        try:
            m = prob.model(res_x[i], i, noise, k, work // len(starts), bool(conv[i]))
        except (DataFormatError, ValueError, ArithmeticError, np.linalg.LinAlgError):
            m = None
        out.append(m if m is not None and math.isfinite(m.chi2_total) else None)
    return out


def start_ladders(data: BundleData, orders: Sequence[int]) -> dict[int, Cauer]:
    """Linear ladders of each order fitted to the Zth of the lowest-power cooling curve (the
    transient masked and extrapolated by √t), as Cauer ladders: the baseline's starts, and a
    start of every candidate's joint refit (the least heated curve is the one the effects,
    which grow with temperature, change least). Each is computed once per curve."""
    out = {}
    for m in orders:
        ladder = _reference_ladder(data.reference_curve, m)
        if ladder is not None and ladder.order == m:
            out[m] = ladder
    return out


def reference_order(data: BundleData) -> int:
    """The order the automatic ladder fit chooses for the least heated curve's Zth: the
    order of the linear network where the effects, which grow with temperature, are
    weakest (the joint baseline's order may have grown with their misfit)."""
    return _reference_order(data.reference_curve)


@lru_cache(maxsize=64)
def _reference_order(c: CurveData) -> int:
    curve = _reference_curve(c)
    try:
        return fit_foster(curve.t_s, curve.zth_k_per_w, rth_k_per_w=curve.rth_k_per_w).order
    except (FitError, DataFormatError, ValueError, ArithmeticError):
        return 0


# cached by the curve itself: a bundle's data with a PWM correction (:func:`~.search.settle`)
# share their curves
@lru_cache(maxsize=64)
def _reference_curve(c: CurveData) -> ZthCurve:
    return ZthCurve.from_cooling(c.t_s, c.tj_c, c.power_w, c.tj_steady_c,
                                 c.tref_c if c.has_tref_column else None, c.tref_steady_c,
                                 label=c.name)


@lru_cache(maxsize=256)
def _reference_ladder(c: CurveData, order: int) -> Cauer | None:
    curve = _reference_curve(c)
    try:
        f = fit_foster(curve.t_s, curve.zth_k_per_w, order=order,
                       rth_k_per_w=curve.rth_k_per_w).foster
    except (FitError, DataFormatError, ValueError, ArithmeticError):
        return None
    # an order whose fit splits one time constant in two is the order below with a stage
    # doubled: no start of its own (the order below with a stage more is one), and a Cauer
    # form of two nearly equal time constants is numerically undetermined
    if np.any(np.diff(np.log(f.tau)) < math.log(MIN_TAU_RATIO)):
        return None
    return as_cauer(f)


def stage_more(ladder: Cauer, share: float = 1e-6) -> Iterator[Cauer]:
    """``ladder`` with a stage more, one ladder for each place it may go: between each two
    time constants (at their geometric mean) and beyond the fastest and the slowest (a
    factor ``e²``), the widest gap first; the new Foster stage carries ``share`` of the
    resistance (at a millionth it changes nothing yet, so a stage more never fits worse).
    Each ladder is converted when it is drawn (the exact Cauer form of a long ladder takes
    tens of ms)."""
    r, tau = NetworkBatch(np.array([ladder.r]), np.array([ladder.c])).foster()
    r, tau = np.maximum(r[0], 1e-9 * np.sum(r[0])), tau[0]
    logs = np.sort(np.log(tau))
    edges = np.concatenate([[logs[0] - 2.0], logs, [logs[-1] + 2.0]])
    for k in np.argsort(-np.diff(edges), kind="stable"):
        yield as_cauer(Foster.from_tau(np.append(r, share * r.sum()),
                                       np.append(tau, math.exp(0.5 * (edges[k] + edges[k + 1])))))


def fit_baseline(data: BundleData, noise: Mapping[str, float],
                 adequate: Callable[[ModelFit], bool] | None = None,
                 max_order: int = MAX_ORDER) -> ModelFit:
    """The linear ladder fitted to every data set (cooling curves, steady readings, PWM
    grid), its order the one with the lowest ``χ² + 2m ln N`` among the ladders that are
    ``adequate`` (bring every data set to its noise). When none is, more stages only chase a
    misfit that is no matter of order (an effect's): the order is then at most that of the
    least heated curve (:func:`reference_order`), where the effects are weakest.

    Parameters
    ----------
    data : BundleData
    noise : mapping of data set name to its noise (K)
    adequate : callable, optional
        Whether a fitted ladder leaves every data set at its noise (default: every one is).
    max_order : int

    Returns
    -------
    ModelFit
    """
    n_points = sum(data.sizes().values())
    fits: list[ModelFit] = []
    best: ModelFit | None = None
    previous: ModelFit | None = None
    worse = 0
    for m in range(1, max_order + 1):
        # from the least heated curve's ladder of this order, and from the previous order's
        # fit with one stage more (so that a stage more never fits worse); a start is
        # computed when its order is reached (the orders past the criterion's are costly fits
        # that split a time constant)
        tries = [Start(s) for s in start_ladders(data, [m]).values()]
        if previous is not None:
            try:
                tries.append(Start(next(stage_more(previous.ladder))))
            except (DataFormatError, ValueError, ArithmeticError, np.linalg.LinAlgError):
                pass
        tries = [t for t in tries if t.ladder.order == m]
        got = [f for f in fit_starts(data, noise, Layout((), m), tries) if f is not None]
        if not got:
            continue
        fit = min(got, key=lambda f: f.chi2_total)
        fits.append(fit)
        previous = fit
        if best is None or bic(fit, n_points) < bic(best, n_points):
            best, worse = fit, 0
        else:
            worse += 1
            if worse >= ORDER_PATIENCE:
                break
    if best is None:
        raise FitError(f"{data.source}: no linear ladder fits the cooling curves")
    if adequate is None or adequate(best):
        return best
    good = [f for f in fits if adequate(f)]
    if good:
        return min(good, key=lambda f: bic(f, n_points))
    limit = max(reference_order(data), 1)
    return min((f for f in fits if f.ladder.order <= limit), default=best,
               key=lambda f: bic(f, n_points))
