"""Uncertainty by residual bootstrap (as PyRth's ``from_data`` mode): bands for the fitted
Zth(t), the time-constant spectrum and the structure functions, and the spread of the
ladder's parameters.

Method: a smooth model of the curve (the fitted ladder, or the spectrum's own ladder) leaves
residuals ``data − model``; each resample adds those residuals, drawn with replacement, to the
model and is analysed again exactly as the data were (same order, weighting, Rth; same
deconvolution). The band is the central ``LEVEL`` (95 %) interval of the resamples at every
abscissa; parameter uncertainties are the resamples' standard deviations. Deterministic in
``seed``. Independent draws ignore any correlation of the noise from sample to sample, so the
bands are a lower bound where the residuals are correlated (early-time correction, drift).

>>> import numpy as np
>>> from spicethermal.core.ladder import Foster
>>> from spicethermal.fit.ladder import fit_foster
>>> t = np.logspace(-4, 1, 60)
>>> z = Foster.from_tau([1.0, 2.0], [1e-3, 1.0]).zth(t)
>>> noisy = z + np.random.default_rng(1).normal(0, 3e-3, t.size)
>>> fb = fit_bootstrap(fit_foster(t, noisy), n=30)
>>> bool(np.all(fb.zth.lo <= fb.zth.hi)), len(fb.u_r_k_per_w)
(True, 2)
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from ..core.errors import DataFormatError, FitError
from ..core.progress import bar
from ..identify.spectrum import time_constant_spectrum
from ..identify.structure import StructureFunction
from .ladder import fit_foster

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

    from ..identify.curves import ZthCurve
    from ..identify.spectrum import Spectrum
    from .ladder import FitResult

#: Central probability of the bands.
LEVEL = 0.95
#: Resamples drawn by default.
DEFAULT_N = 50


@dataclass(frozen=True, eq=False)
class Band:
    """A central ``level`` interval ``lo..hi`` of a quantity at abscissae ``x``."""

    x: NDArray
    lo: NDArray
    hi: NDArray
    level: float = LEVEL

    @classmethod
    def of(cls, x: NDArray, samples: NDArray, level: float = LEVEL) -> Band:
        """The band of ``samples`` (one resample per row) at ``x``.

        Parameters
        ----------
        x : abscissae, one per column of ``samples``.
        samples : one resample per row (NaN where a resample has no value).
        level : central probability.

        Returns
        -------
        Band
        """
        q = 50.0 * (1.0 - level)
        lo, hi = np.nanpercentile(samples, [q, 100.0 - q], axis=0)
        return cls(np.asarray(x, dtype=float), lo, hi, level)

    def to_dict(self, x: str, y: str) -> dict[str, Any]:
        """``{x: [...], y + "_lo": [...], y + "_hi": [...], "level": ...}``."""
        return {x: self.x.tolist(), f"{y}_lo": self.lo.tolist(), f"{y}_hi": self.hi.tolist(),
                "level": self.level}


def resamples(model: NDArray, data: NDArray, n: int, seed: int = 0, *,
              quiet: bool = True) -> Iterator[NDArray]:
    """``n`` curves ``model + residuals`` with the residuals ``data − model`` redrawn.

    Parameters
    ----------
    model : the smooth model at the data's abscissae.
    data : the data.
    n : number of resamples (>= 2).
    seed : random seed.
    quiet : no progress bar on stderr (:func:`spicethermal.core.progress.bar`).

    Returns
    -------
    iterator of ndarray
    """
    if not (isinstance(n, int | np.integer) and n >= 2):
        raise DataFormatError(f"bootstrap: n = {n!r} resamples, need at least 2")
    resid = np.asarray(data, dtype=float) - np.asarray(model, dtype=float)
    rng = np.random.default_rng(seed)
    for _ in bar(range(int(n)), desc="bootstrap resamples", quiet=quiet):
        yield model + rng.choice(resid, size=resid.size, replace=True)


@dataclass(frozen=True, eq=False)
class FitBootstrap:
    """The spread of a fitted ladder: per-stage standard deviations (stages by τ) and the
    Zth band at the data times."""

    n: int
    seed: int
    u_r_k_per_w: tuple[float, ...]
    u_tau_s: tuple[float, ...]
    zth: Band

    def to_dict(self) -> dict[str, Any]:
        """For the model file (``provenance.fit.bootstrap``) and JSON outputs."""
        return {"n": self.n, "seed": self.seed, "u_r_k_per_w": list(self.u_r_k_per_w),
                "u_tau_s": list(self.u_tau_s), "zth_band": self.zth.to_dict("t_s",
                                                                            "zth_k_per_w")}


def fit_bootstrap(result: FitResult, n: int = DEFAULT_N, seed: int = 0) -> FitBootstrap:
    """Refit ``n`` resamples of the fitted data at the fitted order, with the fit's weighting
    (Rth held if it was).

    Parameters
    ----------
    result : the fit to assess.
    n, seed : number of resamples and the random seed.

    Returns
    -------
    FitBootstrap
    """
    t = np.asarray(result.t_s)
    model = result.foster.zth(t)
    rth = result.rth_k_per_w if result.rth_fixed else None
    weighting = "relative" if result.weighting.startswith("relative") else "absolute"
    rs, taus, zs = [], [], []
    for z in resamples(model, np.asarray(result.zth_k_per_w), n, seed):
        try:
            b = fit_foster(t, z, order=result.order, rth_k_per_w=rth, weighting=weighting)
        except FitError:
            continue  # a resample that does not converge at this order says nothing
        rs.append(b.foster.r)
        taus.append(b.foster.tau)
        zs.append(b.foster.zth(t))
    if len(zs) < 2:
        raise DataFormatError("bootstrap: fewer than 2 resamples could be refitted")
    return FitBootstrap(len(zs), seed, tuple(np.std(rs, axis=0, ddof=1).tolist()),
                        tuple(np.std(taus, axis=0, ddof=1).tolist()),
                        Band.of(t, np.array(zs)))


@dataclass(frozen=True, eq=False)
class SpectrumBootstrap:
    """Bands of the time-constant spectrum and of the cumulative structure function."""

    n: int
    seed: int
    spectrum: Band
    structure: Band | None

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {"n": self.n, "seed": self.seed,
                               "spectrum": self.spectrum.to_dict("tau_s", "r_density_k_per_w")}
        if self.structure is not None:
            out["structure"] = self.structure.to_dict("r_k_per_w", "c_j_per_k")
        return out


def spectrum_bootstrap(curve: ZthCurve, spectrum: Spectrum, n: int = DEFAULT_N, seed: int = 0,
                       stages_per_decade: float | None = None, *, quiet: bool = True,
                       **options: Any) -> SpectrumBootstrap:
    """Deconvolve ``n`` resamples of ``curve`` around the spectrum's own model of it.

    Parameters
    ----------
    curve : the Zth curve the spectrum came from.
    spectrum : its spectrum (``options`` as used for it).
    n, seed : resamples and seed.
    stages_per_decade : also band the cumulative structure function (ΣC against ΣR, on the
        ΣR grid of the spectrum's own) at this lumping; ``None``: spectrum only.
    quiet : no progress bar on stderr.

    Returns
    -------
    SpectrumBootstrap
    """
    model = spectrum.zth(curve.t_s)
    dens, cums = [], []
    base_sf = (StructureFunction.from_spectrum(spectrum, stages_per_decade)
               if stages_per_decade is not None else None)
    for z in resamples(model, curve.zth_k_per_w, n, seed, quiet=quiet):
        s = time_constant_spectrum(replace(curve, zth_k_per_w=z), **options)
        dens.append(s.r_density_k_per_w)
        if base_sf is not None:
            sf = StructureFunction.from_spectrum(s, stages_per_decade)
            cums.append(_log_c_at(sf, base_sf.r_k_per_w))
    structure = None
    if base_sf is not None:
        band = Band.of(base_sf.r_k_per_w, np.array(cums))
        structure = Band(band.x, 10.0 ** band.lo, 10.0 ** band.hi, band.level)
    return SpectrumBootstrap(n, seed, Band.of(spectrum.tau_s, np.array(dens)), structure)


def _log_c_at(sf: StructureFunction, r: NDArray) -> NDArray:
    """log10 ΣC of ``sf`` at ΣR = ``r`` (NaN beyond its Rth)."""
    lc = np.interp(r, sf.r_k_per_w, np.log10(sf.c_j_per_k), right=np.nan)
    return np.where(r <= sf.r_k_per_w[-1], lc, np.nan)
