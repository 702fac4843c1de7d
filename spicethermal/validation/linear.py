"""Linear devices of shapes other than a short Cauer ladder, and the linear-data suite.

A linear network is not an effect: whatever its shape, a diagnosis must leave it unnamed and
its baseline must reach the noise. Two classes hold linear devices that
:class:`~.network.Network` (a ladder) does not:

* :class:`LinearNetwork` — any RC network: node capacities and resistances between nodes or
  to the reference (parallel heat paths, trees);
* :class:`FosterNetwork` — a junction response given by its stages directly (a continuous
  spectrum of time constants sampled finely).

Both have what :func:`~.measure.measure` needs of a linear device (``is_linear``,
:meth:`foster`, :meth:`steady`). :func:`shape_network` builds a device class's linear network
of a named shape (:data:`SHAPES`), scaled to the class's thermal resistance and time constants:
a distributed RC line behind the die, a tapered line (heat spreading), a continuous spectrum,
a spectrum with two lobes, two parallel paths, a ladder of one or two stages, a ladder of ten
or more. :func:`linear_cases` is the suite (every shape on every device class, with and without
``tj_steady_c``, curves in °C and in volts, one to three curves, dense and sparse PWM grids);
:func:`linear_fast` a handful of them for unit tests.

>>> net = LinearNetwork((1e-3, 1e-2, 1e-2), ((0, 1, 2.0), (0, 2, 2.0), (1, -1, 3.0), (2, -1, 3.0)))
>>> round(float(net.foster()[0].sum()), 12)       # two 5 K/W paths in parallel
2.5
"""

from __future__ import annotations

import math
import random
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .cases import DEVICES, Case, bench_for
from .network import Network

__all__ = ["SHAPES", "FosterNetwork", "LinearNetwork", "linear_cases", "linear_fast",
           "shape_network"]

SHAPES = ("distributed-line", "tapered-line", "continuous-spectrum", "bimodal-spectrum",
          "parallel-paths", "short-ladder", "long-ladder")


def _foster(conductance: np.ndarray, c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Foster stages of node 0 of an RC network (``r`` ascending in ``τ``)."""
    s = 1.0 / np.sqrt(c)
    lam, vec = np.linalg.eigh(s[:, None] * conductance * s[None, :])
    return vec[0] ** 2 / (c[0] * lam), 1.0 / lam


class _Linear:
    """What every linear device answers like a linear :class:`~.network.Network`."""

    is_linear = True
    hysteretic: tuple = ()

    def cooling_branch(self, start: np.ndarray) -> _Linear:
        return self

    def pwm_network(self) -> _Linear:
        return self

    def time_scales(self) -> np.ndarray:
        return self.foster()[1]

    def foster(self) -> tuple[np.ndarray, np.ndarray]:
        raise NotImplementedError


@dataclass(frozen=True)
class LinearNetwork(_Linear):
    """An RC network: ``c_j_per_k`` per node (node 0 the junction) and ``links``
    ``(i, j, R)``, a resistance between nodes ``i`` and ``j`` or, with ``j = −1``, to the
    reference."""

    c_j_per_k: Sequence[float]
    links: Sequence[tuple[int, int, float]]

    @property
    def n(self) -> int:
        return len(self.c_j_per_k)

    def conductance(self) -> np.ndarray:
        """Nodal conductance matrix (W/K), the reference eliminated."""
        g = np.zeros((self.n, self.n))
        for i, j, r in self.links:
            g[i, i] += 1.0 / r
            if j >= 0:
                g[j, j] += 1.0 / r
                g[i, j] -= 1.0 / r
                g[j, i] -= 1.0 / r
        return g

    def foster(self) -> tuple[np.ndarray, np.ndarray]:
        """Exact Foster form of the junction's response."""
        return _foster(self.conductance(), np.asarray(self.c_j_per_k, dtype=float))

    def steady(self, power_w: float, tref_c: float) -> np.ndarray:
        """Node temperatures (°C) under ``power_w`` at the junction."""
        return tref_c + np.linalg.solve(self.conductance(), np.eye(self.n)[0] * power_w)


@dataclass(frozen=True)
class FosterNetwork(_Linear):
    """A junction response given by its Foster stages ``r`` (K/W) and ``tau`` (s)."""

    r: Sequence[float]
    tau: Sequence[float]

    @property
    def n(self) -> int:
        return 1

    def foster(self) -> tuple[np.ndarray, np.ndarray]:
        order = np.argsort(self.tau)
        return np.asarray(self.r, dtype=float)[order], np.asarray(self.tau, dtype=float)[order]

    def steady(self, power_w: float, tref_c: float) -> np.ndarray:
        return np.array([tref_c + power_w * float(np.sum(self.r))])


def _span(r: Sequence[float], c: Sequence[float]) -> tuple[float, float, float]:
    """(Rth, fastest τ, slowest τ) of a ladder."""
    rf, tau = Network(tuple(r), tuple(c)).foster()
    return float(rf.sum()), float(tau.min()), float(tau.max())


def shape_network(r_k_per_w: Sequence[float], c_j_per_k: Sequence[float], shape: str,
                  rng: random.Random | None = None):
    """A linear network of ``shape`` with the thermal resistance and the span of time
    constants of the ladder ``r_k_per_w``, ``c_j_per_k`` (a device class's).

    Parameters
    ----------
    r_k_per_w, c_j_per_k : the device class's ladder (its scale).
    shape : one of :data:`SHAPES`.
    rng : draws the shape's free proportions; None takes their middle values.

    Returns
    -------
    Network, LinearNetwork or FosterNetwork
        A linear device of that shape, thermal resistance within a factor 1.5 of the
        ladder's.

    Examples
    --------
    >>> net = shape_network((4.0, 12.0, 40.0, 90.0), (2e-5, 4e-4, 8e-3, 0.3), "distributed-line")
    >>> net.n, round(float(net.foster()[0].sum()), 9)
    (41, 146.0)
    """
    rth, lo, hi = _span(r_k_per_w, c_j_per_k)

    def u(a: float, b: float) -> float:
        return 0.5 * (a + b) if rng is None else rng.uniform(a, b)

    def logu(a: float, b: float) -> float:
        return math.exp(u(math.log(a), math.log(b)))

    if shape == "distributed-line":
        # a die (one lumped node) on a uniform RC line of 40 segments to the reference
        share, segments = u(0.05, 0.2), 40
        r_die, r_line = share * rth, (1.0 - share) * rth
        c_line = math.pi ** 2 * hi / (4.0 * r_line)
        c_die = logu(1.0, 3.0) * lo / r_die
        return Network((r_die,) + (r_line / segments,) * segments,
                       (c_die,) + (c_line / segments,) * segments)
    if shape == "tapered-line":
        # heat spreading: each segment's resistance falls and its capacity grows outwards
        segments, q = 30, u(0.8, 0.9)
        w = np.array([q ** i for i in range(segments)])
        r = rth * w / w.sum()
        tau = np.geomspace(lo, hi / 5.0, segments)
        return Network(tuple(r), tuple(tau / r))
    if shape in ("continuous-spectrum", "bimodal-spectrum"):
        tau = np.geomspace(lo / 3.0, hi * 2.0, 80)
        x = np.log(tau)
        if shape == "continuous-spectrum":
            dens = np.exp(-0.5 * ((x - u(0.35, 0.65) * (x[-1] - x[0]) - x[0]) / u(1.5, 3.0)) ** 2)
            dens += u(0.05, 0.3)  # a floor: every decade holds some resistance
        else:
            mid = [x[0] + f * (x[-1] - x[0]) for f in (u(0.15, 0.35), u(0.65, 0.9))]
            dens = sum(a * np.exp(-0.5 * ((x - m) / u(0.5, 1.0)) ** 2)
                       for a, m in zip((u(0.2, 0.6), 1.0), mid, strict=True))
        return FosterNetwork(tuple(rth * dens / dens.sum()), tuple(tau))
    if shape == "parallel-paths":
        # the junction drains through the package (the main path) and through its leads and
        # board (slower); the two in parallel give the ladder's Rth
        ratio = logu(1.0, 4.0)
        paths = (((0.2, lo * 10.0), (0.3, math.sqrt(lo * hi)), (0.3, hi / 3.0), (0.2, 0.0)),
                 ((0.3, hi / 30.0), (0.4, hi * u(0.5, 2.0)), (0.3, 0.0)))
        totals = (rth * (1.0 + 1.0 / ratio), rth * (1.0 + ratio))
        caps, links = [lo / (0.1 * totals[0])], []
        for path, total in zip(paths, totals, strict=True):
            prev = 0
            for share, tau in path[:-1]:  # a node per stage, the last share to the reference
                caps.append(tau / (share * total))
                links.append((prev, len(caps) - 1, share * total))
                prev = len(caps) - 1
            links.append((prev, -1, path[-1][0] * total))
        return LinearNetwork(tuple(caps), tuple(links))
    if shape == "short-ladder":
        stages = 1 if rng is None or rng.random() < 0.5 else 2
        if stages == 1:
            return Network((rth,), (hi / rth,))
        share = u(0.2, 0.4)
        return Network((share * rth, (1 - share) * rth),
                       (lo * 30.0 / (share * rth), hi / ((1 - share) * rth)))
    if shape == "long-ladder":
        stages = 12 if rng is None else rng.randint(10, 14)
        w = np.array([logu(0.3, 3.0) for _ in range(stages)])
        r = rth * w / w.sum()
        tau = np.geomspace(lo, hi / 3.0, stages)
        return Network(tuple(r), tuple(tau / r))
    raise ValueError(f"linear shape {shape!r}: expected one of {SHAPES}")


def linear_cases() -> list[Case]:
    """The linear-data suite: every shape of :data:`SHAPES` on every device class, each with
    and without ``tj_steady_c``; the other bench variants (°C or volts, one to three cooling
    curves, dense or sparse PWM grid, noise, sampling) rotate over the cases. Nothing is
    simulated until :meth:`~.cases.Case.record`.

    Returns
    -------
    list of Case
        Family ``"linear"``, acceptable verdict ``none``; named ``linear/<device>/<shape>/
        steady`` or ``.../no-steady``.

    Examples
    --------
    >>> cases = linear_cases()
    >>> len(cases), {c.acceptable for c in cases}
    (70, {('none',)})
    """
    out = []
    i = 0
    for dev in DEVICES.values():
        for shape in SHAPES:
            net = shape_network(dev.r_k_per_w, dev.c_j_per_k, shape)
            for steady in (True, False):
                variant = {"noise_k": dev.noise_levels[i % 2], "per_decade": (10, 5, 20)[i % 3],
                           "dense_pwm": i % 4 != 1, "steady": steady, "volts": i % 5 in (1, 3),
                           "n_curves": (2, 3, 1, 2, 3, 1, 2)[i % 7]}
                name = f"linear/{dev.name}/{shape}/{'steady' if steady else 'no-steady'}"
                out.append(Case(name, "linear", (), dev.name, net, bench_for(dev, variant),
                                6000 + i, shape, "", {"shape": shape, "variant": variant},
                                kind="linear"))
                i += 1
    return out


#: A fast subset of :func:`linear_cases` (each simulates in about a second or less): every
#: scale, shapes of every kind, with and without steady readings, °C and volts.
FAST_SHAPES = (("actuator", "distributed-line", True), ("mosfet", "parallel-paths", False),
               ("diode", "continuous-spectrum", False), ("mems", "long-ladder", True),
               ("igbt", "bimodal-spectrum", False), ("igbt", "tapered-line", True))


def linear_fast() -> list[Case]:
    """A handful of :func:`linear_cases` for unit tests (:data:`FAST_SHAPES`).

    >>> [c.bench.steady for c in linear_fast()]
    [True, False, False, True, False, True]
    """
    by_name = {c.name: c for c in linear_cases()}
    return [by_name[f"linear/{d}/{s}/{'steady' if st else 'no-steady'}"]
            for d, s, st in FAST_SHAPES]
