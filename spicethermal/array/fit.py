"""Fit the N-port model of an array to its measured Z_ij(t), order chosen automatically.

The model is the Cauer-like network of :class:`~spicethermal.array.ansatz.Layout`: per cell
a chain of ``L`` nodes (the order), coupling conductances between every pair of cell bases
and between neighbours one level up, air paths and a common substrate node. Fitting the
network itself, rather than a matrix of curves, gives every property the issue asks of the
matrix by construction: Z(t) is symmetric, positive semidefinite at every time and shares
its time constants (:mod:`.modal`), and the network *is* the realization the ``.lib``
writes, so the export adds no error of its own.

Method
------
* Residuals: every measured element at its own times, divided by ``sqrt(Z_ii Z_jj)`` (the
  final values of the two self curves), so that every element is judged on the scale of the
  cells it joins; the parameters are the logarithms of every conductance and capacity
  (positive by construction).
* Start: a single-port ladder of order ``L`` fitted to the mean self curve
  (:func:`spicethermal.fit.ladder.fit_foster`), as the chain of every cell; the substrate
  takes the smallest mutual steady value, the couplings start weak.
* Two Levenberg–Marquardt stages with the exact Jacobian (:func:`.ansatz.response`): first
  with the chains shared by all cells (the bases, couplings and substrate free), then every
  parameter free.
* Order: ``L = 1, 2, ...`` up to ``max_order``, stopping after two orders that do not lower
  the Bayesian information criterion ``n ln(RSS/n) + k ln(n)``; the lowest wins.

The error per element is the largest difference between the model and the measured curve,
in percent of the read port's self curve's final value.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from ..core.errors import DataFormatError, FitError
from ..fit.ladder import fit_foster
from .ansatz import Layout, response
from .data import CouplingData
from .model import ArrayModel

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

__all__ = ["DEFAULT_MAX_ORDER", "ArrayFit", "fit_array"]

DEFAULT_MAX_ORDER = 5
#: How far (in e-folds) a parameter may move from its start: keeps a wild step finite.
_RANGE = 12.0
#: Starting coupling conductance between two bases, times the mean self resistance (a tenth
#: of it one level up): strong enough that the fit finds the couplings, not the substrate, to
#: carry the mutual heat at intermediate times.
START_COUPLING = 0.3
#: Most evaluations of the two stages (shared chains, then everything free).
_EVALS = (120, 60)


@dataclass(frozen=True)
class OrderTrial:
    """One order tried: its criterion and fit quality.

    Attributes
    ----------
    order : int
        Chain nodes per cell.
    bic : float
        Bayesian information criterion.
    rms : float
        RMS of the scaled residuals (fraction of the self values).
    max_error : float
        Largest error of any element, fraction of the read port's self final value.
    parameters : int
        Free parameters.
    """

    order: int
    bic: float
    rms: float
    max_error: float
    parameters: int


@dataclass(frozen=True, eq=False)
class ArrayFit:
    """The fitted array model and how well it reproduces every element.

    Attributes
    ----------
    model : ArrayModel
        The fitted network.
    order : int
        Chain nodes per cell.
    error : NDArray
        ``(N, N)``: largest |model − measured| of each element, fraction of the read port's
        self final value (NaN where not measured).
    rms : float
        RMS of the scaled residuals.
    trials : tuple of OrderTrial
        Every order tried.
    """

    model: ArrayModel
    order: int
    error: NDArray
    rms: float
    trials: tuple[OrderTrial, ...] = field(default=())

    @property
    def max_error(self) -> float:
        """The largest element error (fraction)."""
        return float(np.nanmax(self.error))

    def table(self) -> str:
        """The error per element in percent: rows read, columns heated.

        Returns
        -------
        str
        """
        names = [p.name for p in self.model.ports]
        width = max(6, *(len(n) for n in names))
        lines = ["error per element, % of Z_ii final (rows: read port i, columns: heated "
                 "port j)", " " * width + "".join(f"{n:>{width + 1}}" for n in names)]
        for i, n in enumerate(names):
            cells = "".join(f"{'-':>{width + 1}}" if math.isnan(x) else
                            f"{100 * x:>{width + 1}.2f}" for x in self.error[i])
            lines.append(f"{n:<{width}}{cells}")
        return "\n".join(lines)

    def __str__(self) -> str:
        m = self.model
        dc = m.modes.dc()
        n = m.n_ports
        mutual = [dc[i, j] / dc[i, i] for i in range(n) for j in range(n) if i != j]
        ratio = (f"; mutual/self at steady state {100 * min(mutual):.1f}–"
                 f"{100 * max(mutual):.1f} %" if mutual else "")
        taus = m.modes.tau
        return (f"{n}-port network, order {self.order} ({len(m.nodes)} nodes, "
                f"{len(m.resistors)} resistors), time constants {taus.min():.3g}–"
                f"{taus.max():.3g} s{ratio}; worst element {100 * self.max_error:.2f} % of "
                f"Z_ii final, rms {100 * self.rms:.3f} %")


class _Problem:
    """The scaled residuals of one layout against the data, and their Jacobian."""

    def __init__(self, data: CouplingData, layout: Layout) -> None:
        self.data, self.layout = data, layout
        final = data.final()
        self.self_final = np.diag(final).copy()
        if np.any(~np.isfinite(self.self_final)) or np.any(self.self_final <= 0):
            raise FitError(f"{data.source}: a self curve does not rise (final value <= 0)")
        self.groups = []
        for t, members in data.groups():
            els = [data.elements[k] for k in members]
            pairs = [(e.i, e.j) for e in els]
            z = np.array([e.z_k_per_w for e in els])
            w = 1.0 / np.sqrt(np.array([self.self_final[i] * self.self_final[j]
                                        for i, j in pairs]))
            self.groups.append((t, pairs, z, w))
        self.n = sum(z.size for _, _, z, _ in self.groups)

    def residual(self, p: NDArray, jacobian: bool = False):
        zs, dzs = response(self.layout, p, [(t, pairs) for t, pairs, _, _ in self.groups],
                           jacobian)
        r = np.concatenate([((zm - z) * w[:, None]).ravel()
                            for zm, (_, _, z, w) in zip(zs, self.groups, strict=True)])
        if not jacobian:
            return r
        j = np.concatenate([(d * w[None, :, None]).reshape(len(p), -1)
                            for d, (_, _, _, w) in zip(dzs, self.groups, strict=True)], axis=1)
        return r, j.T

    def errors(self, model: ArrayModel) -> NDArray:
        out = np.full((self.data.n_ports,) * 2, np.nan)
        for e in self.data.elements:
            zm = model.zth(e.t_s)[:, e.i, e.j]
            out[e.i, e.j] = np.max(np.abs(zm - e.z_k_per_w)) / self.self_final[e.i]
        return out


def _start(data: CouplingData, layout: Layout, self_final: NDArray) -> tuple[NDArray, NDArray]:
    """Starting parameters and the tying matrix of the first stage (chains shared)."""
    lv, n = layout.levels, layout.n_cells
    ref = data.element(0, 0)
    assert ref is not None  # CouplingData checks every self curve
    logt = np.log(ref.t_s)
    mean = np.mean([np.interp(logt, np.log(e.t_s), e.z_k_per_w)
                    for e in (data.element(k, k) for k in range(n)) if e is not None], axis=0)
    try:
        cauer = fit_foster(ref.t_s, mean, order=lv).foster.to_cauer()
        r, c = np.array(cauer.r), np.array(cauer.c)
    except (FitError, DataFormatError):  # a start only: equal stages over the record
        tau = np.geomspace(ref.t_s[0] * 3, ref.t_s[-1] / 3, lv)
        r = np.full(lv, max(mean[-1], 1e-12) / lv)
        c = tau / r
    final = data.final()
    off = [final[i, j] for i in range(n) for j in range(n) if i != j and np.isfinite(final[i, j])]
    zself = float(np.mean(self_final))
    r_sub = min(max(min(off), 1e-3 * zself), 0.5 * zself) if off else 0.2 * zself
    # the chain's last resistance, less the substrate's, shared by the base's two paths
    share = 0.5 if layout.air else 1.0
    r_base = max(r[-1] - r_sub, 0.2 * r[-1]) / share
    tau_sub = data.span_s[1] / 10
    cols: list[list[int]] = []
    val: list[float] = []

    def tie(index: list[int], value: float) -> None:
        cols.append(index)
        val.append(value)

    for level in range(lv - 1):
        tie([i * lv + level for i in range(n)], -math.log(r[level]))
    for i in range(n):
        tie([i * lv + lv - 1], -math.log(r_base))
    k = n * lv
    for level, _, _ in layout.lateral:
        tie([k], math.log(START_COUPLING * (1.0 if level == lv - 1 else 0.1) / zself))
        k += 1
    if layout.air:
        tie(list(range(k, k + n)), -math.log(r_base))
        k += n
    tie([k], -math.log(r_sub))
    k += 1
    for level in range(lv):
        tie([k + i * lv + level for i in range(n)], math.log(c[level]))
    tie([k + n * lv], math.log(tau_sub / r_sub))
    ties = np.zeros((k + n * lv + 1, len(cols)))
    for q, index in enumerate(cols):
        ties[index, q] = 1.0
    return ties @ np.array(val), ties


def _fit_order(data: CouplingData, order: int, air: bool) -> tuple[ArrayModel, OrderTrial,
                                                                   NDArray]:
    from scipy.optimize import least_squares

    layout = Layout.of(data.ports, order, air)
    prob = _Problem(data, layout)
    p0, ties = _start(data, layout, prob.self_final)
    lo, hi = p0 - _RANGE, p0 + _RANGE

    def fun(p: NDArray) -> NDArray:
        return prob.residual(np.clip(p, lo, hi))

    def jac(p: NDArray) -> NDArray:
        return prob.residual(np.clip(p, lo, hi), jacobian=True)[1]

    q0 = np.linalg.lstsq(ties, p0, rcond=None)[0]
    shared = least_squares(lambda q: fun(ties @ q), q0, jac=lambda q: jac(ties @ q) @ ties,
                           method="lm", max_nfev=_EVALS[0])
    free = least_squares(fun, ties @ shared.x, jac=jac, method="lm", max_nfev=_EVALS[1])
    p = np.clip(free.x, lo, hi)
    n_g = len(layout.conductances)
    rss = float(np.sum(free.fun ** 2))
    bic = prob.n * math.log(max(rss, 1e-300) / prob.n) + p.size * math.log(prob.n)
    model = layout.model(np.exp(p[:n_g]), np.exp(p[n_g:]), data.reference)
    errors = prob.errors(model)
    trial = OrderTrial(order, bic, math.sqrt(rss / prob.n), float(np.nanmax(errors)), p.size)
    return model, trial, errors


def fit_array(data: CouplingData, order: int | str = "auto",
              max_order: int = DEFAULT_MAX_ORDER, *, air: bool = True,
              provenance: dict[str, Any] | None = None) -> ArrayFit:
    """Fit the array's N-port network to its measured self and mutual curves.

    Parameters
    ----------
    data : CouplingData
        The measured Z_ij(t) (every self curve, any mutual ones).
    order : int or "auto"
        Chain nodes per cell, or ``"auto"`` (chosen by BIC, see the module docstring).
    max_order : int
        Largest order tried by ``"auto"``.
    air : bool
        Give each cell's base a path to the reference besides the substrate.
    provenance : dict, optional
        Stored in the model's provenance (with the fit's report under ``fit``).

    Returns
    -------
    ArrayFit

    Examples
    --------
    >>> from spicethermal.array.model import ArrayModel
    >>> from spicethermal.core.ladder import Foster
    >>> from spicethermal.model import ThermalModel
    >>> truth = ArrayModel.from_thermal_model(ThermalModel(Foster.from_tau([2.0, 3.0],
    ...                                                                    [1e-2, 1.0])))
    >>> d = CouplingData.of_model(truth, np.geomspace(1e-3, 20, 40))
    >>> fit = fit_array(d)
    >>> fit.order, len(fit.model.nodes), fit.max_error < 1e-3   # the junction and the substrate
    (1, 2, True)
    """
    if order != "auto" and (isinstance(order, bool) or not isinstance(order, int)
                            or order < 1):
        raise DataFormatError(f"order {order!r}: a positive integer or 'auto'")
    if not isinstance(max_order, int) or max_order < 1:
        raise DataFormatError(f"max_order {max_order!r}: a positive integer")
    orders = [order] if isinstance(order, int) else list(range(1, max_order + 1))
    if isinstance(order, int):
        layout = Layout.of(data.ports, order, air)
        k = len(layout.conductances) + len(layout.capacitor_nodes)
        n = sum(e.z_k_per_w.size for e in data.elements)
        if k > n - 1:
            raise FitError(f"{data.source}: order {order} has {k} free parameters but only "
                           f"{n} readings; use a lower order or 'auto'")
    best = None
    trials: list[OrderTrial] = []
    worse = 0
    for lv in orders:
        try:
            model, trial, errors = _fit_order(data, lv, air)
        except (np.linalg.LinAlgError, DataFormatError, FloatingPointError) as exc:
            if len(orders) == 1:
                raise FitError(f"{data.source}: the order-{lv} network did not fit: it came out "
                               f"singular ({exc}), so these records do not determine {lv} "
                               f"levels per cell; use a lower order or 'auto' (the order by "
                               f"the BIC)") from None
            worse += 1  # an order that does not fit counts as one that does not improve
            if worse >= 2 and best is not None:
                break
            continue
        trials.append(trial)
        if best is None or trial.bic < best[1].bic:
            best, worse = (model, trial, errors), 0
        else:
            worse += 1
            if worse >= 2:
                break
    if best is None:
        raise FitError(f"{data.source}: no order of the array network could be fitted")
    model, trial, errors = best
    report = {"order": trial.order, "rms": trial.rms, "max_error": trial.max_error,
              "criterion": "BIC", "trials": [t.__dict__ for t in trials],
              "error_per_element": [[None if math.isnan(x) else x for x in row]
                                    for row in errors.tolist()],
              "valid_t_s": list(data.span_s)}
    model = ArrayModel(model.ports, model.nodes, model.resistors, model.capacitors,
                       model.reference, {**(provenance or {}), "fit": report})
    return ArrayFit(model, trial.order, errors, trial.rms, tuple(trials))
