"""Figures of a diagnosis: residuals per data set before and after an effect, the candidates,
the RMS staircase of the iterative diagnosis and the paper's Table 2 analysis.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.axes import Axes

    from ..analysis.compare import Comparison

from .base import axes, new_figure, save_figure


class Diagnosis(Protocol):
    """What the figures read of a diagnosis (:class:`spicethermal.analysis.diagnosis.Diagnosis`:
    the figures know its shape, not its module, which draws itself through them)."""

    baseline: Comparison
    candidates: Sequence[Any]
    steps: Sequence[Any]
    verdict: Any
    noise_k: Mapping[str, float]

    @property
    def effects(self) -> list[str]: ...

    @property
    def final(self) -> Comparison: ...

    @property
    def best(self) -> Any: ...


class TableAnalysis(Protocol):
    """What the figure reads of a measured-vs-simulated table's analysis
    (:class:`spicethermal.analysis.table2.TableAnalysis`)."""

    freq_hz: Any
    duty: Any
    exp_k: Any
    model_k: Any
    window_s: float
    mean_model: Mapping[str, tuple[float, float]]
    paper_window_pred_k: Any
    early_pred_k: Any

    @property
    def delta_k(self) -> Any: ...


# ---------------------------------------------- diagnosis: before/after residuals (diagnose.py)
def _residual_axes_style(ax: Axes, dataset: str) -> None:
    ax.axhline(0.0, color="0.5", lw=0.8)
    ax.grid(True, which="both", alpha=0.3)
    if dataset == "pwm":
        ax.set_xscale("log")
        ax.set_xlabel("PWM frequency (Hz)")
    elif dataset == "calibration":
        ax.set_xlabel("calibration temperature (°C)")
    elif dataset == "steady":
        ax.set_xlabel("power before the cut (W)")
    else:
        ax.set_xscale("log")
        ax.set_xlabel("time after the cut (s)")
    ax.set_ylabel("measured − model (K)")


def plot_dataset_residuals(comparison: Comparison, dataset: str, ax: Axes | None = None,
                           color: str | None = None) -> Axes:
    """Residuals (K) of one data set of a :class:`~spicethermal.analysis.compare.Comparison`:
    cooling curves against log time, the PWM grid against frequency (one line per duty), the
    calibration against temperature.

    >>> from spicethermal.analysis.compare import Comparison, ComparisonPoint
    >>> c = Comparison((ComparisonPoint("cooling_1", {"t_s": 1e-3}, 30.0, 29.5),
    ...                 ComparisonPoint("cooling_1", {"t_s": 1e-2}, 29.0, 29.1)))
    >>> plot_dataset_residuals(c, "cooling_1").get_ylabel()
    'measured − model (K)'
    """
    ax = axes(ax)
    sub = comparison.dataset(dataset)
    r = sub.residuals_k
    if dataset == "pwm":
        duties = sorted({p.at["duty"] for p in sub.points})
        for k, d in enumerate(duties):
            pts = sorted((p for p in sub.points if p.at["duty"] == d),
                         key=lambda p: p.at["freq_hz"])
            ax.plot([p.at["freq_hz"] for p in pts], [p.residual_k for p in pts], "o-",
                    color=f"C{k}", ms=4, label=f"D = {100 * d:g} %")
        if duties:
            ax.legend(fontsize=7)
    elif dataset == "calibration":
        ax.plot([p.at["temp_c"] for p in sub.points], r, "o-", color=color or "C3", ms=4)
    elif dataset == "steady":
        ax.plot([p.at["power_w"] for p in sub.points], r, "s", color=color or "C4", ms=5)
    else:
        ax.plot([p.at["t_s"] for p in sub.points], r, "o-", color=color or "C0", ms=3, lw=0.8)
    _residual_axes_style(ax, dataset)
    return ax


def fig_before_after(before: Comparison, after: Comparison, path: str | os.PathLike,
                     titles: Sequence[str] = ("before", "after")) -> Path:
    """Residuals of every data set, before (left) and after (right) an effect is added, one
    row per data set with a shared vertical scale, so the error can be seen to fall.

    >>> import tempfile, pathlib
    >>> from spicethermal.analysis.compare import Comparison, ComparisonPoint
    >>> b = Comparison((ComparisonPoint("pwm", {"freq_hz": 1e3, "duty": 0.5}, 30.0, 31.0),))
    >>> a = Comparison((ComparisonPoint("pwm", {"freq_hz": 1e3, "duty": 0.5}, 30.0, 30.1),))
    >>> fig_before_after(b, a, pathlib.Path(tempfile.mkdtemp()) / "ba.png").exists()
    True
    """
    return fig_stages((before, after), path, titles)


def fig_stages(stages: Sequence[Comparison], path: str | os.PathLike,
               titles: Sequence[str]) -> Path:
    """Residuals of every data set at each stage of a diagnosis (the baseline, then after each
    effect added), one column per stage and one row per data set with a shared vertical
    scale; a data set a stage leaves unchanged is not drawn again.

    >>> import tempfile, pathlib
    >>> from spicethermal.analysis.compare import Comparison, ComparisonPoint
    >>> c = [Comparison((ComparisonPoint("pwm", {"freq_hz": 1e3, "duty": 0.5}, 30.0, m),))
    ...      for m in (31.0, 30.5, 30.1)]
    >>> fig_stages(c, pathlib.Path(tempfile.mkdtemp()) / "s.png", "abc").exists()
    True
    """
    names = list(dict.fromkeys(n for cmp in stages for n in cmp.datasets))
    changed = [n for n in names if any(a.dataset(n) != b.dataset(n)
                                       for a, b in zip(stages, stages[1:], strict=False))]
    names = changed or names  # no row whose every stage is the same
    cols = len(stages)
    fig = new_figure(4.5 * cols, 2.3 * max(len(names), 1) + 0.4)
    axes = fig.subplots(max(len(names), 1), cols, squeeze=False)
    for row, name in enumerate(names):
        lim = 0.0
        for col, (cmp, title) in enumerate(zip(stages, titles, strict=True)):
            ax = axes[row][col]
            sub = cmp.dataset(name)
            if col and sub == stages[col - 1].dataset(name):
                ax.axis("off")
                ax.text(0.5, 0.5, f"{name}: unchanged", ha="center", va="center",
                        transform=ax.transAxes, fontsize=9, color="0.4")
                continue
            plot_dataset_residuals(cmp, name, ax)
            if sub.points:
                lim = max(lim, sub.max_abs_k)
                ax.set_title(f"{title}: {name}, RMS {sub.rms_k:.3g} K", fontsize=9, loc="left")
        for col in range(cols):
            if lim > 0 and axes[row][col].axison:
                axes[row][col].set_ylim(-1.1 * lim, 1.1 * lim)
    return save_figure(fig, path)


def plot_candidates(result: Diagnosis, ax: Axes | None = None) -> Axes:
    """Pooled RMS of the baseline and of every candidate effect (log scale), the verdict's
    candidate highlighted, the improvement written on each bar."""
    ax = axes(ax, 6.4, 3.2)
    names = ["baseline"] + [c.name + ("" if c.catalogued else " (rival)")
                            for c in result.candidates]
    values = [result.baseline.rms_k] + [c.rms_k for c in result.candidates]
    colors = ["0.6"] + ["C2" if c.name in result.effects else "C0" if c.catalogued else "0.8"
                        for c in result.candidates]
    y = np.arange(len(names))[::-1]
    ax.barh(y, values, color=colors)
    for yi, v, c in zip(y[1:], values[1:], result.candidates, strict=True):
        ax.text(v, yi, f" {c.improvement:.1f}×", va="center", fontsize=8)
    ax.set_yticks(y, names, fontsize=8)
    ax.set_xscale("log")
    ax.set_xlabel("RMS over every data set (K)")
    ax.grid(True, axis="x", which="both", alpha=0.3)
    ax.set_title(f"verdict: {result.verdict.cls}"
                 + (f" ({', '.join(result.effects)})" if result.effects else ""),
                 fontsize=10, loc="left")
    return ax


def fig_candidates(result: Diagnosis, path: str | os.PathLike) -> Path:
    """:func:`plot_candidates` as a PNG file."""
    fig = new_figure(6.4, 0.45 * (len(result.candidates) + 1) + 1.2)
    plot_candidates(result, fig.add_subplot())
    return save_figure(fig, path)


def plot_staircase(result: Diagnosis, ax: Axes | None = None) -> Axes:
    """The RMS error falling with each effect added by the iterative diagnosis (log scale),
    each step labelled with its effect, form and improvement; the noise level dashed."""
    ax = axes(ax, 6.4, 3.2)
    labels = ["baseline"] + [f"+ {s.chosen.effect.name}\n({s.chosen.effect.form})"
                             for s in result.steps]
    values = [result.baseline.rms_k] + [s.comparison.rms_k for s in result.steps]
    x = np.arange(len(values))
    ax.step(x, values, where="mid", color="C0")
    ax.plot(x, values, "o", color="C0")
    for xi, s in zip(x[1:], result.steps, strict=True):
        ax.annotate(f"{s.chosen.improvement:.3g}×", (xi, s.comparison.rms_k), fontsize=8,
                    textcoords="offset points", xytext=(4, 4))
    noise = float(np.sqrt(np.mean([v ** 2 for v in result.noise_k.values()])))
    ax.axhline(noise, color="0.5", ls="--", lw=1, label=f"noise ≈ {noise:.2g} K")
    ax.set_xticks(x, labels, fontsize=8)
    ax.set_yscale("log")
    ax.set_ylabel("RMS over every data set (K)")
    ax.legend(fontsize="small")
    ax.grid(True, axis="y", which="both", alpha=0.3)
    ax.set_title("error after each added effect", fontsize=10, loc="left")
    return ax


def fig_staircase(result: Diagnosis, path: str | os.PathLike) -> Path:
    """:func:`plot_staircase` as a PNG file."""
    fig = new_figure(6.4, 3.4)
    plot_staircase(result, fig.add_subplot())
    return save_figure(fig, path)


def diagnosis_figures(result: Diagnosis, out_dir: str | os.PathLike) -> list[Path]:
    """The diagnosis figures, written into ``out_dir``: the RMS staircase of the steps
    (``diagnosis_steps.png``), the residuals at the baseline and after each effect found
    (``diagnosis_before_after.png``; with the best candidate when none was found) and the
    candidates (``diagnosis_candidates.png``).
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = [fig_staircase(result, out / "diagnosis_steps.png")]
    if result.steps:
        stages = [result.baseline, *(s.comparison for s in result.steps)]
        titles = ["baseline", *(f"+ {s.chosen.effect.name}" for s in result.steps)]
    else:
        best = result.candidates[0] if result.candidates else None
        stages = [result.baseline] + ([best.comparison] if best is not None else [])
        titles = ["baseline"] + ([f"with {best.effect.name}"] if best is not None else [])
    paths.append(fig_stages(stages, out / "diagnosis_before_after.png", titles))
    if result.candidates:
        paths.append(fig_candidates(result, out / "diagnosis_candidates.png"))
    return paths


def fig_table2_diagnosis(analysis: TableAnalysis, path: str | os.PathLike) -> Path:
    """A measured-vs-simulated PWM table (the paper's Table 2) and the explanations tried:
    (a) both columns against frequency per duty, with the mean rise D·P·Rth; (b) Δ = measured
    − simulated (points) with the sample window's prediction (dashed) and the early-time
    one (dotted)."""
    a = analysis
    fig = new_figure(9.0, 3.8)
    ax1, ax2 = fig.subplots(1, 2)
    km = a.mean_model["measured"][0]
    for k, d in enumerate(sorted(set(a.duty.tolist()))):
        sel = a.duty == d
        order = np.argsort(a.freq_hz[sel])
        f = a.freq_hz[sel][order]
        color = f"C{k}"
        ax1.plot(f, a.exp_k[sel][order], "o-", color=color, ms=4, label=f"measured, D = {d:.0%}")
        ax1.plot(f, a.model_k[sel][order], "s--", color=color, ms=3, mfc="none",
                 label="simulated")
        ax1.axhline(km * d, color=color, lw=0.6, ls=":")
        ax2.plot(f, a.delta_k[sel][order], "o", color=color, ms=5, label=f"Δ, D = {d:.0%}")
        ax2.plot(f, a.paper_window_pred_k[sel][order], "--", color=color, lw=1.2)
        ax2.plot(f, a.early_pred_k[sel][order], ":", color=color, lw=1.2)
    for ax in (ax1, ax2):
        ax.set_xscale("log")
        ax.set_xlabel("PWM frequency (Hz)")
        ax.grid(True, which="both", alpha=0.3)
    ax1.set_ylabel("rise over the reference (K)")
    ax1.set_title("(a) readings; dotted: D·P·Rth", fontsize=9, loc="left")
    ax1.legend(fontsize=6, ncol=2)
    ax2.axhline(0.0, color="0.5", lw=0.8)
    ax2.set_ylabel("measured − simulated (K)")
    ax2.set_title(f"(b) Δ; dashed: {a.window_s * 1e6:g} µs window, dotted: early time",
                  fontsize=9, loc="left")
    ax2.legend(fontsize=7)
    return save_figure(fig, path)
