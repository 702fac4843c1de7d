"""The batch report: figures of the population and the HTML page (``OUTDIR/index.html``, laid
out by the project's report template, :func:`spicethermal.report.html.render`)."""

from __future__ import annotations

from collections import Counter
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..io.files import atomic_write_text
from ..report.html import Section, render
from ..viz.plots import new_figure, save_figure
from .spread import PERCENTILES, RESOLUTION, Z_OUTLIER, Outlier, robust_scale

__all__ = ["fig_rth_histogram", "fig_verdicts", "fig_zth_population", "verdict_counts",
           "write_page"]

_GREY, _RED, _BLUE = "#9aa5b1", "#c53030", "#2b6cb0"


def fig_rth_histogram(rth: np.ndarray, flagged: Sequence[int], path: Path) -> Path:
    """Histogram of Rth over the population, outliers in red."""
    fig = new_figure(6.4, 3.6)
    ax = fig.add_subplot()
    bins = np.histogram_bin_edges(rth, bins=min(40, max(8, rth.size // 4)))
    mask = np.zeros(rth.size, dtype=bool)
    mask[list(flagged)] = True
    ax.hist([rth[~mask], rth[mask]], bins=bins, stacked=True, color=[_BLUE, _RED],
            label=["devices", "outliers"])
    ax.axvline(float(np.median(rth)), color="k", lw=1, ls="--", label="median")
    ax.set_xlabel("Rth (K/W)")
    ax.set_ylabel("devices")
    ax.legend(frameon=False)
    return save_figure(fig, path)


def fig_zth_population(curves: Sequence[dict], flagged: Sequence[int], typical: Any,
                       worst: Any, path: Path) -> Path:
    """Every measured Zth(t) (grey, outliers red) with the typical and worst-case ladders."""
    fig = new_figure(6.4, 4.2)
    ax = fig.add_subplot()
    for i, c in enumerate(curves):
        bad = i in flagged
        ax.semilogx(c["t_s"], c["zth_k_per_w"], color=_RED if bad else _GREY,
                    lw=1.0 if bad else 0.5, alpha=0.9 if bad else 0.5, zorder=3 if bad else 1)
    lo = min(c["t_s"][0] for c in curves)
    hi = max(c["t_s"][-1] for c in curves)
    t = np.logspace(np.log10(lo), np.log10(hi), 300)
    for model, label, style in ((typical, "typical ladder", "-"), (worst, "worst-case ladder",
                                                                    "--")):
        if model is not None:
            ax.semilogx(t, model.ladder.zth(t), color="k", lw=1.8, ls=style, label=label,
                        zorder=4)
    ax.plot([], [], color=_GREY, label="devices")
    if flagged:
        ax.plot([], [], color=_RED, label="outliers")
    ax.set_xlabel("t (s)")
    ax.set_ylabel("Zth (K/W)")
    ax.legend(frameon=False, loc="upper left")
    return save_figure(fig, path)


def fig_verdicts(counts: dict[str, int], path: Path) -> Path:
    """Bar chart of the diagnosis verdicts."""
    names = sorted(counts, key=lambda k: (-counts[k], k))
    fig = new_figure(9.0, 1.0 + 0.3 * len(names))
    ax = fig.add_subplot()
    ax.barh(names, [counts[k] for k in names], color=_BLUE)
    ax.invert_yaxis()
    ax.set_xlabel("devices")
    return save_figure(fig, path)


def write_page(out: Path, results: Sequence[dict], good: Sequence[dict],
               outliers: Sequence[Outlier], typical: Any, worst: Any,
               pwm: Sequence[dict], elapsed_s: float, power_origin: str = "") -> Path:
    """Figures into ``out/figures`` and the page ``out/index.html``; returns the page."""

    rows = [r["row"] for r in results]
    rth = np.array([r["row"]["rth_k_per_w"] for r in good], dtype=float)
    flagged = [o.index for o in outliers]
    figs = out / "figures"
    counts = dict(verdict_counts(rows))
    errors = [r for r in rows if r.get("error")]
    twins = [r for r in rows if r.get("duplicate_of")]
    summary = [f"{len(rows)} inputs: {len(good)} characterized, {len(errors)} with an error, "
               f"{len(twins)} duplicate{'' if len(twins) == 1 else 's'} (the same content as "
               f"another input, counted once), {len(outliers)} outlier"
               f"{'' if len(outliers) == 1 else 's'} (robust |z| ≥ {Z_OUTLIER:g})."]
    sections = []
    if twins:
        same = Section("duplicates", "Duplicate inputs")
        same.paragraphs.append("Inputs with the same content hash (sha256 of results.csv): "
                               "one measurement given twice is not two devices, so only the "
                               "first is in the population's statistics.")
        same.table(["input", "source", "same content as"],
                   [[r["name"], r["source"], r["duplicate_of"]] for r in twins])
        sections.append(same)
    if good:
        med = float(np.median(rth))
        s = float(robust_scale(rth, RESOLUTION * med))
        floor = " — the floor, 1 % of the median" if s <= RESOLUTION * med else ""
        summary.append(f"Rth median {med:.4g} K/W, robust σ {s:.3g} K/W "
                       f"({100 * s / med:.1f} %{floor}), range {rth.min():.4g} … "
                       f"{rth.max():.4g} K/W.")
        dist = Section("distribution", "Rth and Zth(t) over the population")
        dist.figure(fig_rth_histogram(rth, flagged, figs / "rth_histogram.png"), out,
                    "Rth of every device (outliers in red).")
        dist.figure(fig_zth_population([r["curve"] for r in good if r.get("curve")], flagged,
                                       typical, worst, figs / "zth_population.png"), out,
                    "Measured Zth(t) of every device with the typical (median) and worst-case "
                    "(maximum) ladders fitted to the envelope of the devices that are not "
                    "outliers.")
        sections.append(dist)
    diag = Section("verdicts", "Diagnosis verdicts")
    diag.table(["verdict", "devices"], sorted(counts.items(), key=lambda kv: -kv[1]))
    diag.figure(fig_verdicts(counts, figs / "verdicts.png"), out, "Verdict of every device.")
    sections.append(diag)
    odd = Section("outliers", "Outliers and why they stand out")
    odd.paragraphs.append("Robust z-scores (median and MAD) of Rth and of the heat path: the "
                          "cumulative structure function of each fitted ladder, compared with "
                          "the population's at fixed cumulative capacitance.")
    odd.table(["device", "Rth (K/W)", "z Rth", "z path", "reason"],
              [[good[o.index]["row"]["name"], f"{rth[o.index]:.4g}", f"{o.z_rth:+.1f}",
                f"{o.z_path:+.1f}", o.reason] for o in outliers])
    sections.append(odd)
    if typical is not None:
        spread = Section("spread", "Typical and worst-case models")
        spread.table(["model", "Rth (K/W)", "stages", "time constants (s)", "files"],
                     [[label, f"{m.rth:.4g}", m.ladder.order,
                       ", ".join(f"{t:.3g}" for t in m.ladder.time_constants()),
                       f"spread/{name}.lib, spread/{name}.json"]
                      for label, name, m in (("typical (median Zth)", "typical", typical),
                                             ("worst case (maximum Zth)", "worst", worst))])
        sections.append(spread)
    if pwm:
        table = Section("pwm", "PWM junction peak over the population")
        table.paragraphs.append(f"Periodic steady-state peak rise (K) at {pwm[0]['power_w']:.4g} W "
                                f"({power_origin or 'given'}) of every device's ladder; "
                                f"percentiles over the devices (pwm_peaks.csv).")
        table.table(["f (Hz)", "duty", *[f"p{p} (K)" for p in PERCENTILES], "max (K)"],
                    [[f"{r['freq_hz']:g}", f"{r['duty']:g}",
                      *[f"{r[f'peak_p{p}_k']:.4g}" for p in PERCENTILES],
                      f"{r['peak_max_k']:.4g}"] for r in pwm])
        sections.append(table)
    if errors:
        bad = Section("errors", "Inputs with an error")
        bad.table(["source", "error"], [[r["source"], r["error"]] for r in errors])
        sections.append(bad)
    every = Section("devices", "Every device")
    every.paragraphs.append("The full table with every column is results.csv.")
    every.table(["device", "Rth (K/W)", "order", "fit RMS (K/W)", "verdict", "wall (s)",
                 "duplicate of"],
                [[r["name"], _num(r.get("rth_k_per_w")), r.get("order") or "",
                  _num(r.get("fit_rms_k_per_w"), 2), r.get("verdict") or "",
                  _num(r.get("wall_s"), 2), r.get("duplicate_of") or ""] for r in rows])
    sections.append(every)
    html = render("Batch characterization", f"{len(rows)} inputs", summary, sections,
                  elapsed_s)
    return atomic_write_text(out / "index.html", html)


def verdict_counts(rows: Sequence[dict[str, Any]]) -> Counter:
    """How many devices got each verdict (``error`` for failed rows, ``not diagnosed``).

    >>> dict(verdict_counts([{"verdict": "none"}, {"error": "x"}, {"verdict": ""}]))
    {'none': 1, 'error': 1, 'not diagnosed': 1}
    """
    return Counter("error" if r.get("error") else (r.get("verdict") or "not diagnosed")
                   for r in rows)


def _num(x: Any, digits: int = 4) -> str:
    return "" if x is None or x == "" else f"{float(x):.{digits}g}"
