"""The verdict of a diagnosis's steps (docs/diagnosis.md, §7): whether a model is at the
noise, which class the steps earn, and the reasons, generated from the numbers.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from typing import TYPE_CHECKING

from ..fit.joint import penalty
from .compare import comparison_of
from .diagnosis import AMBIGUOUS, APPROXIMATE, NAMED, NONE, RIVAL, UNSHOWN, Verdict, last_model
from .rules import MIN_APPROXIMATE, beyond_noise, correlated_gain, explained
from .where import localise

if TYPE_CHECKING:  # pragma: no cover
    from ..fit.joint import ModelFit
    from ..fit.measurement import BundleData
    from .diagnosis import Step

__all__ = ["beyond", "short", "verdict", "weighed_fall"]


def beyond(data: BundleData, fit: ModelFit) -> dict[str, bool]:
    """Whether ``fit`` leaves each data set of ``data`` beyond its noise."""
    return {n: beyond_noise(fit.chi2[n], data.measured(n).size,
                            data.measured(n) - fit.predictions[n]) for n in data.datasets}


def short(data: BundleData, fit: ModelFit) -> bool:
    """Whether ``fit`` leaves a data set of ``data`` beyond its noise."""
    return any(beyond(data, fit).values())


def weighed_fall(data: BundleData, before: ModelFit, after: ModelFit, noise: dict) -> float:
    """How much ``after`` lowers the criterion from ``before`` when each data set's fall of
    χ² is weighed under the correlation of the misfit ``after`` leaves
    (:func:`.rules.correlated_gain`)."""
    fall = sum(correlated_gain((before.predictions[n] - data.measured(n)) / noise[n],
                               (after.predictions[n] - data.measured(n)) / noise[n])
               for n in data.datasets)
    return fall - penalty(after.n_params - before.n_params, sum(data.sizes().values()))


def verdict(data: BundleData, base: ModelFit, steps: Sequence[Step], noise: dict,
            note: str = "", cut: bool = False) -> Verdict:
    """The verdict of the steps (docs/diagnosis.md §7).

    Parameters
    ----------
    data : BundleData
    base : ModelFit
    steps : sequence of Step
    noise : dict
    note : str
        What else the search says: why its first step is not the best candidate alone, why
        the work budget stopped it (ends the reason; with no step, it is the reason).
    cut : bool
        Whether the budget stopped the search (what is left is then not said to be elsewhere).

    Returns
    -------
    Verdict
    """
    found = _judge(data, base, steps, noise, note, cut)
    return replace(found, reason=f"{found.reason}; {note}") if note and steps else found


def _judge(data: BundleData, base: ModelFit, steps: Sequence[Step], noise: dict,
           note: str, cut: bool) -> Verdict:
    final = last_model(steps, base)
    kept = {e.name for e in final.effects}
    live = [s for s in steps if s.chosen.name in kept]
    named = [s for s in live if s.status in (NAMED, AMBIGUOUS)]
    rivals = [s for s in live if s.status == RIVAL]
    alternatives = tuple(dict.fromkeys(
        c.name for s in live for c in (s.chosen, *s.tied) if not c.catalogued))
    over = beyond(data, final)
    left = tuple(localise(comparison_of(data, final.predictions), noise, over))
    share = explained(base.chi2, final.chi2, data.sizes())
    if not short(data, base):
        return Verdict(NONE, (), "the linear ladder fits every data set within its noise: no "
                       "effect is missing")
    if note and not steps:
        return Verdict(NONE, (), f"{note}: nothing is named; the error sits in "
                       + "; and in ".join(left[:2]), where=left)
    if not named:
        unshown = [s for s in live if s.status == UNSHOWN]
        why = ("no catalogued effect lowers the criterion decisively" if not live else
               _unshown_reason(unshown) if unshown else _rival_reason(rivals, live))
        if unshown:  # the error is what is left without the effects the data do not show
            first = steps.index(unshown[0])
            before = steps[first - 1].model if first else base
            left = tuple(localise(comparison_of(data, before.predictions), noise,
                                  beyond(data, before)))
        return Verdict(NONE, (), f"{why}; not in the catalogue: the error sits in "
                       + ("; and in ".join(left[:2]) or "no data set beyond its noise"),
                       alternatives, _separate(live), left)
    effects = tuple(dict.fromkeys(
        n for s in named for n in (s.chosen.name, *(t.name for t in s.tied if t.catalogued))))
    separate = _separate(named)
    held = [s for s in live if s.status == UNSHOWN]  # in the model, not named: say why
    unshown_text = f"; in the model also {_unshown_reason(held)}" if held else ""
    if rivals:
        return Verdict(NONE, (), f"{', '.join(effects)} would explain part of it, but "
                       f"{_rival_reason(rivals, live)}; not named: the cause is perhaps not in "
                       "the catalogue", alternatives, separate, left)
    ambiguous = any(s.status == AMBIGUOUS for s in named)
    if not any(over.values()):
        return Verdict(AMBIGUOUS if ambiguous else NAMED, effects,
                       _named_reason(named, share, "every data set is at its noise after it")
                       + unshown_text,
                       alternatives, separate)
    if share >= MIN_APPROXIMATE:
        return Verdict(AMBIGUOUS if ambiguous else APPROXIMATE, effects,
                       _named_reason(named, share, "its catalogued form is approximate: it "
                                     "leaves " + "; and ".join(left[:2])) + unshown_text,
                       alternatives, separate, left)
    return Verdict(NONE, (), f"{', '.join(effects)} would remove only {100 * share:.0f} % of "
                   f"the misfit beyond the noise (an approximate name needs "
                   f"{100 * MIN_APPROXIMATE:.0f} %) and leave " + "; and ".join(left[:2])
                   + ("" if cut else "; not in the catalogue"), alternatives, separate, left)


def _named_reason(named: Sequence[Step], share: float, tail: str) -> str:
    parts = []
    for s in named:
        c = s.chosen
        names = [t.name for t in s.tied if t.catalogued]
        names += [f"outside the catalogue, {t.evidence}" for t in s.tied if not t.catalogued]
        also = f" (or {'; or '.join(names)}: as likely)" if names else ""
        parts.append(f"{c.name}{also} lowers the criterion by {c.delta_bic:.1f} and removes "
                     f"{100 * max(c.explained, 0):.0f} % of the misfit beyond the noise "
                     f"({c.evidence})")
    return f"{'; then '.join(parts)}; together {100 * share:.0f} %; {tail}"


def _rival_reason(rivals: Sequence[Step], live: Sequence[Step]) -> str:
    texts = [t.evidence for s in rivals for t in (s.chosen, *s.tied) if not t.catalogued]
    return ("an explanation outside the catalogue fits as well or better: "
            + "; ".join(dict.fromkeys(texts))) if texts else "nothing decisive"


def _unshown_reason(steps: Sequence[Step]) -> str:
    return "; ".join(f"{s.chosen.name} would explain it ({s.chosen.evidence}), but {s.why}"
                     for s in steps)


def _separate(steps: Sequence[Step]) -> str:
    """What would tell tied explanations apart (their traits say)."""
    out = []
    for s in steps:
        for t in s.tied:
            a, b = s.chosen.effect.plugin, t.effect.plugin
            how = a.traits.confusable_with.get(b.name) or b.traits.confusable_with.get(a.name)
            out.append(f"{a.name} or {b.name}: "
                       + (how or "a data set that shows one and not the other"))
        if s.status == UNSHOWN:
            traits = s.chosen.effect.plugin.traits
            needs = " and ".join(sorted(traits.needs))
            out.append(f"{s.chosen.name}: " + (f"a {needs} over the temperatures reached"
                                               if needs else traits.shown_alone_by))
    return "; ".join(out)
