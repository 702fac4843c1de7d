"""The swap of a first effect that took up the second one's signature: the first two steps
again with another device effect first (:func:`swap_first`), or the first step again when it
led to a dead end (:func:`swap_dead_end`). :func:`~spicethermal.analysis.diagnose.diagnose`
calls them."""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping, Sequence

from ..effects import Effect
from ..fit.effectfit import BundleData
from .candidates import candidates
from .compare import Comparison
from .diagnosis import Candidate, Step
from .refits import refit_step
from .verdict import MIN_BIC_DROP, at_noise, criterion, decisive

__all__ = ["SWAPPABLE", "swap_dead_end", "swap_first"]

#: Device effects that can pass for one another at the first step (each changes how the
#: heat flows through the device): when the first step took one and the second step found
#: another effect, the others that were decisive at the first step are tried in its place
#: (:func:`swap_first`).
SWAPPABLE = ("temperature-coefficient", "phase-change")


def swap_first(data: BundleData, steps: Sequence[Step], first: Sequence[Candidate],
               base: Comparison, noise: Mapping[str, float],
               budget_s: float) -> list[Step] | None:
    """The first two steps again with the first effect swapped for another device effect of
    :data:`SWAPPABLE` that was decisive at the first step too, or ``None``.

    A first effect chosen greedily can take up the signature of the second: a phase change
    took the first milliseconds that a transient proportional to the power corrupts, and was
    chosen over the temperature coefficient that fits far closer once the transient is found
    (seed 23's draw 013 of the random validation set). For each alternative, its own
    first-step candidate, the second step is fitted again on top of it, for the second
    effect only (:func:`candidates`, every form, within ``budget_s`` of work): the
    swap is taken when that is decisive on top of the alternative and the model with both has
    a criterion lower by :data:`MIN_BIC_DROP` than the first two steps'."""
    one, two = steps[0].chosen, steps[1].chosen
    bic_now = criterion(two.comparison, noise, one.n_params + two.n_params)
    for alt, on_alt in _alternatives(steps[0], first, base, noise, (two.effect.name,)):
        def closer(new: Candidate, alt: Candidate = alt) -> bool:
            return bic_now - criterion(new.comparison, noise,
                                       alt.n_params + new.n_params) >= MIN_BIC_DROP

        second = _second_step(data, alt, on_alt, [two.effect.name], noise, budget_s, closer)
        if second is None:
            continue
        new, cands, model_effects = second
        return [Step(alt, steps[0].candidates, tuple(on_alt)),
                Step(new, tuple(cands), tuple(model_effects))]
    return None


def _alternatives(step: Step, first: Sequence[Candidate], base: Comparison,
                  noise: Mapping[str, float], also_not: tuple[str, ...] = ()
                  ) -> Iterator[tuple[Candidate, list[Effect]]]:
    """The other device effects of :data:`SWAPPABLE` (not ``also_not``) that were decisive and
    not contradicted at the first step, each with the model's effects with it in place of the
    step's effect."""
    one = step.chosen
    if one.effect.name not in SWAPPABLE:
        return
    before = [e for e in step.effects if e.name != one.effect.name]
    bic0 = criterion(base, noise, 0)
    for alt in first:
        if alt.effect.name in SWAPPABLE and alt.effect.name not in (one.effect.name, *also_not) \
                and not alt.contradicted and decisive(alt, bic0):
            yield alt, list(alt.model_effects) or [*before, alt.effect]


def _second_step(data: BundleData, alt: Candidate, on_alt: list[Effect], names: Sequence[str],
                 noise: Mapping[str, float], budget_s: float,
                 keep: Callable[[Candidate], bool] = lambda _c: True
                 ) -> tuple[Candidate, list[Candidate], list[Effect]] | None:
    """The best decisive candidate of ``names`` on top of ``alt`` (then refitted with the
    effects before it), the candidates weighed and the model's effects; ``None`` when none is
    or ``keep`` rejects it."""
    cands = candidates(data, alt.ladder, on_alt, names, alt.comparison, noise,
                       lambda _text: None, {}, budget_s, step=2)
    new = next((c for c in cands if decisive(c, alt.bic) and not c.contradicted), None)
    if new is None or not keep(new):
        return None
    model_effects = list(new.model_effects) or [*on_alt, new.effect]
    if not new.model_effects:
        new, model_effects = refit_step(data, new, model_effects, alt.comparison, noise)
    return new, cands, model_effects


def swap_dead_end(data: BundleData, step: Step, first: Sequence[Candidate], base: Comparison,
                  names: Sequence[str], noise: Mapping[str, float],
                  budget_s: float) -> list[Step] | None:
    """The first step again with another device effect of :data:`SWAPPABLE` that was decisive
    at the first step too, alone or with a second step on top of it, or ``None``: for a first
    effect that leaves a residual beyond the noise that no second effect lowers decisively.

    Each device effect can mimic the other: a latent-heat band, with its ladder refitted on
    one more stage, explained 97 % of a strong temperature coefficient on the inner layers and
    left the rest to nothing, where the coefficient alone brings every data set to its noise
    (temperature-coefficient/inner-layers/strong of the validation set; with the coefficient's
    budget cut, an electrical transient the case does not have took up what it left). The swap
    is taken only when the alternative alone, or with a second effect (any of ``names`` but
    the effect it replaces, :func:`candidates` within ``budget_s`` of work), leaves every data
    set at its noise. The replaced effect does not come back second: that pair was weighed
    already, in the other order, and its second effect was not decisive (a 0.49 J plateau at a
    diode's node 1, 99 % of the misfit, got a junction coefficient of 56 % put before it: seed
    53's draw 012 of the random validation set)."""
    for alt, on_alt in _alternatives(step, first, base, noise):
        if at_noise(alt.comparison, noise):  # nothing is left for a second effect to take
            return [Step(alt, step.candidates, tuple(on_alt))]
        taken = {e.name for e in on_alt} | {step.chosen.effect.name}
        second = _second_step(data, alt, on_alt, [n for n in names if n not in taken], noise,
                              budget_s)
        if second is not None and at_noise(second[0].comparison, noise):
            new, cands, model_effects = second
            return [Step(alt, step.candidates, tuple(on_alt)),
                    Step(new, tuple(cands), tuple(model_effects))]
    return None
