"""The two-phase drive: a boost duty for a boost time, then the hold duty (grid search).

The simple alternative to the greedy profile, optimized for comparison: closed form on the
linear model (a candidate is the hold-duty step plus a step of ``boost - hold`` duty that ends
at the boost time), the junction as the averaged mean plus the ripple of the duty in force.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ..io.jsondoc import JsonDocument
from .trajectory import settle_rows, time_grid

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

    from .dynamics import Dynamics


@dataclass(frozen=True)
class TwoPhase(JsonDocument):
    """The best ``boost_duty`` for ``boost_s``, then the hold duty (grid search).

    Attributes
    ----------
    boost_s : float
        Length of the boost, s (whole PWM periods).
    boost_duty : float
        Duty during the boost.
    time_to_target_s : float
        Time until the node settles in the band, s.
    peak_junction_c : float
        Largest junction peak, °C.

    Examples
    --------
    >>> tp = TwoPhase(0.5, 0.8, 0.55, 69.9)
    >>> TwoPhase.from_json(tp.to_json()) == tp
    True
    >>> print(tp)
    two-phase drive: duty 0.8000 for 0.5 s, then hold: time to target 0.55 s
    """

    boost_s: float
    boost_duty: float
    time_to_target_s: float
    peak_junction_c: float

    def to_dict(self) -> dict[str, float]:
        """The ``"two_phase"`` object of the ``spicethermal drive --json`` document.

        Returns
        -------
        dict
            ``boost_s``, ``boost_duty``, ``time_to_target_s``, ``peak_junction_c``.
        """
        return {"boost_s": self.boost_s, "boost_duty": self.boost_duty,
                "time_to_target_s": self.time_to_target_s,
                "peak_junction_c": self.peak_junction_c}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> TwoPhase:
        """Rebuild the two-phase drive from its :meth:`to_dict` document.

        Parameters
        ----------
        data : dict
            ``boost_s``, ``boost_duty``, ``time_to_target_s`` and ``peak_junction_c``.

        Returns
        -------
        TwoPhase
            Equal to the one that wrote ``data``.
        """
        return cls(float(data["boost_s"]), float(data["boost_duty"]),
                   float(data["time_to_target_s"]), float(data["peak_junction_c"]))

    #: Deprecated spelling of :meth:`to_dict` (kept for existing callers).
    as_json = to_dict

    def __str__(self) -> str:
        return (f"two-phase drive: duty {self.boost_duty:.4f} for {self.boost_s:.4g} s, then "
                f"hold: time to target {self.time_to_target_s:.4g} s")


def search_two_phase(dyn: Dynamics, node: int, lim_k: float, tgt_k: float, tol: float,
                     hold_duty: float, horizon: float) -> TwoPhase | None:
    """Grid search over boost time (whole periods) and boost duty, then the hold duty.

    Parameters
    ----------
    dyn : Dynamics
        A linear network (its modes give every candidate in closed form).
    node : int
        The node to settle in the band.
    lim_k, tgt_k, tol : float
        Junction-peak limit, node target and half-width of its band, K.
    hold_duty : float
        The hold duty.
    horizon : float
        Longest time considered, s.

    Returns
    -------
    TwoPhase or None
        The fastest safe candidate (its peak as a rise, K, over the ambient); None if no
        candidate settles.
    """
    period = dyn.period
    band = 0.98 * tol  # a curve that grazes the band's edge between grid points is not robust
    lam, v, _ = dyn.modes(np.zeros(dyn.n))
    gain = v[0] / lam

    def resp(row: int, t: NDArray) -> NDArray:  # rise per watt after a step at t = 0
        tt = np.maximum(t, 0.0)[..., None]
        return (v[row] * gain * -np.expm1(-lam * tt)).sum(axis=-1)

    def evaluate(tbs: NDArray, dbs: NDArray) -> tuple[NDArray, NDArray, NDArray]:
        t = time_grid(period, horizon, tuple(tbs), 1200)
        sn, sj = resp(node, t), resp(0, t)
        best_t = np.full((tbs.size, dbs.size), math.inf)
        peak = np.full((tbs.size, dbs.size), math.inf)
        rip_b = dyn.ripple(dbs)
        rip_h = float(dyn.ripple(hold_duty))
        for i, tb in enumerate(tbs):
            dn = sn - resp(node, t - tb) * (t > tb)
            dj = sj - resp(0, t - tb) * (t > tb)
            extra = (dbs - hold_duty)[:, None] * dyn.p
            jm = hold_duty * dyn.p * sj + extra * dj
            jp = np.where(t <= tb, jm + rip_b[:, None], jm + rip_h)
            peak[i] = jp.max(axis=1)
            ok = peak[i] <= lim_k  # only the safe candidates need their settling time
            if ok.any():
                y = hold_duty * dyn.p * sn + extra[ok] * dn
                best_t[i, ok] = settle_rows(t, y, tgt_k, band)[0]
        return best_t, peak, t

    tbs = np.unique(np.maximum(1, np.round(np.geomspace(period, horizon / 4, 160) / period)))
    dbs = np.linspace(hold_duty, 1.0, 141)
    times, peaks, _ = evaluate(tbs * period, dbs)
    if not np.isfinite(times).any():
        return None
    i, q = np.unravel_index(np.argmin(times), times.shape)
    best = (float(times[i, q]), float(tbs[i]), float(dbs[q]), float(peaks[i, q]))
    # zoom in around the best candidate: +-2 grid steps in both, three times
    tb_lo, tb_hi = tbs[max(i - 2, 0)], tbs[min(i + 2, tbs.size - 1)]
    d_step = 2 * (dbs[1] - dbs[0])
    for _ in range(3):
        tb2 = np.unique(np.maximum(1, np.round(np.linspace(tb_lo, tb_hi, 25))))
        db2 = np.unique(np.clip(np.linspace(best[2] - d_step, best[2] + d_step, 25),
                                hold_duty, 1.0))
        times2, peaks2, _ = evaluate(tb2 * period, db2)
        i2, q2 = np.unravel_index(np.argmin(times2), times2.shape)
        if times2[i2, q2] <= best[0]:
            best = (float(times2[i2, q2]), float(tb2[i2]), float(db2[q2]),
                    float(peaks2[i2, q2]))
        span = max((tb_hi - tb_lo) / 6, 2.0)
        tb_lo, tb_hi = max(1.0, best[1] - span), best[1] + span
        d_step /= 4
    return TwoPhase(best[1] * period, best[2], best[0], best[3])
