"""``spicethermal diagnose BUNDLE [--model MODEL.json] [--json] [--report DIR] [--budget COST]``.

Compares the model (default: the linear ladder fitted from the bundle's cooling curves) with
every data set of the bundle, shows where it fails, fits every catalogued effect and names the
one that is missing (or says that none is and where the misfit is). ``--json`` prints the
``spicethermal-diagnosis/9`` document; ``--report DIR`` writes an HTML page with the before /
after residual figures. ``--budget`` sets the simulator's work the search may spend (counted,
never timed: the verdict is the same on every machine); a diagnosis the budget stopped says so,
and a larger budget lets it go on.

SOURCE may also be a table of PWM readings with a measured and a simulated column (columns
``freq_hz, duty, tj_exp_c, tj_model_c``, as ``spicethermal/data/actuator_table2.csv`` holds the
paper's Table 2): the two columns are then compared and the explanations the paper gives
(the 100 µs sample window, early-time extrapolation) are tested against the numbers
(``--rth``, ``--power``, ``--window``, ``--ambient``).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from ...analysis.diagnose import diagnose
from ...analysis.rules import WORK_BUDGET
from ...analysis.table2 import diagnose_table
from ...core.errors import DataFormatError
from ...core.progress import status_line
from ...effects import plugin
from ...io.files import dumps_json
from ...io.sources import csv_header
from ...model import ThermalModel
from ...report.diagnosis import write_report
from ._source import SOURCE_HELP, add_source_arguments, comparable_source
from ._types import count, positive_duration, positive_power
from ._types import number as _number
from ._types import positive as _positive

NAME = "diagnose"
HELP = "show where the model fails and which physical effect is missing"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("source", metavar="SOURCE",
                        help=f"{SOURCE_HELP}; or a CSV of PWM readings with measured and "
                             f"simulated columns (tj_exp_c, tj_model_c)")
    parser.add_argument("--model", metavar="MODEL.json",
                        help="baseline model (default: the linear ladder fitted from the "
                             "bundle's cooling curves)")
    parser.add_argument("--json", action="store_true",
                        help="print the spicethermal-diagnosis/9 document")
    parser.add_argument("--report", metavar="DIR",
                        help="write an HTML report with the before/after figures into DIR")
    parser.add_argument("--effect", action="append", metavar="NAME",
                        help="candidate effect to try (repeatable; default every registered "
                             "effect, the rivals outside the catalogue included)")
    parser.add_argument("--budget", type=count, metavar="COST",
                        help=f"the simulator's work the search may spend, counted, never timed "
                             f"(default {WORK_BUDGET}: under a minute of CPU on a loaded 2-core "
                             f"machine, the time in proportion); a diagnosis the budget stopped "
                             f"says so, and a larger one lets it go on")
    table = parser.add_argument_group("for a table of measured vs simulated PWM readings")
    table.add_argument("--rth", type=_positive, metavar="K_PER_W", default=146.0,
                       help="Rth of the simulated ladder (default 146, the paper's)")
    table.add_argument("--power", type=positive_power, metavar="W",
                       help="pulse power (default: from the simulated column at the lowest "
                            "frequency)")
    table.add_argument("--window", type=positive_duration, metavar="S", default=1e-4,
                       help="sample window the bench used (default 1e-4 s, the paper's)")
    table.add_argument("--ambient", type=_number, metavar="DEGC", dest="tref",
                       help="reference added to a table's rises (default 25, as in the "
                            "paper); for a raw record, the temperature at its end (anchors the "
                            "calibration) or the reference of a cooling CSV")
    parser.add_argument("-q", "--quiet", action="store_true",
                        help="no progress line on stderr (none either when it is not a terminal)")
    add_source_arguments(parser, curve=False, power=False, rth=False, tref=False, early=False)


def run(args: argparse.Namespace) -> int:
    source = Path(args.source)
    hint = ""
    if source.is_file() and "tj_exp_c" in csv_header(source):
        for flag, given in (("--model", args.model), ("--effect", args.effect),
                            ("--budget", args.budget)):
            if given:
                raise DataFormatError(f"{flag} applies to a bundle, not to a table of readings")
        result = diagnose_table(source, rth_k_per_w=args.rth, power_w=args.power,
                                window_s=args.window,
                                ambient_c=25.0 if args.tref is None else args.tref)
    else:
        for name in args.effect or ():
            plugin(name)
        model = ThermalModel.load(args.model) if args.model else None
        bundle = comparable_source(args, args.source, rth=False)
        with status_line(quiet=args.quiet) as say:
            budget = args.budget or WORK_BUDGET
            result = diagnose(bundle, model, args.effect, progress=say, budget=budget)
        if result.spent.stopped:
            hint = (f"(the work budget stopped the search: a larger one lets it go on, e.g. "
                    f"--budget {4 * budget}, in about four times the time)")
    if args.report:
        page = write_report(result, args.report)
        if not args.json and not args.quiet:
            print(f"wrote {page}")
    if args.json:
        print(dumps_json(result.to_dict(), indent=2))
    else:
        print(result)
        if hint:
            print(hint)
    return 0
