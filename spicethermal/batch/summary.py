"""The population's summary: outliers, typical and worst-case ladders (model and ``.lib``), the
PWM peak table, the figures and the HTML page, written into a batch's output directory::

    OUTDIR/outliers.csv                  device, Rth, z-scores, where the path departs, reason
    OUTDIR/spread/typical.json, .lib     the median Zth(t) fitted (``TYPICAL``)
    OUTDIR/spread/worst.json, .lib       the maximum Zth(t) fitted (``WORST``)
    OUTDIR/pwm_peaks.csv                 junction peak percentiles over the population
    OUTDIR/index.html, figures/*.png     the report
"""

from __future__ import annotations

import csv
import io
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..io.files import atomic_write_text
from ..model import ThermalModel
from ..spice.lib import export
from .report import write_page
from .spread import (
    PERCENTILES,
    Outlier,
    envelopes,
    find_outliers,
    fit_envelope,
    population_power,
    pwm_peaks,
)

__all__ = ["Summary", "summarize"]


@dataclass(frozen=True)
class Summary:
    """The population's findings (see :func:`summarize`)."""

    outliers: tuple[Outlier, ...]
    names: tuple[str, ...]
    typical: Any
    worst: Any
    pwm: tuple[dict[str, float], ...]
    page: Path
    power_w: float = 1.0
    power_origin: str = ""

    @property
    def outlier_names(self) -> list[str]:
        """Output names of the outlier devices."""
        return [self.names[o.index] for o in self.outliers]


def _csv(rows: Sequence[dict[str, Any]], header: Sequence[str]) -> str:
    text = io.StringIO()
    writer = csv.DictWriter(text, fieldnames=list(header), lineterminator="\n")
    writer.writeheader()
    writer.writerows({k: ("" if r.get(k) is None else r[k]) for k in header} for r in rows)
    return text.getvalue()


def summarize(results: Sequence[dict[str, Any]], out_dir: str | Path, *,
              power_w: float | None = None,
              freqs_hz: Sequence[float] = (100.0, 1e3, 1e4),
              duties: Sequence[float] = (0.1, 0.5, 0.9), dialect: str = "ngspice",
              elapsed_s: float = 0.0) -> Summary:
    """Outliers, envelope ladders, PWM table and report of a batch's ``results`` (records
    ``{"row", "model", "curve"}`` as :func:`~.runner.run_batch` returns them) into ``out_dir``.
    A duplicate input (``duplicate_of``) is counted once; the PWM table is at ``power_w``,
    default the devices' own (:func:`~.spread.population_power`).
    """
    out = Path(out_dir)
    good = [r for r in results if not r["row"].get("error") and r.get("model")
            and not r["row"].get("duplicate_of")]
    models = [ThermalModel.from_dict(r["model"], r["row"]["name"]) for r in good]
    names = tuple(r["row"]["name"] for r in good)
    rth = np.array([m.rth for m in models])
    outliers = tuple(find_outliers(rth, [m.ladder for m in models])) if good else ()
    flagged = {o.index for o in outliers}
    rows = [{"name": names[o.index], "device": good[o.index]["row"]["device"],
             "rth_k_per_w": round(float(rth[o.index]), 6), "z_rth": round(o.z_rth, 2),
             "z_path": round(o.z_path, 2), "excess_k_per_w": round(o.excess_k_per_w, 6),
             "departs_c_j_per_k": o.departs_c_j_per_k, "reason": o.reason} for o in outliers]
    atomic_write_text(out / "outliers.csv", _csv(rows, ["name", "device", "rth_k_per_w", "z_rth",
                                                         "z_path", "excess_k_per_w",
                                                         "departs_c_j_per_k", "reason"]))
    typical = worst = None
    inliers = [i for i in range(len(good)) if i not in flagged and good[i].get("curve")]
    if len(inliers) >= 2:
        grid, z_typ, z_max = envelopes([good[i]["curve"] for i in inliers])
        r_in = rth[inliers]
        typical = fit_envelope(grid, z_typ, float(np.median(r_in)), "typical (median Zth)")
        worst = fit_envelope(grid, z_max, float(np.max(r_in)), "worst case (maximum Zth)")
        for model, name in ((typical, "typical"), (worst, "worst")):
            model.save(out / "spread" / f"{name}.json")
            export(model, out / "spread" / f"{name}.lib", dialect, None, name.upper())
    power_w, origin = population_power([r["row"].get("power_w") for r in good], power_w)
    pwm = tuple(pwm_peaks([m.ladder for m in models], power_w, freqs_hz, duties)) if good else ()
    header = ["freq_hz", "duty", "power_w", "devices",
              *[f"peak_p{p}_k" for p in PERCENTILES], "peak_max_k"]
    atomic_write_text(out / "pwm_peaks.csv", _csv(pwm, header))

    page = write_page(out, results, good, outliers, typical, worst, pwm, elapsed_s, origin)
    return Summary(outliers, names, typical, worst, pwm, page, power_w, origin)
