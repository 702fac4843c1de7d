"""The HTML report of a diagnosis (``spicethermal diagnose --report DIR``)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from ..io.files import atomic_write_text
from ..spice.templates import environment

if TYPE_CHECKING:  # pragma: no cover
    from ..analysis.diagnosis import Diagnosis
    from ..analysis.table2 import TableDiagnosis

__all__ = ["write_report"]


def write_report(result: Diagnosis | TableDiagnosis, out_dir: str | Path) -> Path:
    """Write the HTML report of a diagnosis (``index.html``, self-contained but for its PNG
    figures beside it, from ``templates/report/diagnosis.html.j2``) into ``out_dir``: its
    numbers are those of the ``spicethermal-diagnosis/9`` document, its text the CLI's."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    figs = result.plot(out)
    html = environment().get_template("report/diagnosis.html.j2").render(
        doc=result.to_dict(), figures=[p.name for p in figs], text=str(result))
    return atomic_write_text(out / "index.html", html)
