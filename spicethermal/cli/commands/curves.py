"""``spicethermal curves MODEL.json -o FIG.png [--duty D]...``: the paper's Fig. 8 for a model.

Duty-cycle impedance curves r_D(t) for D = 0, 0.1 ... 0.9 (or the given ``--duty`` values):
the paper's eq. 3, ``D + (1 − D) r(t)`` (dashed), and the exact periodic-steady-state form
(solid). Both come from the model's linear ladder (device effects are not used here). Beside
the figure, ``FIG.csv`` holds the exact family in K/W per duty (columns ``t_s`` and
``zth_k_per_w_d<D>``), as a datasheet gives it.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from ...analysis.tables import duty_family
from ...io.bundle import format_columns
from ...io.files import atomic_write_text
from ...model import ThermalModel
from ...viz.plots import FIG8_DUTIES, fig8
from ._types import duty as _duty

NAME = "curves"
HELP = "duty-cycle impedance curves r_D(t), eq. 3 and exact (the paper's Fig. 8) as a PNG"




def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("model", metavar="MODEL.json", help="a spicethermal-model/3 (/2, /1) file")
    parser.add_argument("-o", "--output", required=True, metavar="FIG.png",
                        help="where to write the figure (PNG)")
    parser.add_argument("--duty", type=_duty, action="append", metavar="D",
                        help="a duty cycle to draw (repeatable; default 0, 0.1 ... 0.9)")
    parser.add_argument("--title", default=None, help="a title line above the plot")


def run(args: argparse.Namespace) -> int:
    model = ThermalModel.load(args.model)
    duties = tuple(args.duty) if args.duty else FIG8_DUTIES
    path = fig8(model.ladder, args.output, duties, title=args.title)
    table = atomic_write_text(Path(path).with_suffix(".csv"), format_columns(
        duty_family(model.ladder, duties),
        [f"peak Zth (K/W) of pulses of width t_s repeated at duty D, exact; {args.model}"]))
    print(path)
    print(table)
    return 0
