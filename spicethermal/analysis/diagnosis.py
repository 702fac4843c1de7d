"""The result of a diagnosis: the baseline, the candidates weighed, the steps taken, the
verdict; its text report and its ``spicethermal-diagnosis/9`` document
(docs/diagnosis-json.md). Prose is generated from the numbers, never the other way round.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from ..effects.base import CALIBRATION, STEADY
from ..io.jsondoc import JsonDocument
from ..model import ThermalModel
from .where import fmt_time

if TYPE_CHECKING:  # pragma: no cover
    from ..effects import Effect
    from ..fit.joint import ModelFit
    from .compare import Comparison

__all__ = ["DIAGNOSIS_FORMAT", "NAMED", "APPROXIMATE", "AMBIGUOUS", "NONE", "RIVAL", "UNSHOWN",
           "Candidate", "Diagnosis", "Step", "Verdict", "WorkSpent", "last_model"]

#: The document's format; version 9 gives the noise of the baseline and of each step
#: (docs/diagnosis-json.md), and keeps every other key of versions 1 to 8.
DIAGNOSIS_FORMAT = "spicethermal-diagnosis/9"
#: Verdict classes (and the statuses of a step, :class:`Step`, with the two below).
NAMED, APPROXIMATE, AMBIGUOUS, NONE = "named", "approximate", "ambiguous", "none"
RIVAL, UNSHOWN = "rival", "unshown"
#: Worst points listed.
WORST_POINTS = 5


@dataclass(frozen=True, eq=False)
class Candidate:
    """One effect (its best form) fitted onto the model of a step, with the ladder and the
    model's other effects refitted. ``delta_bic``: the step's model's BIC minus this one's
    (positive: better); ``explained``: the fraction of the step's model's misfit beyond the
    noise it removes; ``improvement``: pooled RMS before over after; ``forms``: every form
    fitted, ``(form, delta_bic)``."""

    effect: Effect
    fit: ModelFit
    comparison: Comparison
    delta_bic: float
    explained: float
    improvement: float
    forms: tuple[tuple[str, float], ...] = ()

    @property
    def name(self) -> str:
        return self.effect.name

    @property
    def catalogued(self) -> bool:
        return self.effect.plugin.traits.catalogued

    @property
    def rms_k(self) -> float:
        return self.comparison.rms_k

    @property
    def evidence(self) -> str:
        return self.effect.describe()

    def to_dict(self) -> dict[str, Any]:
        return {"effect": self.name, "form": self.effect.form,
                "params": dict(self.effect.form_params), "catalogued": self.catalogued,
                "delta_bic": _finite(self.delta_bic), "rms_k": _finite(self.rms_k),
                "improvement": _finite(self.improvement), "explained": _finite(self.explained),
                "evidence": self.evidence,
                "forms": [{"form": f, "delta_bic": _finite(b)} for f, b in self.forms]}


@dataclass(frozen=True, eq=False)
class Step:
    """One step of the forward selection: the effect added (``chosen``), the candidates
    weighed, best first, its ``status`` (``named``, ``ambiguous``: ``tied`` explain the data
    as well; ``rival``: an explanation outside the catalogue, weighed and never named;
    ``unshown``: an effect the data cannot show alone, ``why`` not), the effects the backward
    check dropped after it, the model after it, and the noise estimated from it (the next's)."""

    chosen: Candidate
    candidates: tuple[Candidate, ...]
    status: str
    model: ModelFit
    comparison: Comparison
    tied: tuple[Candidate, ...] = ()
    dropped: tuple[str, ...] = ()
    why: str = ""
    noise_k: Mapping[str, float] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        c = self.chosen
        return {"effect": c.name, "form": c.effect.form, "params": dict(c.effect.form_params),
                "status": self.status, "rms_k": _finite(self.comparison.rms_k),
                "improvement": _finite(c.improvement), "delta_bic": _finite(c.delta_bic),
                "explained": _finite(c.explained), "tied": [t.name for t in self.tied],
                "dropped": list(self.dropped), "why": self.why, "noise_k": dict(self.noise_k)}


def last_model(steps: Sequence[Step], base: ModelFit) -> ModelFit:
    """The model after the last of ``steps`` (``base`` before any)."""
    return steps[-1].model if steps else base


@dataclass(frozen=True)
class Verdict:
    """What the diagnosis concludes: a class (:data:`NAMED`, :data:`APPROXIMATE`,
    :data:`AMBIGUOUS`, :data:`NONE`), the effects named in order, the explanations outside
    the catalogue the data also support, the reason, what would separate tied explanations,
    and where a residual remains."""

    cls: str
    effects: tuple[str, ...]
    reason: str
    alternatives: tuple[str, ...] = ()
    separate_by: str = ""
    where: tuple[str, ...] = ()

    @property
    def effect(self) -> str | None:
        return self.effects[0] if self.effects else None

    def to_dict(self) -> dict[str, Any]:
        return {"class": self.cls, "effect": self.effect, "effects": list(self.effects),
                "alternatives": list(self.alternatives), "reason": self.reason,
                "separate_by": self.separate_by, "where": list(self.where)}


@dataclass(frozen=True)
class WorkSpent:
    """The simulator's work a diagnosis spent (:func:`spicethermal.engines.meter.metered`):
    network solves, the steps they were done in and their cost, the budget of that cost, and
    why the budget stopped the search ("" when it did not)."""

    solves: int = 0
    budget: int = 0
    stopped: str = ""
    steps: int = 0
    cost: int = 0


@dataclass(frozen=True, eq=False)
class Diagnosis(JsonDocument):
    """What :func:`~spicethermal.analysis.diagnose.diagnose` found. ``str()`` is the text
    report, :meth:`to_dict` the ``spicethermal-diagnosis/9`` document, :meth:`plot` the
    figures. ``noise_k`` is the last estimate, ``baseline_noise_k`` the baseline's."""

    source: str
    noise_k: Mapping[str, float]
    baseline: Comparison
    baseline_fit: ModelFit
    baseline_model: ThermalModel
    steps: tuple[Step, ...]
    verdict: Verdict
    candidates: tuple[Candidate, ...] = ()
    skipped: Mapping[str, str] = field(default_factory=dict)
    n_points: int = 0
    work: int = 0
    elapsed_s: float = 0.0
    where: tuple[str, ...] = ()
    spent: WorkSpent = field(default_factory=WorkSpent)
    #: The best further candidate the search refused because it leaves a structured residual
    #: too (weighed on the last step's model), or None ...
    refused: Candidate | None = None
    #: ... and how much it lowers the criterion weighed under the correlation of that
    #: residual (:func:`.rules.correlated_gain`).
    refused_weighed: float = 0.0
    baseline_noise_k: Mapping[str, float] = field(default_factory=dict)

    # -- views -------------------------------------------------------------------------------
    @property
    def verdict_effect(self) -> str | None:
        return self.verdict.effect

    @property
    def effects(self) -> list[str]:
        """The effects named, in order."""
        return list(self.verdict.effects)

    @property
    def final(self) -> Comparison:
        """The comparison with the last step's model (the baseline's when none)."""
        return self.steps[-1].comparison if self.steps else self.baseline

    @property
    def final_fit(self) -> ModelFit:
        return last_model(self.steps, self.baseline_fit)

    @property
    def best(self) -> Candidate | None:
        """The first step's chosen candidate when an effect is named."""
        return self.steps[0].chosen if self.steps and self.verdict.effects else None

    def model(self) -> ThermalModel:
        """The model after the last step: its ladder (Foster) and every effect fitted."""
        fit = self.final_fit
        base = self.baseline_model
        provenance = {**base.provenance, "diagnosis": self.verdict.cls,
                      "effects": list(self.verdict.effects)}
        return ThermalModel(fit.foster, fit.effects, base.reference, provenance)

    def staircase(self) -> str:
        """The pooled RMS after each step, e.g. ``baseline 0.38 K → +temperature-coefficient
        (junction) 0.05 K (7.6×)``."""
        parts = [f"baseline {self.baseline.rms_k:.3g} K"]
        parts += [f"+{s.chosen.name} ({s.chosen.effect.form}) {s.comparison.rms_k:.3g} K "
                  f"({s.chosen.improvement:.3g}×)" for s in self.steps]
        return " → ".join(parts)

    def plot(self, out_dir: str) -> list:
        """The figures (PNG files in ``out_dir``): residuals before and after, the
        candidates, the staircase."""
        from ..viz.plots import diagnosis_figures

        return diagnosis_figures(self, out_dir)

    # -- document -------------------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        """The ``spicethermal-diagnosis/9`` document."""
        worst = [{"dataset": p.dataset, "at": dict(p.at), "residual_k": p.residual_k}
                 for p in self.baseline.worst(WORST_POINTS)]
        fit = self.final_fit
        return {"format": DIAGNOSIS_FORMAT, "source": self.source,
                "noise_k": dict(self.noise_k), "points": self.n_points,
                "baseline": {"order": self.baseline_fit.ladder.order,
                             "noise_k": dict(self.baseline_noise_k or self.noise_k),
                             "rms_k": _finite(self.baseline.rms_k),
                             "max_abs_k": _finite(self.baseline.max_abs_k),
                             "chi2": {k: _finite(v) for k, v in self.baseline_fit.chi2.items()},
                             "worst": worst, "where": list(self.where)},
                "candidates": [c.to_dict() for c in self.candidates],
                "steps": [s.to_dict() for s in self.steps],
                "final": {"rms_k": _finite(self.final.rms_k),
                          "max_abs_k": _finite(self.final.max_abs_k),
                          "chi2": {k: _finite(v) for k, v in fit.chi2.items()}},
                "verdict": self.verdict.to_dict(),
                "refused": {**self.refused.to_dict(),
                            "weighed_delta_bic": _finite(self.refused_weighed)}
                if self.refused is not None else None,
                "skipped": dict(self.skipped), "work": {"rows": self.work,
                                                  "solves": self.spent.solves,
                                                  "steps": self.spent.steps,
                                                  "cost": self.spent.cost,
                                                  "budget": self.spent.budget,
                                                  "stopped": self.spent.stopped}}

    def __str__(self) -> str:
        b = self.baseline_fit
        sets = ", ".join(f"{n} ({len(self.baseline.dataset(n).points)})"
                         for n in self.baseline.datasets)
        lines = [f"diagnosis of {self.source}: {self.n_points} points in {sets}",
                 "noise (from each data set's own scatter, the last estimate): "
                 + ", ".join(f"{n} {v:.3g} K" for n, v in self.noise_k.items()),
                 f"baseline (linear {b.ladder.order}-stage ladder fitted to every data set"
                 + (f" + {', '.join(e.name for e in b.effects)}" if b.effects else "")
                 + f"): RMS {self.baseline.rms_k:.3g} K, worst {self.baseline.max_abs_k:.3g} K",
                 "where it fails:"]
        lines += [f"  {s}" for s in self.where] or ["  nowhere beyond the noise"]
        lines.append("worst points:")
        for p in self.baseline.worst(WORST_POINTS):
            lines.append(f"  {p.dataset:12s} {_at_text(p.at):24s} {p.residual_k:+8.3f} K")
        if self.candidates:
            lines.append("candidates (best first; ΔBIC against the baseline, positive is "
                         "better; pooled RMS; share of the misfit beyond the noise removed):")
        for c in self.candidates:
            kind = "" if c.catalogued else " [not in the catalogue: never named]"
            lines.append(f"  {c.name:24s} ΔBIC {c.delta_bic:+9.1f}  RMS {c.rms_k:.3g} K  "
                         f"{c.improvement:5.2f}×  explains {100 * max(c.explained, 0):3.0f} %  "
                         f"form {c.effect.form}: {c.evidence}{kind}")
        for name, why in self.skipped.items():
            lines.append(f"  {name:24s} not tried: {why}")
        for i, s in enumerate(self.steps, 1):
            tied = (f" (as well: {', '.join(t.name for t in s.tied)})" if s.tied else "")
            dropped = (f"; {', '.join(s.dropped)} no longer needed" if s.dropped else "")
            lines.append(f"step {i}: +{s.chosen.name} ({s.chosen.effect.form}) {s.status}"
                         f"{tied}, ΔBIC {s.chosen.delta_bic:+.1f}, explains "
                         f"{100 * max(s.chosen.explained, 0):.0f} %{dropped}")
        lines.append(f"RMS staircase: {self.staircase()}")
        v = self.verdict
        lines.append(f"verdict: {v.cls}" + (f" — {', '.join(v.effects)}" if v.effects else "")
                     + f": {v.reason}")
        if v.separate_by:
            lines.append(f"to tell them apart: {v.separate_by}")
        if self.steps:
            final = self.final
            lines.append(f"error before → after: RMS {self.baseline.rms_k:.3g} → "
                         f"{final.rms_k:.3g} K, worst {self.baseline.max_abs_k:.3g} → "
                         f"{final.max_abs_k:.3g} K")
            for name, sub in self.baseline.by_dataset().items():
                lines.append(f"  {name:12s} {sub.rms_k:8.3f} → "
                             f"{final.dataset(name).rms_k:8.3f} K")
        lines.append(f"(work: {self.work} model evaluations, {self.spent.solves:,} network "
                     f"solves in {self.spent.steps:,} steps, a cost of {self.spent.cost:,} of a "
                     f"budget of {self.spent.budget:,}, {self.elapsed_s:.1f} s)")
        return "\n".join(lines)


def _finite(x: float) -> float | None:
    x = float(x)
    return x if math.isfinite(x) else None


def _at_text(at: Mapping[str, float]) -> str:
    if "freq_hz" in at:
        return f"{at['freq_hz'] / 1e3:g} kHz, D = {100 * at['duty']:g} %"
    if "temp_c" in at:
        return f"{at['temp_c']:g} °C ({CALIBRATION})"
    if "power_w" in at:
        return f"{at['power_w']:.3g} W ({STEADY})"
    return f"t = {fmt_time(at['t_s'])}"
