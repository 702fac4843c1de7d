"""``spicethermal curves MODEL.json [--plot FIG.png] [-o TABLE.csv] [--duty D,...]``: the
paper's Fig. 8 for a model.

Duty-cycle impedance curves r_D(t) for D = 0, 0.1 ... 0.9 (or the given ``--duty`` values):
the paper's eq. 3, ``D + (1 − D) r(t)`` (dashed), and the exact periodic-steady-state form
(solid), drawn by ``--plot``. Both come from the model's linear ladder (device effects are not
used here). ``-o TABLE.csv`` writes the exact family in K/W per duty (columns ``t_s`` and
``zth_k_per_w_d<D>``), as a datasheet gives it. The old ``-o FIG.png`` (deprecated) draws the
figure and writes ``FIG.csv`` beside it.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from ...core.errors import DataFormatError
from ...io.bundle import format_columns
from ...io.files import atomic_write_text
from ...model import ThermalModel
from ...report.tables import duty_family
from ...viz.plots import FIG8_DUTIES, fig8
from ._types import duty as _duty
from ._types import listed, old_figure_output

NAME = "curves"
HELP = "duty-cycle impedance curves r_D(t), eq. 3 and exact (the paper's Fig. 8): figure and table"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("model", metavar="MODEL.json", help="a spicethermal-model file (/1 to /4)")
    parser.add_argument("--plot", metavar="FIG.png",
                        help="write the figure (eq. 3 dashed, exact solid)")
    parser.add_argument("-o", "--output", metavar="TABLE.csv",
                        help="write the exact family as CSV: t_s and zth_k_per_w_d<D> in K/W "
                             "(at least one of --plot and -o)")
    parser.add_argument("--duty", type=listed(_duty), action="extend", metavar="D,...",
                        help="duty cycles to draw, 0..1 (comma-separated, repeatable; default "
                             "0,0.1,...,0.9)")
    parser.add_argument("--title", default=None,
                        help="a title line above the plot (default: none)")


def run(args: argparse.Namespace) -> int:
    old = old_figure_output(args)  # -o FIG.png: the figure and FIG.csv, as before --plot
    table = args.output or (str(Path(old).with_suffix(".csv")) if old else None)
    if not (args.plot or table):
        raise DataFormatError("curves writes nothing without --plot FIG.png (the figure) or "
                              "-o TABLE.csv (the family in K/W)")
    model = ThermalModel.load(args.model)
    duties = tuple(args.duty) if args.duty else FIG8_DUTIES
    listing = ", ".join(f"{d:g}" for d in duties)
    if args.plot:
        path = fig8(model.ladder, args.plot, duties, title=args.title)
        print(f"wrote figure {path}: r_D(t) for duty {listing} (eq. 3 dashed, exact solid)")
    if table:
        family = duty_family(model.ladder, duties)
        path = atomic_write_text(table, format_columns(family, [
            f"peak Zth (K/W) of pulses of width t_s repeated at duty D, exact; {args.model}"]))
        print(f"wrote table {path}: peak Zth in K/W for duty {listing}, "
              f"{len(family['t_s'])} pulse widths from {family['t_s'][0]:.3g} to "
              f"{family['t_s'][-1]:.3g} s")
    return 0
