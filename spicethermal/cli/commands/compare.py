"""``spicethermal compare MODEL.json BUNDLE [--json] [--engine auto|analytic|ngspice|pyspice]``.

Measured vs model over every data set of the bundle, one table per kind: the PWM readings as the
paper's Table 2 (Freq × duty: T_exp, T_mod, Δ; the power in a column when each row has its
own), the cooling curves one row each. Unless the model has an ``electrical-transient`` effect,
the samples ``fit`` masks as the electrical transient are left out, as fit leaves them out, and
counted. ``--json`` prints the ``spicethermal-comparison/1`` document. Δ = measured − model.
"""

from __future__ import annotations

import argparse

from ...analysis.compare import compare
from ...engines.interface import NAMES, engine
from ...io.files import dumps_json
from ...model import ThermalModel
from ._source import SOURCE_HELP, add_source_arguments, comparable_source
from ._types import duration as _window

NAME = "compare"
HELP = "measured vs model over every data set of a bundle (the paper's Table 2)"




def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("model", metavar="MODEL.json", help="a spicethermal-model file (/1 to /4)")
    parser.add_argument("bundle", metavar="SOURCE", help=SOURCE_HELP)
    parser.add_argument("--json", action="store_true",
                        help="print the spicethermal-comparison/1 document")
    parser.add_argument("--engine", choices=NAMES, default="auto",
                        help="PWM engine: auto (the network simulator: the closed form, made "
                             "exact with device effects by their periodic state; default), "
                             "analytic (linear models only), ngspice or pyspice")
    parser.add_argument("--window", type=_window, metavar="S",
                        help="sample window for PWM readings, s (default: the model's "
                             "sample-window effect, else the bundle's sample_window_s)")
    parser.add_argument("--reference", choices=("case", "ambient"),
                        help="what SOURCE is measured to, for a file that does not say (a CSV, "
                             "PyRth, T3Ster; default: the model's reference); a bundle states "
                             "its own")
    add_source_arguments(parser, curve=False, early=False)
    parser.add_argument("-q", "--quiet", action="store_true",
                        help="no progress bar on stderr (none either when it is not a terminal)")


def run(args: argparse.Namespace) -> int:
    model = ThermalModel.load(args.model)
    engine(args.engine, model)  # --engine analytic refuses device effects in one line
    # judged on what its fit described: a ladder fitted to a Zth (its provenance records the
    # early-time treatment) leaves out, and counts, the samples that fit masked as the
    # electrical transient; a model fitted to every reading (fit --effect, diagnose) is
    # compared on every reading
    bundle = comparable_source(args, args.bundle, model_reference=model.reference,
                               mask_transient="early_time" in model.provenance)
    result = compare(model, bundle, args.engine, window_s=args.window, quiet=args.quiet)
    if args.json:
        print(dumps_json(result.to_json(), indent=2))
    else:
        print(result.table())
    return 0
