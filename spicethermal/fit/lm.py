"""Levenberg–Marquardt for many small least-squares problems at once.

The problems of one call share their residual function and the layout of their parameters
(the same model, from different starts or with different discrete choices); each moves on its
own. Every round evaluates, in one batched call of the residual function, every problem's
trial step together with its finite-difference Jacobian there (ready when the step is
accepted, as most are), so the forward model's fixed cost per call is paid once a round for
all of them.

The work is counted, never timed: a fit stops after :data:`MAX_ROUNDS` rounds (or the caller's
``rounds``) whatever the machine, so the same input gives the same result on every machine
and under any load.

>>> import numpy as np
>>> t = np.linspace(0, 1, 20)
>>> y = 3.0 * np.exp(-2.0 * t)
>>> def fun(x, _rows):
...     return x[:, :1] * np.exp(-x[:, 1:2] * t) - y
>>> res = levenberg_marquardt(fun, np.array([[1.0, 1.0], [5.0, 0.5]]), [0, 0], [10, 10])
>>> np.round(res.x, 6).tolist()
[[3.0, 2.0], [3.0, 2.0]]
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import ArrayLike, NDArray

__all__ = ["FTOL", "MAX_ROUNDS", "LMResult", "levenberg_marquardt"]

#: Rounds (one Jacobian and one trial step each) a fit may take at most.
MAX_ROUNDS = 40
#: A problem has converged when an accepted step lowers its cost by less than this fraction.
FTOL = 1e-4
#: Relative finite-difference step (of each parameter's size or typical size).
FD_STEP = 1e-6


@dataclass(frozen=True, eq=False)
class LMResult:
    """The problems' end points ``x`` ``(P, k)``, their residuals ``fun`` ``(P, N)`` and costs
    ``½|r|²`` ``(P,)``, whether each converged, and the work spent (rows evaluated)."""

    x: NDArray
    fun: NDArray
    cost: NDArray
    converged: NDArray
    rows: int
    rounds: int


def _cost(r: NDArray) -> NDArray:
    with np.errstate(over="ignore", invalid="ignore"):
        c = 0.5 * np.sum(r * r, axis=1)
    return np.where(np.isfinite(c), c, np.inf)


def levenberg_marquardt(fun: Callable[[NDArray, NDArray], NDArray], x0: ArrayLike,
                        lo: Sequence[float], hi: Sequence[float],
                        typical: Sequence[float] | None = None,
                        rounds: int = MAX_ROUNDS,
                        go_on: Callable[[], bool] | None = None) -> LMResult:
    """Minimise ``½|fun(x)|²`` from every start of ``x0`` ``(P, k)`` within ``[lo, hi]``.

    Parameters
    ----------
    fun : callable
        ``fun(X, rows)`` gives the residuals ``(M, N)`` at the ``M`` parameter sets ``X``
        ``(M, k)``; ``rows`` ``(M,)`` says which problem each set belongs to. A set where the
        model fails gives non-finite residuals.
    x0 : array_like
        Starts, ``(P, k)``.
    lo, hi : sequence of float
        Bounds: a parameter at a bound that the descent pushes beyond it is held there for
        the step, the others' step is projected on the bounds, or cut short at them when the
        projection would not lower the linear model's cost.
    typical : sequence of float, optional
        Typical size of each parameter (finite-difference steps); default 1.
    rounds : int
        Rounds at most.
    go_on : callable, optional
        Asked before each round after the first: the fit stops where it is (its problems
        not converged) when it says no (a budget of work spent).

    Returns
    -------
    LMResult
    """
    x = np.array(x0, dtype=float, ndmin=2)
    p_count, k = x.shape
    lo_a, hi_a = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    typ = np.ones(k) if typical is None else np.abs(np.asarray(typical, dtype=float))
    x = np.clip(x, lo_a, hi_a)
    offsets = np.vstack([np.zeros((1, k)), np.eye(k)])  # (k + 1, k)

    def stencil(points: NDArray, which: NDArray) -> tuple[NDArray, NDArray]:
        """Residuals at ``points`` and their finite-difference Jacobians, each point with its
        own perturbations in one batch: a forward model whose adaptive steps are shared
        across a batch then differences on one grid."""
        h = FD_STEP * np.maximum(np.abs(points), typ)
        h = np.where(points + h > hi_a, -h, h)  # step away from a bound it would cross
        xs = (np.repeat(points, k + 1, axis=0)
              + np.tile(offsets, (len(points), 1)) * np.repeat(h, k + 1, axis=0))
        rs = fun(xs, np.repeat(which, k + 1)).reshape(len(points), k + 1, -1)
        j = np.swapaxes((rs[:, 1:] - rs[:, :1]) / h[:, :, None], 1, 2)  # (q, N, k)
        return rs[:, 0], np.where(np.isfinite(j), j, 0.0)

    r, jac = stencil(x, np.arange(p_count))
    cost = _cost(r)
    work = p_count * (k + 1)
    lam = np.full(p_count, 1e-2)
    nu = np.full(p_count, 2.0)
    active = np.isfinite(cost)
    converged = np.zeros(p_count, dtype=bool)
    done_rounds = 0
    for done_rounds in range(1, rounds + 1):  # noqa: B007 - the count is returned
        idx = np.nonzero(active)[0]
        if not idx.size or (done_rounds > 1 and go_on is not None and not go_on()):
            break
        trials = np.empty((idx.size, k))
        predicted = np.empty(idx.size)
        for q, i in enumerate(idx):
            j = jac[i]
            # a parameter at a bound that the cost's descent (−Jᵀr) pushes beyond it is held
            # there: the step of the others is the damped step of their own columns (the
            # whole step, projected on the bounds, leaves the linear model's descent, and
            # a trial that cannot lower the cost is rejected round after round)
            grad = j.T @ r[i]
            free = ~(((x[i] <= lo_a) & (grad > 0)) | ((x[i] >= hi_a) & (grad < 0)))
            if not free.any():  # a minimum on the bounds
                converged[i], active[i] = True, False
                trials[q], predicted[q] = x[i], 0.0
                continue
            jf = j[:, free]
            # the damped step on columns scaled to unit norm, solved by least squares on the
            # augmented system (never the normal equations, whose condition is squared)
            norms = np.linalg.norm(jf, axis=0)
            norms = np.where(norms > 0, norms, 1.0)
            aug = np.vstack([jf / norms, np.sqrt(lam[i]) * np.eye(jf.shape[1])])
            rhs = np.concatenate([-r[i], np.zeros(jf.shape[1])])
            step = np.zeros(k)
            step[free] = np.linalg.lstsq(aug, rhs, rcond=None)[0] / norms
            trials[q] = np.clip(x[i] + step, lo_a, hi_a)
            lin = j @ (trials[q] - x[i])
            predicted[q] = -(r[i] @ lin + 0.5 * lin @ lin)
            if predicted[q] <= 0:  # projected off the descent: the step cut short at the bounds
                room = np.where(step > 0, hi_a - x[i], np.where(step < 0, lo_a - x[i], np.inf))
                frac = float(np.min(np.where(step != 0, room / np.where(step != 0, step, 1.0),
                                             np.inf)))
                trials[q] = np.clip(x[i] + min(frac, 1.0) * step, lo_a, hi_a)
                lin = j @ (trials[q] - x[i])
                predicted[q] = -(r[i] @ lin + 0.5 * lin @ lin)
        keep = active[idx]  # those with a step to try
        if not keep.all():
            idx, trials, predicted = idx[keep], trials[keep], predicted[keep]
            if not idx.size:
                break
        # the trial points and, ready for those accepted, their Jacobians: one batch
        rt, jt = stencil(trials, idx)
        work += idx.size * (k + 1)
        ct = _cost(rt)
        for q, i in enumerate(idx):
            gain = cost[i] - ct[q]
            if gain > 0:
                rho = gain / predicted[q] if predicted[q] > 0 else 0.0
                small = gain < FTOL * cost[i] or np.all(np.abs(trials[q] - x[i])
                                                        <= 1e-10 * (np.abs(x[i]) + typ))
                x[i], r[i], cost[i], jac[i] = trials[q], rt[q], ct[q], jt[q]
                lam[i] *= max(1 / 3, 1 - (2 * rho - 1) ** 3)
                nu[i] = 2.0
                if small:
                    converged[i], active[i] = True, False
            else:
                lam[i] *= nu[i]
                nu[i] *= 2.0
                if lam[i] > 1e12:  # no step lowers the cost: a minimum at this precision
                    converged[i], active[i] = True, False
    return LMResult(x, r, cost, converged, work, done_rounds)
