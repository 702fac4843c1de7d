"""The HTML report of a diagnosis (``spicethermal diagnose --report DIR``)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from ..io.files import atomic_write_text
from ..spice.templates import environment
from ..viz.plots import diagnosis_figures

if TYPE_CHECKING:  # pragma: no cover
    from ..analysis.diagnosis import Diagnosis

__all__ = ["write_report"]


def write_report(result: Diagnosis, out_dir: str | Path) -> Path:
    """Write the HTML report of a diagnosis (``index.html``, self-contained but for its PNG
    figures beside it, from ``templates/report/diagnosis.html.j2``) into ``out_dir``."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    figs = diagnosis_figures(result, out)
    html = environment().get_template("report/diagnosis.html.j2").render(
        diagnosis=result, doc=result.to_json(), figures=[p.name for p in figs],
        text=str(result))
    return atomic_write_text(out / "index.html", html)
