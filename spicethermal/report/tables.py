"""Datasheet-style tables of a model, as CSV: the Foster table (R_i, τ_i) and the duty-cycle
Zth family of the paper's Fig. 8 in K/W per duty.

>>> from spicethermal.core.ladder import Foster
>>> f = Foster.from_tau([1.0, 2.0], [1e-3, 1.0])
>>> print(foster_table_csv(f), end="")
# Foster model: Zth(t) = sum r_k_per_w (1 - exp(-t / tau_s)), Rth = 3 K/W
r_k_per_w,tau_s,c_j_per_k
1.0,0.001,0.001
2.0,1.0,0.5
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from ..engines.pwm import r_duty_exact
from ..identify.curves import log_grid
from ..io.bundle import format_columns

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

    from ..core.ladder import Cauer, Foster


def foster_table_csv(foster: Foster, u_r_k_per_w: Sequence[float] | None = None,
                     u_tau_s: Sequence[float] | None = None) -> str:
    """The Foster table as CSV (``r_k_per_w, tau_s, c_j_per_k`` and, when given, the standard
    uncertainties ``u_r_k_per_w, u_tau_s``), readable by
    :func:`spicethermal.io.datasheet.read_foster_table`.

    Parameters
    ----------
    foster : the ladder.
    u_r_k_per_w, u_tau_s : per-stage standard uncertainties (both or neither).

    Returns
    -------
    str
        The CSV text (module docstring).
    """
    cols: dict[str, Sequence[float]] = {"r_k_per_w": foster.r, "tau_s": foster.tau,
                                        "c_j_per_k": foster.c}
    if u_r_k_per_w is not None and u_tau_s is not None:
        cols.update(u_r_k_per_w=u_r_k_per_w, u_tau_s=u_tau_s)
    return format_columns(cols, [f"Foster model: Zth(t) = sum r_k_per_w (1 - exp(-t / tau_s)), "
                                 f"Rth = {foster.rth:.6g} K/W"])


def duty_family(ladder: Foster | Cauer, duties: Sequence[float],
                t_s: NDArray | None = None) -> dict[str, NDArray]:
    """Peak Zth (K/W) of pulses of width ``t`` repeated at each duty, exact periodic steady
    state (:func:`spicethermal.engines.pwm.r_duty_exact` × Rth): columns ``t_s`` and
    ``zth_k_per_w_d<D>``. ``t_s`` defaults to 10 points per decade from a decade below the
    fastest to a decade above the slowest time constant.

    Parameters
    ----------
    ladder : the model's ladder.
    duties : duty cycles, 0..1 (0: single pulse).
    t_s : pulse widths, s.

    Returns
    -------
    dict of str to ndarray
        The columns, ready for :func:`~spicethermal.io.bundle.format_columns`.

    >>> from spicethermal.core.ladder import Foster
    >>> fam = duty_family(Foster.from_tau([2.0], [1.0]), [0.0, 0.5], np.array([1.0]))
    >>> [round(float(fam[k][0]), 6) for k in ("zth_k_per_w_d0", "zth_k_per_w_d0.5")]
    [1.264241, 1.462117]
    """
    if t_s is None:
        taus = ladder.time_constants()
        t_s = log_grid(10.0 ** math.floor(math.log10(taus[0]) - 1),
                       10.0 ** math.ceil(math.log10(taus[-1]) + 1), 10)
    out = {"t_s": np.asarray(t_s, dtype=float)}
    for d in duties:
        out[f"zth_k_per_w_d{d:g}"] = r_duty_exact(ladder, out["t_s"], d) * ladder.rth
    return out
