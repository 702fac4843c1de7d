"""The result of a diagnosis: the candidates weighed, the steps taken, the verdict; its text
report and its ``spicethermal-diagnosis/2`` document (docs/diagnosis-json.md).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from .residuals import fmt_time
from .verdict import DIRECT

if TYPE_CHECKING:  # pragma: no cover
    from ..core.ladder import Foster
    from ..effects import Effect
    from ..model import ThermalModel
    from .compare import Comparison

__all__ = ["DIAGNOSIS_FORMAT", "WORST_POINTS", "Candidate", "Diagnosis", "Step"]

#: The document's format. Version 2 adds ``steps``, ``verdict.effects``, the candidates'
#: ``form`` and ``explained`` (docs/diagnosis-json.md); every key of version 1 is kept.
DIAGNOSIS_FORMAT = "spicethermal-diagnosis/2"
#: How many worst points the document lists.
WORST_POINTS = 5


@dataclass(frozen=True, eq=False)
class Candidate:
    """One candidate effect fitted to the bundle (its best form). ``improvement`` is the
    previous model's pooled RMS over this one's; ``explained`` the fraction of the previous
    model's misfit beyond the noise that the effect removes (see :func:`explained_fraction`);
    ``contradicted`` why the data contradict its physics ("" when they do not, see
    :mod:`spicethermal.analysis.consistency`)."""

    effect: Effect
    ladder: Foster
    comparison: Comparison
    n_params: int
    bic: float
    improvement: float
    evidence: str
    explained: float
    fit_s: float
    contradicted: str = ""
    #: The fit's facts behind the evidence sentence (see
    #: :class:`~spicethermal.fit.effectfit.EffectFit`).
    facts: Mapping[str, Any] = field(default_factory=dict)
    #: The improvement with the noise (:func:`~spicethermal.analysis.verdict.improvement`
    #: given the noise estimates: ``improvement`` or, when larger, the noise-weighted ratio;
    #: ``None``: not measured, as for a Table-2 candidate).
    noise_gain: float | None = None
    #: Every effect of the model with this candidate, when they were refitted jointly with it
    #: (empty: the model's effects as they were, and this one).
    model_effects: tuple[Effect, ...] = ()

    @property
    def rms_k(self) -> float:
        return self.comparison.rms_k

    @property
    def gain(self) -> float:
        """The improvement the decision weighs: ``noise_gain`` when measured, else
        ``improvement``."""
        return self.improvement if self.noise_gain is None else self.noise_gain

    def to_json(self) -> dict[str, Any]:
        return {"effect": self.effect.name, "form": self.effect.form,
                "params": dict(self.effect.params), "rms_k": self.rms_k,
                "improvement": self.improvement if math.isfinite(self.improvement) else None,
                "explained": self.explained, "evidence": self.evidence}


@dataclass(frozen=True, eq=False)
class Step:
    """One step of the iterative diagnosis: the effect added (its candidate, with the ladder
    refitted), the candidates that were weighed at this step, best first, and the model's
    effects after it (from the second step on, every effect refitted jointly with the
    ladder: :func:`~spicethermal.fit.backfit.refit_effects`)."""

    chosen: Candidate
    candidates: tuple[Candidate, ...]
    effects: tuple[Effect, ...] = ()

    def to_json(self) -> dict[str, Any]:
        c = self.chosen
        return {"effect": c.effect.name, "form": c.effect.form, "params": dict(c.effect.params),
                "rms_k": c.rms_k, "improvement": c.improvement}


@dataclass(frozen=True, eq=False)
class Diagnosis:
    """What :func:`diagnose` found. ``str()`` is the human report, :meth:`to_json` the
    ``spicethermal-diagnosis/2`` document. ``candidates`` are those of the first step (every
    effect against the baseline); ``steps`` the effects added in turn."""

    baseline: Comparison
    baseline_model: ThermalModel
    noise_k: Mapping[str, float]
    baseline_bic: float
    candidates: tuple[Candidate, ...]
    verdict_effect: str | None
    verdict_reason: str
    where: tuple[str, ...]
    skipped: Mapping[str, str] = field(default_factory=dict)
    elapsed_s: float = 0.0
    source: str = ""
    extra: Mapping[str, Any] = field(default_factory=dict)
    steps: tuple[Step, ...] = ()

    @property
    def best(self) -> Candidate | None:
        """The verdict's candidate (None when no effect was found)."""
        if self.verdict_effect is None:
            return None
        return next(c for c in self.candidates if c.effect.name == self.verdict_effect)

    @property
    def effects(self) -> list[str]:
        """Names of the effects added, in order."""
        return [s.chosen.effect.name for s in self.steps]

    @property
    def final(self) -> Comparison:
        """The comparison after the last step (the baseline when no effect was added)."""
        return self.steps[-1].chosen.comparison if self.steps else self.baseline

    def model(self) -> ThermalModel:
        """The baseline model with every effect of the steps (as refitted at the last step) and
        the last step's ladder."""
        if not self.steps:
            return self.baseline_model
        last = self.steps[-1]
        return type(self.baseline_model)(
            last.chosen.ladder,
            last.effects or (*self.baseline_model.effects,
                             *(s.chosen.effect for s in self.steps)),
            self.baseline_model.reference, self.baseline_model.provenance)

    def to_json(self) -> dict[str, Any]:
        """The ``spicethermal-diagnosis/2`` document."""
        worst = [{"dataset": p.dataset, "at": dict(p.at), "residual_k": p.residual_k}
                 for p in self.baseline.worst(WORST_POINTS)]
        return {"format": DIAGNOSIS_FORMAT,
                "baseline": {"rms_k": self.baseline.rms_k, "max_abs_k": self.baseline.max_abs_k,
                             "worst": worst},
                "candidates": [c.to_json() for c in self.candidates],
                "steps": [s.to_json() for s in self.steps],
                "verdict": {"effect": self.verdict_effect, "effects": self.effects,
                            "reason": self.verdict_reason}}

    def staircase(self) -> str:
        """The RMS after each step, e.g. ``0.38 K → +temperature-coefficient 0.05 K (7.6×)``."""
        parts = [f"baseline {self.baseline.rms_k:.3g} K"]
        parts += [f"+{s.chosen.effect.name} ({s.chosen.effect.form}) {s.chosen.rms_k:.3g} K "
                  f"({s.chosen.improvement:.3g}×)" for s in self.steps]
        return " → ".join(parts)

    def __str__(self) -> str:
        lines = [f"diagnosis of {self.source or 'the bundle'}: "
                 f"{len(self.baseline.points)} points in {', '.join(self.baseline.datasets)}",
                 f"baseline (linear {self.baseline_model.ladder.order}-stage ladder"
                 + (f" + {', '.join(e.name for e in self.baseline_model.effects)}"
                    if self.baseline_model.effects else "")
                 + f"): RMS {self.baseline.rms_k:.3g} K, worst {self.baseline.max_abs_k:.3g} K",
                 "where it fails:"]
        lines += [f"  {s}" for s in self.where] or ["  nowhere beyond the noise"]
        lines.append("worst points:")
        for p in self.baseline.worst(WORST_POINTS):
            lines.append(f"  {p.dataset:12s} {_at_text(p.at):24s} {p.residual_k:+8.3f} K")
        lines.append("candidates (best first; ΔBIC vs baseline, RMS, improvement):")
        for c in self.candidates:
            params = ", ".join(f"{k} = {_num(v)}" for k, v in c.effect.params.items())
            lines.append(f"  {c.effect.name:24s} ΔBIC {c.bic - self.baseline_bic:+10.1f}  "
                         f"RMS {c.rms_k:.3g} K  {c.improvement:6.2f}×  "
                         f"explains {100 * max(c.explained, 0):.0f} %"
                         # an effect judged on some data sets only says which
                         f"{''.join(f' in its {d}' for d in DIRECT.get(c.effect.name, ()))}  "
                         f"(form {c.effect.form}; {params})")
        for name, why in self.skipped.items():
            lines.append(f"  {name:24s} not tried: {why}")
        table = self.extra.get("table2")
        if table is not None:
            lines.append("findings (measured vs simulated table):")
            lines += [f"  - {x}" for x in table.findings.values()]
        lines.append(f"RMS staircase: {self.staircase()}")
        lines.append(f"verdict: {', '.join(self.effects) or self.verdict_effect or 'none'} — "
                     f"{self.verdict_reason}")
        best = self.best
        if best is not None:
            for i, st in enumerate(self.steps):
                lines.append(f"evidence{f' (step {i + 1})' if i else ''}: "
                             f"{st.chosen.evidence}")
            final = self.final
            lines.append(f"error before → after: RMS {self.baseline.rms_k:.3g} → "
                         f"{final.rms_k:.3g} K, worst {self.baseline.max_abs_k:.3g} → "
                         f"{final.max_abs_k:.3g} K")
            for name, sub in self.baseline.by_dataset().items():
                lines.append(f"  {name:12s} {sub.rms_k:8.3f} → "
                             f"{final.dataset(name).rms_k:8.3f} K")
        lines.append(f"({self.elapsed_s:.1f} s)")
        return "\n".join(lines)


def _num(v: float) -> str:
    return f"{v:.4g}"


def _at_text(at: Mapping[str, float]) -> str:
    if "freq_hz" in at:
        return f"{at['freq_hz'] / 1e3:g} kHz, D = {100 * at['duty']:g} %"
    if "temp_c" in at:
        return f"{at['temp_c']:g} °C"
    return f"t = {fmt_time(at['t_s'])}"
