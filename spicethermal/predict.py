"""Junction temperature under a measured power profile: the designer's everyday question.

A :class:`PowerProfile` is a power waveform sampled at times ``t_s`` from 0: linear between
samples (as a SPICE ``PWL`` source), held at its last value after the last sample; a step is
two samples close together. :func:`predict` gives Tj(t) of a model under it, starting from
the reference temperature:

* ``analytic`` (linear models): the exact response of the ladder to a piecewise-linear input,
  mode by mode (the ladder's generalized eigenvalues ``G v = λ C v``), no time step at all;
* ``ngspice`` or ``pyspice`` (any model; ngspice is the default with device effects): the
  exported subcircuit driven by the same ``PWL`` source in a transient run
  (:meth:`spicethermal.engines.interface.Spice.transient`).

>>> from spicethermal.core.ladder import Foster
>>> from spicethermal.model import ThermalModel
>>> m = ThermalModel(Foster.from_tau([2.0], [1.0]))
>>> p = PowerProfile([0.0, 1.0], [0.0, 1.0])          # a 1 W/s ramp
>>> tj = predict(m, p, [1.0], tref_c=25.0).tj_c         # 25 + 2 (t - τ (1 - e^(-t/τ))) at t = τ
>>> bool(abs(tj[0] - (25 + 2 * np.exp(-1.0))) < 1e-12)
True
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from .core.errors import DataFormatError
from .core.progress import task
from .engines.interface import NAMES
from .engines.interface import engine as by_name
from .io.bundle import read_columns
from .io.files import atomic_open
from .model import Network

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import ArrayLike, NDArray

    from .model import ThermalModel

#: Engines of :func:`predict` (``auto``: analytic for linear models, ngspice otherwise).
ENGINES = NAMES
#: Output points spread evenly over the profile, besides its own sample times.
DEFAULT_POINTS = 1000


@dataclass(frozen=True, eq=False)
class PowerProfile:
    """Power ``power_w`` (W, >= 0) at times ``t_s`` (s, from 0, increasing); linear between
    samples, held after the last. Raises :class:`DataFormatError` naming the bad row.

    Attributes
    ----------
    t_s : ndarray
        Sample times (s), from 0, increasing.
    power_w : ndarray
        Power (W, >= 0) at ``t_s``.
    label : str
        Where the profile came from (error messages name it).
    rows : ndarray or None
        The file row of each sample, when read from a file.
    """

    t_s: NDArray
    power_w: NDArray
    label: str = "power profile"
    rows: NDArray | None = None

    def __post_init__(self) -> None:
        t = np.array(self.t_s, dtype=float).ravel()
        p = np.array(self.power_w, dtype=float).ravel()
        rows = np.arange(1, t.size + 1) if self.rows is None else np.asarray(self.rows)
        if t.size != p.size or t.size == 0:
            raise DataFormatError(f"{self.label}: t_s and power_w must be non-empty and equally "
                                  f"long")
        for name, arr in (("t_s", t), ("power_w", p)):
            bad = np.flatnonzero(~np.isfinite(arr))
            if bad.size:
                raise DataFormatError(f"{self.label}, row {int(rows[bad[0]])}, column {name}: "
                                      f"not a finite number")
        if t[0] != 0:
            raise DataFormatError(f"{self.label}, row {int(rows[0])}, column t_s: the profile "
                                  f"must start at t = 0 (the model starts at the reference)")
        back = np.flatnonzero(np.diff(t) <= 0)
        if back.size:
            raise DataFormatError(f"{self.label}, row {int(rows[back[0] + 1])}, column t_s: "
                                  f"times must increase")
        neg = np.flatnonzero(p < 0)
        if neg.size:
            raise DataFormatError(f"{self.label}, row {int(rows[neg[0]])}, column power_w: "
                                  f"power must not be negative")
        object.__setattr__(self, "t_s", t)
        object.__setattr__(self, "power_w", p)

    @classmethod
    def read(cls, path: str | os.PathLike) -> PowerProfile:
        """A CSV with columns ``t_s`` and ``power_w`` (``#`` comments allowed).

        Parameters
        ----------
        path : the CSV file.

        Returns
        -------
        PowerProfile
        """
        cols = read_columns(path, ["t_s", "power_w"])
        return cls(cols["t_s"], cols["power_w"], str(path), cols.rows)

    def at(self, t_s: ArrayLike) -> NDArray:
        """Power (W) at ``t_s`` (linear between samples, held after the last)."""
        return np.interp(np.asarray(t_s, dtype=float), self.t_s, self.power_w)


@dataclass(frozen=True, eq=False)
class Prediction:
    """Tj (degC) at times ``t_s`` under a profile, and how it was computed."""

    t_s: NDArray
    power_w: NDArray
    tj_c: NDArray
    tref_c: float
    engine: str

    @property
    def peak(self) -> tuple[float, float]:
        """(time, Tj) of the hottest point."""
        k = int(np.argmax(self.tj_c))
        return float(self.t_s[k]), float(self.tj_c[k])

    def columns(self) -> dict[str, NDArray]:
        """The CSV columns: ``t_s``, ``power_w``, ``tj_c``."""
        return {"t_s": self.t_s, "power_w": self.power_w, "tj_c": self.tj_c}

    def __str__(self) -> str:
        t, tj = self.peak
        return (f"Tj from {self.tref_c:g} degC under {self.t_s.size} points to "
                f"{self.t_s[-1]:.4g} s ({self.engine}): peak {tj:.4g} degC at {t:.4g} s, "
                f"final {self.tj_c[-1]:.4g} degC")


def output_times(profile: PowerProfile, t_end_s: float | None = None,
                 points: int = DEFAULT_POINTS) -> NDArray:
    """The profile's own times up to ``t_end_s`` (default its last) and ``points`` even ones.

    Parameters
    ----------
    profile : the power profile.
    t_end_s : the last output time, s (after the profile's end its power is held).
    points : even points from 0 to ``t_end_s``.

    Returns
    -------
    ndarray
        Sorted, without duplicates.

    >>> output_times(PowerProfile([0.0, 2.0], [1.0, 1.0]), points=3).tolist()
    [0.0, 1.0, 2.0]
    """
    end = float(profile.t_s[-1]) if t_end_s is None else float(t_end_s)
    if not end > 0:
        raise DataFormatError(f"the prediction must end after t = 0 (got {end!r} s)")
    grid = np.linspace(0.0, end, max(int(points), 2))
    return np.union1d(profile.t_s[profile.t_s <= end], grid)


def predict(model: ThermalModel, profile: PowerProfile, t_s: ArrayLike | None = None, *,
            tref_c: float = 25.0, engine: str = "auto", quiet: bool = True) -> Prediction:
    """Junction temperature of ``model`` under ``profile`` at times ``t_s``.

    Parameters
    ----------
    model : the thermal model (linear, or with device effects for ngspice).
    profile : the power waveform.
    t_s : output times (default :func:`output_times`).
    tref_c : reference temperature, degC (the model starts there).
    engine : ``"auto"``, ``"analytic"``, ``"ngspice"`` or ``"pyspice"`` (module docstring).
    quiet : no progress on stderr while ngspice runs (:func:`spicethermal.core.progress.task`).

    Returns
    -------
    Prediction
    """
    t = output_times(profile) if t_s is None else np.asarray(t_s, dtype=float).ravel()
    if t.size == 0 or not np.all(np.isfinite(t)) or np.any(t < 0) or np.any(np.diff(t) < 0):
        raise DataFormatError("output times must be finite, >= 0 and ascending")
    if engine not in ENGINES:
        raise DataFormatError(f"--engine {engine!r}: expected one of {', '.join(ENGINES)}")
    chosen = by_name(engine, model)  # analytic refuses device effects in one line
    engine = chosen.name
    if engine == "analytic":
        rise = pwl_response(model, profile, t)
    else:

        with task(f"{engine} transient", quiet=quiet):
            rise = chosen.transient(model, list(zip(profile.t_s.tolist(),
                                                    profile.power_w.tolist(), strict=True)),
                                    t, tref_c)
    return Prediction(t, profile.at(t), tref_c + rise, float(tref_c), engine)


def pwl_response(model: ThermalModel, profile: PowerProfile, t_s: NDArray) -> NDArray:
    """Exact junction rise (K) of the model's linear ladder under the piecewise-linear
    ``profile`` at ``t_s``, from rest: each mode ``z' = -λ z + b p(t)`` integrated in closed
    form over every segment where ``p`` is linear.

    Parameters
    ----------
    model : the model (its ladder; device effects are ignored here).
    profile : the power profile.
    t_s : output times, ascending.

    Returns
    -------
    ndarray
        The rise over the reference at ``t_s``, K.

    Examples
    --------
    >>> from spicethermal.core.ladder import Foster
    >>> from spicethermal.model import ThermalModel
    >>> m = ThermalModel(Foster.from_tau([3.0], [0.5]))
    >>> step = PowerProfile([0.0, 1e-12], [0.0, 2.0])
    >>> rise = pwl_response(m, step, np.array([0.5]))[0]
    >>> bool(abs(rise - 6 * (1 - np.exp(-1))) < 1e-9)
    True
    """
    from scipy.linalg import eigh


    net = Network.of(model.ladder)
    lam, v = eigh(net.conductance(), net.capacitance())
    b = v[0, :]
    # segments: the profile's own, and a last one (held power) to beyond the last output time
    edges = np.append(profile.t_s, max(float(t_s[-1]), float(profile.t_s[-1])) + 1.0)
    powers = np.append(profile.power_w, profile.power_w[-1])
    z = np.zeros(lam.size)
    start = np.empty((edges.size - 1, lam.size))
    for k in range(edges.size - 1):
        start[k] = z
        z = _advance(z, lam, b, powers[k], _slope(edges, powers, k), edges[k + 1] - edges[k])
    k = np.clip(np.searchsorted(edges, t_s, side="right") - 1, 0, edges.size - 2)
    dt = t_s - edges[k]
    slopes = np.array([_slope(edges, powers, i) for i in range(edges.size - 1)])
    zt = _advance(start[k], lam[None, :], b[None, :], powers[k][:, None], slopes[k][:, None],
                  dt[:, None])
    return zt @ b


def _slope(edges: NDArray, powers: NDArray, k: int) -> float:
    if k >= edges.size - 2:
        return 0.0  # held after the last sample
    return float((powers[k + 1] - powers[k]) / (edges[k + 1] - edges[k]))


def _advance(z: NDArray, lam: NDArray, b: NDArray, p0: NDArray | float, slope: NDArray | float,
             dt: NDArray | float) -> NDArray:
    """Mode states after ``dt`` under ``p0 + slope · τ``: exact, stable for tiny λ·dt."""
    x = lam * dt
    decay = np.exp(-x)
    one = -np.expm1(-x) / lam  # ∫ e^(-λ(dt-τ)) dτ
    # ∫ τ e^(-λ(dt-τ)) dτ = (x - 1 + e^-x) / λ², by its series where x is small
    small = np.abs(x) < 1e-3
    xs = np.where(small, x, 0.0)
    series = dt * dt * (0.5 - xs / 6.0 + xs * xs / 24.0)
    ramp = np.where(small, series, (x - one * lam) / np.where(small, 1.0, lam) ** 2)
    return z * decay + b * (p0 * one + slope * ramp)


def plot_prediction(result: Prediction, path: str | os.PathLike, title: str | None = None,
                    ax=None):
    """Tj (left axis) and power (right axis) against time, written to ``path`` (PNG).

    Parameters
    ----------
    result : the prediction.
    path : the PNG file (written atomically; with ``ax`` nothing is written).
    title : a title (default: engine and reference).
    ax : draw into these axes instead of a new figure.

    Returns
    -------
    Path
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig = None
    if ax is None:
        fig, ax = plt.subplots(figsize=(7, 4), layout="constrained")
    ax.plot(result.t_s, result.tj_c, color="C3", label="Tj")
    ax.set_xlabel("t (s)")
    ax.set_ylabel("Tj (°C)", color="C3")
    t_peak, tj_peak = result.peak
    ax.plot([t_peak], [tj_peak], "o", color="C3")
    ax.annotate(f"peak {tj_peak:.4g} °C", (t_peak, tj_peak), textcoords="offset points",
                xytext=(6, 6))
    power = ax.twinx()
    power.plot(result.t_s, result.power_w, color="C0", lw=0.8, label="power")
    power.set_ylabel("power (W)", color="C0")
    ax.set_title(title or f"junction temperature ({result.engine}, Tref {result.tref_c:g} °C)")
    if fig is not None:

        with atomic_open(path, "wb") as handle:
            fig.savefig(handle, format="png", dpi=120)
        plt.close(fig)
    return Path(path)
