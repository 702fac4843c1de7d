"""The nodal form of a ladder, power schedules, and the exact response of a linear network.

:class:`Network` stamps a Foster or Cauer ladder into conductance and capacitance matrices
(node 0 is the junction, the reference is implicit); :class:`Schedule` is a piecewise-constant
power; :func:`linear_response` is the exact response of the linear network to a schedule, and
:class:`Trajectory` the node rises it returns. :class:`~spicethermal.model.ThermalModel` builds
its nonlinear simulation on these.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..engines.pwm import check_drive
from .errors import DataFormatError
from .ladder import Cauer, Foster

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import ArrayLike, NDArray

__all__ = ["Network", "Schedule", "Trajectory", "linear_response"]


@dataclass(frozen=True)
class Network:
    """Nodal form of a ladder: node 0 is the junction, the reference is node ``n`` (implicit).

    ``branches_r`` and ``branches_c`` are ``(a, b, value)`` with ``b == n`` meaning the
    reference. Foster stages sit between consecutive nodes; Cauer capacitors go to the reference.
    """

    n: int
    branches_r: tuple[tuple[int, int, float], ...]
    branches_c: tuple[tuple[int, int, float], ...]

    @classmethod
    def of(cls, ladder: Foster | Cauer) -> Network:
        n = ladder.order
        if isinstance(ladder, Foster):
            rs = tuple((i, i + 1, r) for i, r in enumerate(ladder.r))
            cs = tuple((i, i + 1, c) for i, c in enumerate(ladder.c))
        else:
            ladder = ladder.with_capacitances()
            n = ladder.order
            rs = tuple((i, i + 1, r) for i, r in enumerate(ladder.r))
            cs = tuple((i, n, c) for i, c in enumerate(ladder.c))
        return cls(n, rs, cs)

    @staticmethod
    def _stamp(n: int, branches: Iterable[tuple[int, int, float]], scale: float = 1.0) -> NDArray:
        m = np.zeros((n, n))
        for a, b, v in branches:
            v = v * scale
            m[a, a] += v
            if b < n:
                m[b, b] += v
                m[a, b] -= v
                m[b, a] -= v
        return m

    def conductance(self, scale_r: float | ArrayLike = 1.0) -> NDArray:
        """G with every resistance multiplied by ``scale_r`` (one factor, or one per branch)."""
        scales = np.broadcast_to(np.asarray(scale_r, dtype=float), (len(self.branches_r),))
        return self._stamp(self.n, ((a, b, 1.0 / (r * s)) for (a, b, r), s
                                    in zip(self.branches_r, scales, strict=True)))

    def capacitance(self) -> NDArray:
        return self._stamp(self.n, self.branches_c)

    def node_capacitance(self) -> NDArray:
        """Heat capacity (J/K) of every node to the reference (a Cauer ladder's layer
        capacities; in a Foster network only its last stage's)."""
        out = np.zeros(self.n)
        for a, b, c in self.branches_c:
            if b == self.n:
                out[a] += c
        return out


@dataclass(frozen=True)
class Trajectory:
    """Node rises (K over the reference) at times ``t_s``; ``tj_k`` is the junction's."""

    t_s: NDArray
    theta_k: NDArray  # shape (len(t_s), n)

    @property
    def tj_k(self) -> NDArray:
        return self.theta_k[:, 0]


@dataclass(frozen=True)
class Schedule:
    """Piecewise-constant power: ``power_w[k]`` from ``t_s[k]`` until ``t_s[k+1]`` (last: forever).

    >>> Schedule.step(0.1).power_at(5.0)
    0.1
    """

    t_s: tuple[float, ...]
    power_w: tuple[float, ...]

    def __post_init__(self) -> None:
        t = np.asarray(self.t_s, dtype=float)
        p = np.asarray(self.power_w, dtype=float)
        if t.size == 0 or t.size != p.size:
            raise DataFormatError("schedule: t_s and power_w must be non-empty and equally long")
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(p))):
            raise DataFormatError("schedule: times and powers must be finite")
        if np.any(np.diff(t) <= 0) or t[0] < 0:
            raise DataFormatError("schedule: times must start at or after 0 and increase")
        if np.any(p < 0):
            raise DataFormatError("schedule: power must not be negative")

    @classmethod
    def step(cls, power_w: float, t_on_s: float = 0.0) -> Schedule:
        return cls((0.0, t_on_s), (0.0, power_w)) if t_on_s > 0 else cls((0.0,), (power_w,))

    @classmethod
    def pwm(cls, power_w: float, freq_hz: float, duty: float, periods: int,
            t0_s: float = 0.0) -> Schedule:
        """``periods`` periods of a rectangular train starting with an on-phase at ``t0_s``."""
        check_drive(freq_hz, duty, power_w)
        period = 1 / freq_hz
        ts, ps = [], []
        for k in range(periods):
            ts += [t0_s + k * period, t0_s + (k + duty) * period]
            ps += [power_w, 0.0]
        if t0_s > 0:
            ts, ps = [0.0, *ts], [0.0, *ps]
        return cls(tuple(ts), tuple(ps))

    def power_at(self, t: float) -> float:
        k = int(np.searchsorted(self.t_s, t, side="right")) - 1
        return float(self.power_w[max(k, 0)]) if k >= 0 else 0.0

    def segments(self, t_end: float) -> list[tuple[float, float, float]]:
        """(start, end, power) pieces covering [0, t_end]."""
        edges = [t for t in self.t_s if t < t_end] + [t_end]
        out = []
        if self.t_s[0] > 0:
            out.append((0.0, min(self.t_s[0], t_end), 0.0))
        for k in range(len(edges) - 1):
            out.append((edges[k], edges[k + 1], float(self.power_w[k])))
        return [s for s in out if s[1] > s[0]]



def linear_response(net: Network, x0: NDArray, schedule: Schedule, t: NDArray) -> NDArray:
    """Exact response of the linear network by modal decomposition, segment by segment."""
    from scipy.linalg import eigh

    lam, v = eigh(net.conductance(), net.capacitance())  # G v = λ Cm v, vᵀ Cm v = I
    bm = v[0, :]  # modal input vᵀ e0
    segs = schedule.segments(float(t[-1]) + 1.0)
    starts = np.array([s[0] for s in segs])
    z = np.linalg.solve(v, x0)
    z_at = []
    for t0, t1, p in segs:  # modal state at the start of every segment
        z_at.append(z)
        z = z * np.exp(-lam * (t1 - t0)) + p * bm / lam * -np.expm1(-lam * (t1 - t0))
    k = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(segs) - 1)
    dt = (t - starts[k])[:, None]
    p = np.array([segs[i][2] for i in k])[:, None]
    zt = np.array(z_at)[k] * np.exp(-lam * dt) + p * bm / lam * -np.expm1(-lam * dt)
    return zt @ v.T
