"""The heater diode's law Vf(I, T) fitted to the bench's forward-voltage points and its TSP
calibration (:class:`~spicethermal.core.diode.DiodeLaw`).

Two kinds of points, fitted together by weighted linear least squares in the law's linear
form (:func:`spicethermal.core.diode.linear_terms`):

* **forward points** ``(T, I, V)``: the heater's absolute voltage at a few currents at each
  calibration temperature (``docs/bundle-format.md``, section ``forward``), read in the
  middle of a short current pulse;
* **calibration points** ``(T, v_tsp)`` at the sense current: the TSP is the heater's voltage
  less the reference diode's, so ``v_tsp + o = V(I_sense, T)`` with the offset ``o`` one more
  unknown. They are precise (µV) where the forward points are coarse (mV): they fix the
  temperature dependence, the forward points the current dependence and the level.

Every point's temperature is the junction's: the recorded (fixture) temperature plus the sense
current's steady heating ``I_sense·V·Rth`` and, for a pulse, its own heating
``(I·V − I_sense·V_sense)·Zth(t_pulse)`` from the thermal model (the law is refitted twice with
the voltages it predicts). Each kind of point gets its own noise, estimated from its residuals
(iterated), which weighs it; the uncertainties are the weighted fit's (1σ). ``XTI`` is fitted
when the points span four temperatures or more (else SPICE's 3 is kept), ``RS`` when they span
three currents or more (else 0); both choices are said.

>>> import numpy as np
>>> from spicethermal.core.diode import DiodeLaw
>>> true = DiodeLaw(n=1.75, is_a=2.5e-9, rs_ohm=0.57, xti=0.0, eg_ev=1.195)
>>> t, i = np.meshgrid([25.0, 45.0, 65.0, 85.0], [5e-3, 2e-2, 0.1, 0.3])
>>> fit = fit_diode(t.ravel(), i.ravel(), true.voltage(i, t).ravel())
>>> round(fit.law.n, 4), round(fit.law.rs_ohm, 4)
(1.75, 0.57)
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from ..core.diode import K_OVER_Q, ZERO_C_K, DiodeLaw, linear_terms
from ..core.errors import DataFormatError, where
from ..io.datasets import CalibrationTable
from ..io.jsondoc import JsonDocument

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import ArrayLike, NDArray

    from ..io.bundle import Bundle
    from ..model import ThermalModel

#: SPICE's default ``XTI`` of a junction diode, kept when the points cannot tell it.
XTI_DEFAULT = 3.0
#: Temperatures and currents count as distinct when further apart than these.
SAME_T_K, SAME_I_REL = 0.5, 0.02


def _distinct(values: NDArray, same) -> int:
    out: list[float] = []
    for v in np.sort(values):
        if not out or not same(out[-1], v):
            out.append(float(v))
    return len(out)


@dataclass(frozen=True, eq=False)
class DiodeFit(JsonDocument):
    """A fitted :class:`~spicethermal.core.diode.DiodeLaw` with its residuals.

    Attributes
    ----------
    law : DiodeLaw
        The law; ``law.fit`` holds the uncertainties and residuals as the model file keeps
        them.
    u : dict
        1σ uncertainties of ``n``, ``is_a`` (A), ``rs_ohm``, ``xti``, ``eg_ev`` and
        ``tsp_offset_v`` (0 for a parameter held).
    junction_c : NDArray
        The forward points' junction temperatures (self-heating added), °C.
    residual_v : NDArray
        Forward points: measured − law, V.
    calibration_residual_v : NDArray
        Calibration points: (TSP + offset) − law, V (empty without a calibration).
    rms_v, rms_k : dict
        RMS residual per kind of point (``forward``, ``calibration``), V and its
        temperature equivalent (K, through dV/dT).
    held : tuple of str
        Parameters not fitted (the points cannot tell them), with why.
    """

    law: DiodeLaw
    u: dict[str, float]
    junction_c: NDArray
    residual_v: NDArray
    calibration_residual_v: NDArray
    rms_v: dict[str, float]
    rms_k: dict[str, float]
    held: tuple[str, ...] = field(default=())

    def to_dict(self) -> dict[str, Any]:
        """The fit as the model file keeps it (``electrical.fit``)."""
        return {"u": dict(self.u), "rms_v": dict(self.rms_v), "rms_k": dict(self.rms_k),
                "points": {"forward": int(self.residual_v.size),
                           "calibration": int(self.calibration_residual_v.size)},
                "held": list(self.held)}

    def __str__(self) -> str:
        law, u = self.law, self.u
        is_rel = u["is_a"] / law.is_a if law.is_a else math.nan
        lines = [f"diode law Vf(I, T) from {self.residual_v.size} forward points"
                 + (f" and {self.calibration_residual_v.size} calibration points"
                    if self.calibration_residual_v.size else "") + ":",
                 f"  N   = {law.n:.4f} ± {u['n']:.2g}   (ideality)",
                 f"  IS  = {law.is_a:.4g} A ± {100 * is_rel:.2g} %   (saturation current at "
                 f"{law.t0_c:g} degC)",
                 f"  XTI = {law.xti:.3g} ± {u['xti']:.2g}, EG = {law.eg_ev:.4f} ± "
                 f"{u['eg_ev']:.2g} eV   (its temperature dependence)",
                 f"  RS  = {law.rs_ohm:.4g} ± {u['rs_ohm']:.2g} ohm   (series resistance)"]
        for kind in ("forward", "calibration"):
            if kind in self.rms_v:
                lines.append(f"  residual, {kind} points: {1e3 * self.rms_v[kind]:.3g} mV rms "
                             f"({self.rms_k[kind]:.2g} K)")
        lines += [f"  held: {h}" for h in self.held]
        return "\n".join(lines)


def fit_diode(temp_c: ArrayLike, i_a: ArrayLike, vf_v: ArrayLike, *,
              t_pulse_s: ArrayLike | None = None,
              calibration: tuple[ArrayLike, ArrayLike] | None = None,
              sense_current_a: float | None = None, model: ThermalModel | None = None,
              t0_c: float = 25.0, label: str = "forward") -> DiodeFit:
    """Fit the diode law to forward points and, optionally, the TSP calibration.

    Parameters
    ----------
    temp_c, i_a, vf_v : array_like
        Forward points: recorded temperature (°C), current (A), voltage (V).
    t_pulse_s : array_like, optional
        Time from the start of each point's current pulse to its reading, s (0: a steady
        reading; default all 0). Needs ``model`` for the self-heating.
    calibration : (array_like, array_like), optional
        The TSP calibration's ``temp_c`` and ``v_tsp_v``, taken at ``sense_current_a``.
    sense_current_a : float, optional
        The bench's sense current, A (needed with ``calibration``).
    model : ThermalModel, optional
        The thermal model whose Rth and Zth(t) give each point's self-heating (none without).
    t0_c : float
        The temperature of ``IS``, °C.
    label : str
        What error messages name (the file of the points).

    Returns
    -------
    DiodeFit
        The law, its uncertainties and residuals.
    """
    t_rec = np.asarray(temp_c, dtype=float).ravel()
    i = np.asarray(i_a, dtype=float).ravel()
    v = np.asarray(vf_v, dtype=float).ravel()
    tp = np.zeros_like(t_rec) if t_pulse_s is None else \
        np.asarray(t_pulse_s, dtype=float).ravel()
    if not (t_rec.size == i.size == v.size == tp.size) or t_rec.size == 0:
        raise DataFormatError(f"{where(label)}forward points: temp_c, i_a and vf_v must be "
                              "equally long and not empty")
    bad = ~(np.isfinite(t_rec) & np.isfinite(i) & np.isfinite(v) & np.isfinite(tp)) | \
        (i <= 0) | (v <= 0) | (tp < 0)
    if bad.any():
        raise DataFormatError(f"{where(label)}forward point {int(np.argmax(bad)) + 1}: current "
                              "and voltage must be > 0, the pulse time >= 0, all finite")
    if np.any(tp > 0) and model is None:
        raise DataFormatError(f"{where(label)}pulsed points need the thermal model (their "
                              "self-heating is Zth(t_pulse)·P)")
    cal_t = cal_v = np.empty(0)
    if calibration is not None:
        if sense_current_a is None:
            raise DataFormatError(f"{where(label)}the calibration's points need the sense "
                                  "current they were taken at (sense_current_a)")
        cal_t, cal_v = (np.asarray(x, dtype=float).ravel() for x in calibration)
    i_s = sense_current_a
    currents = np.append(i, [i_s] if cal_t.size else [])
    n_i = _distinct(currents, lambda a, b: b <= a * (1 + SAME_I_REL))
    n_t = _distinct(np.append(t_rec, cal_t), lambda a, b: b - a <= SAME_T_K)
    if n_i < 2 or n_t < 2:
        raise DataFormatError(f"{where(label)}the diode law needs points at 2 currents and 2 "
                              f"temperatures at least (here {n_i} and {n_t})")
    held = []
    fit_xti, fit_rs = n_t >= 4, n_i >= 3
    if not fit_xti:
        held.append(f"XTI = {XTI_DEFAULT:g} (SPICE's default: the points span {n_t} "
                    f"temperatures, 4 tell it)")
    if not fit_rs:
        held.append(f"RS = 0 (the points span {n_i} currents, 3 tell it)")
    rth = model.rth if model is not None else 0.0
    zth = model.ladder.zth(np.where(tp > 0, tp, 1.0)) * (tp > 0) if model is not None else \
        np.zeros_like(tp)
    law = DiodeLaw(n=1.0, is_a=1e-30, t0_c=t0_c, sense_current_a=i_s)  # its "+1" is nil
    v_sense = np.full(t_rec.size, 0.6)
    v_sense_cal = np.full(cal_t.size, 0.6)
    sigma = {"forward": 1e-3, "calibration": 1e-4}
    for _ in range(4):  # self-heating from the last law's voltages, then the fit again
        p_sense = 0.0 if i_s is None else i_s
        t_j = t_rec + p_sense * v_sense * rth + np.maximum(i * v - p_sense * v_sense, 0) * zth
        t_cal = cal_t + p_sense * v_sense_cal * rth
        # the linear form drops the law's "+1" (I >> Is): put its share back, from the last law
        v_lin = v - law.thermal_voltage(t_j) * np.log1p(law.saturation_current(t_j) / i)
        cal_lin = cal_v if i_s is None else \
            cal_v - law.thermal_voltage(t_cal) * np.log1p(law.saturation_current(t_cal) / i_s)
        for _ in range(4):  # weights from each kind's residuals
            sol = _solve(t_j, i, v_lin, t_cal, cal_lin, i_s, t0_c, fit_xti, fit_rs, sigma)
            params, cov, res_f, res_c = sol
            sigma = _noise(res_f, res_c, params.size, sigma)
        law = _law(params, cov, t0_c, i_s, currents, np.append(t_j, t_cal), fit_xti)
        if i_s is not None:
            v_sense = law.voltage(i_s, t_rec)
            v_sense_cal = law.voltage(i_s, cal_t)
    u = _uncertainties(params, cov, t0_c, law)
    slope = np.abs(law.slope_v_per_k(i, t_j))
    rms_v = {"forward": float(np.sqrt(np.mean(res_f ** 2)))}
    rms_k = {"forward": float(np.sqrt(np.mean((res_f / slope) ** 2)))}
    if res_c.size:
        slope_c = np.abs(law.slope_v_per_k(i_s, t_cal))
        rms_v["calibration"] = float(np.sqrt(np.mean(res_c ** 2)))
        rms_k["calibration"] = float(np.sqrt(np.mean((res_c / slope_c) ** 2)))
    result = DiodeFit(law, u, t_j, res_f, res_c, rms_v, rms_k, tuple(held))
    return replace(result, law=replace(law, fit=result.to_dict()))


def _solve(t_j, i, v, t_cal, cal_v, i_s, t0_c, fit_xti, fit_rs, sigma):
    """Weighted least squares in ``[a, b, c, d, RS, offset]``; held columns dropped."""
    rows = linear_terms(i, t_j, t0_c)
    rhs = v.copy()
    weight = np.full(v.size, 1 / sigma["forward"])
    if t_cal.size:
        cal_rows = linear_terms(np.full(t_cal.size, i_s), t_cal, t0_c)
        rows = np.vstack([rows, cal_rows])
        rhs = np.concatenate([rhs, cal_v])
        weight = np.concatenate([weight, np.full(t_cal.size, 1 / sigma["calibration"])])
    offset = np.concatenate([np.zeros(v.size), -np.ones(t_cal.size)])[:, None]
    a = np.hstack([rows, offset])
    keep = [True, True, True, fit_xti, fit_rs, bool(t_cal.size)]
    if not fit_xti:  # d = −XTI·k/q held: its term moves to the right-hand side
        rhs = rhs - a[:, 3] * (-XTI_DEFAULT * K_OVER_Q)
    cols = np.flatnonzero(keep)
    aw = a[:, cols] * weight[:, None]
    scale = np.sqrt(np.sum(aw ** 2, axis=0))
    sol, *_ = np.linalg.lstsq(aw / scale, rhs * weight, rcond=None)
    cov_small = np.linalg.pinv((aw / scale).T @ (aw / scale)) / np.outer(scale, scale)
    params = np.zeros(6)
    params[3] = -XTI_DEFAULT * K_OVER_Q
    params[cols] = sol / scale
    cov = np.zeros((6, 6))
    cov[np.ix_(cols, cols)] = cov_small
    fitted = a @ params
    res = rhs + (0 if fit_xti else a[:, 3] * (-XTI_DEFAULT * K_OVER_Q)) - fitted
    return params, cov, res[:v.size], res[v.size:]


def _noise(res_f: NDArray, res_c: NDArray, n_params: int, old: dict) -> dict:
    """Each kind's noise from its residuals (degrees of freedom shared in proportion)."""
    n = res_f.size + res_c.size
    out = dict(old)
    for kind, r in (("forward", res_f), ("calibration", res_c)):
        if r.size:
            dof = max(r.size - n_params * r.size / n, 1.0)
            out[kind] = max(float(np.sqrt(np.sum(r ** 2) / dof)), 1e-7)
    return out


def _law(params: NDArray, cov: NDArray, t0_c: float, i_s: float | None, currents: NDArray,
         t_j: NDArray, fit_xti: bool) -> DiodeLaw:
    a, b, c, d, rs, offset = params
    if not a > 0:
        raise DataFormatError("the diode law's fit gives no positive ideality: the forward "
                              "voltage does not rise with the current in these points")
    t0k = t0_c + ZERO_C_K
    return DiodeLaw(n=a / K_OVER_Q, is_a=math.exp(-(b + c / t0k) / a),
                    rs_ohm=max(rs, 0.0), xti=-d / K_OVER_Q if fit_xti else XTI_DEFAULT,
                    eg_ev=c if c > 0 else 1e-3, t0_c=t0_c, sense_current_a=i_s,
                    tsp_offset_v=float(offset) if cov[5, 5] > 0 else None,
                    valid_i_a=(float(currents.min()), float(currents.max())),
                    valid_t_c=(float(t_j.min()), float(t_j.max())))


def _uncertainties(params: NDArray, cov: NDArray, t0_c: float, law: DiodeLaw) -> dict:
    a, b, c = params[:3]
    t0k = t0_c + ZERO_C_K
    grad = np.zeros(6)  # ln IS = −(b + c/T0)/a
    grad[:3] = [(b + c / t0k) / a ** 2, -1 / a, -1 / (a * t0k)]
    u_ln_is = math.sqrt(max(float(grad @ cov @ grad), 0.0))
    sd = np.sqrt(np.maximum(np.diag(cov), 0.0))
    return {"n": float(sd[0] / K_OVER_Q), "is_a": float(law.is_a * u_ln_is),
            "rs_ohm": float(sd[4]), "xti": float(sd[3] / K_OVER_Q), "eg_ev": float(sd[2]),
            "tsp_offset_v": float(sd[5])}


def fit_electrical(bundle: Bundle, model: ThermalModel | None = None) -> DiodeFit | None:
    """The diode law of a bundle's ``forward`` section with its TSP calibration (a table of
    points) and the thermal ``model``'s self-heating; None when the bundle has no forward
    points.

    Parameters
    ----------
    bundle : Bundle
        The measurement bundle.
    model : ThermalModel, optional
        Its thermal model (for the points' self-heating).

    Returns
    -------
    DiodeFit or None
        The fit.
    """
    fwd = bundle.forward
    if fwd is None:
        return None
    cal = bundle.calibration
    points = (cal.temp_c, cal.v_tsp_v) if isinstance(cal, CalibrationTable) and \
        fwd.sense_current_a is not None else None
    return fit_diode(fwd.temp_c, fwd.i_a, fwd.vf_v, t_pulse_s=fwd.t_pulse_s,
                     calibration=points, sense_current_a=fwd.sense_current_a, model=model,
                     label=fwd.file or "forward.csv")
