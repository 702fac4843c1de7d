"""A ladder's Cauer form: exact from a Foster ladder, many at a time.

The network simulator (:mod:`.network`) runs on Cauer ladders (node temperatures are
physical there); fits move ladders in their Foster coordinates (``log R``, ``log τ``) and
simulate each trial on its Cauer form.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..core.ladder import Cauer, Foster

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

__all__ = ["as_cauer", "cauer_of_foster"]


def as_cauer(ladder: Foster | Cauer) -> Cauer:
    """``ladder`` as a Cauer ladder with a heat capacity at every node (exact).

    Parameters
    ----------
    ladder : Foster or Cauer

    Returns
    -------
    Cauer
    """
    return (ladder if isinstance(ladder, Cauer) else ladder.to_cauer()).with_capacitances()


def cauer_of_foster(r: NDArray, tau: NDArray) -> tuple[NDArray, NDArray]:
    """The Cauer ladders ``(R, C)``, ``(B, n)`` each, of the Foster ladders ``r``, ``tau``
    ``(B, n)``: Lanczos on the modes (``λ = 1/τ``, weights ``r/τ``) with full
    reorthogonalisation, in double precision, side by side. A fit's parameterisation: smooth
    in ``r`` and ``τ``, accurate to about 1e-10 relative for the ladders a fit meets (the
    exact conversions of :mod:`spicethermal.core.ladder` are for model files).

    >>> from spicethermal.core.ladder import Foster
    >>> f = Foster.from_tau([6.0, 20.0, 50.0, 70.0], [1e-4, 5e-3, 0.4, 30.0])
    >>> r, c = cauer_of_foster(np.array([f.r]), np.array([f.tau]))
    >>> exact = f.to_cauer()
    >>> bool(np.allclose(r[0], exact.r, rtol=1e-8) and np.allclose(c[0], exact.c, rtol=1e-8))
    True
    """
    with np.errstate(all="ignore"):  # a degenerate trial ladder gives NaN, never a warning
        return _lanczos(np.atleast_2d(np.asarray(r, dtype=float)),
                        np.atleast_2d(np.asarray(tau, dtype=float)))


def _lanczos(r: NDArray, tau: NDArray) -> tuple[NDArray, NDArray]:
    size, n = r.shape
    lam = 1.0 / tau
    w = r / tau
    q = np.sqrt(w / w.sum(axis=1, keepdims=True))
    basis = np.zeros((size, n, n))
    alpha, beta = np.zeros((size, n)), np.zeros((size, n))
    basis[:, 0] = q
    for k in range(n):
        v = basis[:, k]
        av = lam * v
        alpha[:, k] = np.sum(v * av, axis=1)
        if k == n - 1:
            break
        res = av - alpha[:, k:k + 1] * v - (beta[:, k - 1:k] * basis[:, k - 1] if k else 0.0)
        for _ in range(2):  # full reorthogonalisation, twice
            res = res - np.einsum("bj,bji->bi", np.einsum("bji,bi->bj", basis[:, :k + 1], res),
                                  basis[:, :k + 1])
        beta[:, k] = np.linalg.norm(res, axis=1)
        basis[:, k + 1] = res / np.where(beta[:, k:k + 1] > 0, beta[:, k:k + 1], np.nan)
    cap = np.empty((size, n))
    g = np.empty((size, n))
    cap[:, 0] = 1.0 / w.sum(axis=1)
    g[:, 0] = alpha[:, 0] * cap[:, 0]
    for k in range(1, n):
        cap[:, k] = g[:, k - 1] ** 2 / (beta[:, k - 1] ** 2 * cap[:, k - 1])
        g[:, k] = alpha[:, k] * cap[:, k] - g[:, k - 1]
    res_r = 1.0 / g
    return np.where(res_r > 0, res_r, np.nan), cap
