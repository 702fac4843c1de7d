"""What a ladder fit returns: :class:`FitResult` (the ladder, its uncertainties, the residuals,
every order tried as an :class:`OrderTrial`), printable and serialisable.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from ..core.ladder import Foster
from ..io.jsondoc import JsonDocument
from .problem import CRITERION, CRITERION_RULE

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray


# ----------------------------------------------------------------------------- results
@dataclass(frozen=True)
class OrderTrial(JsonDocument):
    """What happened at one order: its fit quality, criterion value and verdict."""

    order: int
    criterion_value: float
    rms_k_per_w: float
    accepted: bool
    reason: str = ""

    def to_dict(self) -> dict[str, Any]:
        """The trial as JSON-ready data (a criterion value that is not finite is None)."""
        return {
            "order": self.order,
            "criterion_value": _json_float(self.criterion_value),
            "rms_k_per_w": _json_float(self.rms_k_per_w),
            "accepted": self.accepted,
            "reason": self.reason,
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> OrderTrial:
        """The trial :meth:`to_dict` described (None back to NaN).

        >>> t = OrderTrial(3, float("nan"), 0.5, False, "no convergence")
        >>> OrderTrial.from_json(t.to_json()).reason
        'no convergence'
        """
        nan = float("nan")
        return cls(int(data["order"]),
                   nan if data["criterion_value"] is None else float(data["criterion_value"]),
                   nan if data["rms_k_per_w"] is None else float(data["rms_k_per_w"]),
                   bool(data["accepted"]), str(data.get("reason", "")))


@dataclass(frozen=True, eq=False)
class FitResult(JsonDocument):
    """A fitted Foster ladder with its diagnostics. Immutable; prints as a table.

    Attributes
    ----------
    foster : Foster
        The fitted ladder, stages sorted fastest first.
    u_r_k_per_w, u_tau_s : tuple of float
        Standard uncertainties of each ``r_i`` (K/W) and ``τ_i`` (s), in stage order.
    t_s, zth_k_per_w, residuals : ndarray (read-only)
        The data as given and the residuals ``data - model`` (K/W) at every data point.
    rms_k_per_w : float
        Root-mean-square of ``residuals``.
    criterion : str
        Name of the order-selection criterion (``"BIC"``; ``"fixed"`` when the order was given).
    trials : tuple of OrderTrial
        Every order tried, with its criterion value and why it was accepted or rejected.
    rth_fixed : bool
        Whether ``ΣR = Rth`` was imposed.
    converged : bool
        The optimiser's convergence flag for the returned fit.
    message : str
        The optimiser's message.
    warnings : tuple of str
        What the user should know about an accepted fit (a given order the data do not
        support, an undetermined time constant, an order at ``max_order``).
    n_fit_points : int
        Points actually fitted (fewer than the data when dense data were binned).
    weighting : str
        How the residuals were weighted, in words (absolute or relative).
    """

    foster: Foster
    u_r_k_per_w: tuple[float, ...]
    u_tau_s: tuple[float, ...]
    t_s: NDArray
    zth_k_per_w: NDArray
    residuals: NDArray
    rms_k_per_w: float
    criterion: str
    trials: tuple[OrderTrial, ...]
    rth_fixed: bool
    converged: bool
    message: str
    n_fit_points: int
    warnings: tuple[str, ...] = ()
    weighting: str = field(default="absolute K/W, equal weight per point on the log-time grid")

    @property
    def order(self) -> int:
        """Number of stages of the fitted ladder."""
        return self.foster.order

    @property
    def rth_k_per_w(self) -> float:
        """Fitted total thermal resistance ΣR (K/W)."""
        return self.foster.rth

    @property
    def resampled(self) -> bool:
        """Whether dense data were averaged into log-spaced bins before fitting."""
        return self.n_fit_points != len(self.t_s)

    @property
    def criterion_values(self) -> dict[int, float]:
        """Criterion value of every order tried (lower is better)."""
        return {tr.order: tr.criterion_value for tr in self.trials}

    @property
    def stages(self) -> list[dict[str, float]]:
        """Stage table: r, u(r), τ, u(τ), C for each stage, fastest first."""
        return [
            {"r_k_per_w": r, "u_r_k_per_w": ur, "tau_s": tau, "u_tau_s": ut, "c_j_per_k": c}
            for r, ur, tau, ut, c in zip(self.foster.r, self.u_r_k_per_w, self.foster.tau,
                                         self.u_tau_s, self.foster.c, strict=True)
        ]

    def to_dict(self) -> dict[str, Any]:
        """The fit report as plain JSON-ready data (without the data arrays)."""
        return {
            "order": self.order,
            "criterion": self.criterion,
            "criterion_rule": CRITERION_RULE if self.criterion == CRITERION else
            "order given by the user",
            "criterion_values": {str(k): _json_float(v) for k, v in self.criterion_values.items()},
            "trials": [tr.to_dict() for tr in self.trials],
            "rth_k_per_w": self.rth_k_per_w,
            "rth_fixed": self.rth_fixed,
            "stages": self.stages,
            "rms_k_per_w": self.rms_k_per_w,
            "n_points": len(self.t_s),
            "n_fit_points": self.n_fit_points,
            "weighting": self.weighting,
            "converged": self.converged,
            "message": self.message,
            "warnings": list(self.warnings),
        }

    def __str__(self) -> str:
        head = (f"Foster ladder, order {self.order} ({self._order_note()}), "
                f"Rth = {_g(self.rth_k_per_w)} K/W{' (held)' if self.rth_fixed else ''}, "
                f"rms residual = {_g(self.rms_k_per_w, 3)} K/W over {len(self.t_s)} points")
        rows = [("stage", "R (K/W)", "± u", "tau (s)", "± u", "C (J/K)")]
        for i, s in enumerate(self.stages, 1):
            rows.append((str(i), _g(s["r_k_per_w"]), _g(s["u_r_k_per_w"], 2), _g(s["tau_s"]),
                         _g(s["u_tau_s"], 2), _g(s["c_j_per_k"])))
        widths = [max(len(r[k]) for r in rows) for k in range(len(rows[0]))]
        lines = [head]
        for j, row in enumerate(rows):
            lines.append("  ".join(x.rjust(w) for x, w in zip(row, widths, strict=True)))
            if j == 0:
                lines.append("  ".join("-" * w for w in widths))
        if len(self.trials) > 1:
            lines.append(f"{self.criterion} per order: " + ", ".join(
                f"{tr.order}: {tr.criterion_value:.1f}{'' if tr.accepted else ' (rejected)'}"
                for tr in self.trials))
            lines.extend(f"order {tr.order} rejected: {tr.reason}" for tr in self.trials
                         if not tr.accepted and tr.reason)
        lines.extend(f"warning: {w}" for w in self.warnings)
        return "\n".join(lines)

    def _order_note(self) -> str:
        if self.criterion == "fixed":
            return "given"
        return f"chosen by {self.criterion}"


def _g(x: float, digits: int = 5) -> str:
    return f"{x:.{digits}g}"


def _json_float(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None
