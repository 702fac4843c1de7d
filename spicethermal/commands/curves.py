"""``spicethermal curves MODEL.json -o FIG.png [--duty D]...``: the paper's Fig. 8 for a model.

Duty-cycle impedance curves r_D(t) for D = 0, 0.1 ... 0.9 (or the given ``--duty`` values):
the paper's eq. 3, ``D + (1 − D) r(t)`` (dashed), and the exact periodic-steady-state form
(solid). Both come from the model's linear ladder (device effects are not used here).
"""

from __future__ import annotations

import argparse

from ._types import duty as _duty

NAME = "curves"
HELP = "duty-cycle impedance curves r_D(t), eq. 3 and exact (the paper's Fig. 8) as a PNG"




def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("model", metavar="MODEL.json", help="a spicethermal-model/1 file")
    parser.add_argument("-o", "--output", required=True, metavar="FIG.png",
                        help="where to write the figure (PNG)")
    parser.add_argument("--duty", type=_duty, action="append", metavar="D",
                        help="a duty cycle to draw (repeatable; default 0, 0.1 ... 0.9)")
    parser.add_argument("--title", default=None, help="a title line above the plot")


def run(args: argparse.Namespace) -> int:
    from ..model import ThermalModel
    from ..plots import FIG8_DUTIES, fig8

    model = ThermalModel.load(args.model)
    duties = tuple(args.duty) if args.duty else FIG8_DUTIES
    path = fig8(model.ladder, args.output, duties, title=args.title)
    print(path)
    return 0
