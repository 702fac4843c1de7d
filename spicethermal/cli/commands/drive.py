"""``spicethermal drive MODEL.json --t-max C --target C [...]``: the safe fast PWM drive.

Finds the duty schedule that brings the actuation node (the junction, or Cauer node N of the
model converted to Cauer with ``--node N``) to the target fastest while the junction peak,
PWM ripple included, stays at or below ``--t-max``; then holds it. Prints the schedule and
the time to target against the constant duty with the same steady state; ``--json`` prints
the result document, ``--plot`` writes the figure, ``--spice`` a self-contained ngspice deck
that reproduces the switched drive, and ``--verify`` runs that deck in ngspice and compares
the junction peak with the prediction; with ``--circuit`` the deck and the check are the
paper's bench circuit around the electrothermal heater (a model with a diode law), the
schedule switching the heating current (:mod:`spicethermal.drive.circuit`).
"""

from __future__ import annotations

import argparse

from ...core.errors import DataFormatError
from ...drive.check import verify
from ...drive.circuit import circuit_deck, verify_circuit
from ...drive.optimize import (
    DEFAULT_DUTY_STEP,
    DEFAULT_F_PWM_HZ,
    DEFAULT_TOL_K,
    optimize_drive,
)
from ...engines.interface import NAMES
from ...io.files import atomic_write_text, dumps_json
from ...model import ThermalModel
from ...spice.lib import DIALECTS
from ...viz.plots import fig_drive
from ._array import add_drive_arguments, is_array_document, run_drive
from ._types import add_engine_options, add_option, frequency, positive_power, quantity
from ._types import index as _node
from ._types import number as _number

NAME = "drive"
HELP = "safe fast drive: the PWM schedule that actuates fastest with the junction peak <= t-max"


def _duty(text: str) -> float:
    value = _number(text)
    if not 0 <= value < 1:
        raise argparse.ArgumentTypeError(f"{text!r} must lie in [0, 1)")
    return value


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("model", metavar="MODEL.json",
                        help="model file (spicethermal-model/1 to /4), or an array model "
                             "(spicethermal-array-model/1: the options below for arrays)")
    parser.add_argument("--t-max", type=_number, required=True, metavar="C",
                        help="junction limit in °C; applies to the PWM peak")
    parser.add_argument("--target", type=_number, required=True, metavar="C",
                        help="target temperature of the actuation node (period average), °C")
    parser.add_argument("--ambient", type=_number, default=25.0, metavar="C",
                        help="reference temperature, °C (default 25)")
    add_option(parser, "--power", old=("--p-max",), dest="p_max", type=positive_power,
               metavar="W", help="heater power when on (default: the DC power whose steady state "
                             "puts the junction at t-max)")
    add_option(parser, "--freq", old=("--f-pwm",), dest="f_pwm", type=frequency,
               default=DEFAULT_F_PWM_HZ, metavar="HZ",
               help=f"PWM frequency (default {DEFAULT_F_PWM_HZ:g})")
    parser.add_argument("--node", type=_node, default=0, metavar="N",
                        help="actuation node: 0 junction (default), N = Cauer node N")
    parser.add_argument("--tol", type=quantity("K", open_low=True), default=DEFAULT_TOL_K,
                        metavar="K",
                        help=f"band around the target the node must settle in "
                             f"(default {DEFAULT_TOL_K:g})")
    parser.add_argument("--release", type=_number, metavar="C",
                        help="also report the time to fall below this temperature from the "
                             "steady hold")
    parser.add_argument("--keep-warm", type=_duty, default=0.0, metavar="D",
                        help="duty kept during the release (default 0: power off)")
    parser.add_argument("--duty-step", type=_duty, default=DEFAULT_DUTY_STEP, metavar="D",
                        help=f"merge consecutive steps whose duties differ by at most this "
                             f"(default {DEFAULT_DUTY_STEP:g})")
    parser.add_argument("--json", action="store_true", help="print the result as JSON")
    parser.add_argument("--plot", metavar="FIG.png", help="write the temperatures and duty figure")
    parser.add_argument("--spice", metavar="FILE.cir",
                        help="write a self-contained ngspice deck reproducing the switched drive")
    parser.add_argument("--verify", action="store_true",
                        help="run the deck in ngspice and compare the junction peak")
    parser.add_argument("--circuit", action="store_true",
                        help="--spice and --verify through the bench circuit (Fig. 3) around the "
                             "electrothermal heater: the schedule switches the heating current "
                             "(set to give --power at the ambient); needs a model with a diode "
                             "law")
    parser.add_argument("--dialect", choices=DIALECTS, default="ngspice",
                        help="with --circuit: the .lib dialect (default ngspice)")
    add_engine_options(parser, NAMES, "engine of --verify: ngspice (ngspice -b, pieces in "
                       "parallel; auto) or pyspice; the drive itself is computed in closed form")
    add_drive_arguments(parser)


def run(args: argparse.Namespace) -> int:
    if args.engine == "analytic":  # before anything is computed or written
        raise DataFormatError("--engine analytic: the drive is already computed in closed form; "
                              "--verify runs it in ngspice or pyspice")
    if is_array_document(args.model):  # an array: its dots, their patterns, the baselines
        return run_drive(args)
    for flag, given in (("--actuation", args.actuation), ("--margin", args.margin),
                        ("--text", args.text), ("--patterns", args.patterns),
                        ("--dwell", args.dwell), ("--report", args.report)):
        if given is not None:
            raise DataFormatError(f"{flag}: for an array model (spicethermal-array-model/1); "
                                  f"{args.model} is a single device")
    spice = "ngspice" if args.engine == "auto" else args.engine
    model = ThermalModel.load(args.model)
    if args.node >= model.ladder.order:
        raise DataFormatError(f"--node {args.node}: the model has Cauer nodes 0.."
                              f"{model.ladder.order - 1}")
    result = optimize_drive(model, args.t_max, args.target, args.ambient, args.p_max,
                            args.f_pwm, args.node, tol_k=args.tol, release_c=args.release,
                            keep_warm_duty=args.keep_warm, duty_step=args.duty_step)
    written = []
    if args.spice:
        deck = circuit_deck(result, args.dialect) if args.circuit else result.spice_bench()
        written.append(str(atomic_write_text(args.spice, deck)))
    if args.plot:
        written.append(str(fig_drive(result, args.plot)))
    check = None
    if args.verify and args.circuit:
        check = verify_circuit(result, spice, args.dialect)
    elif args.verify:
        check = verify(result, quiet=args.quiet, engine=spice)
    if args.json:
        doc = result.to_dict()
        if check is not None:
            doc["ngspice"] = check
        print(dumps_json(doc, indent=2))
        return 0
    print(result)
    print()
    print(result.table())
    if check is not None and args.circuit:
        print(f"{check['engine']} bench circuit ({check['dialect']}, from cold, first "
              f"{check['window_s']:.4g} s; heating current {check['heating_current_a']:.4g} A): "
              f"junction peak {check['circuit_peak_junction_c']:.4f} °C at "
              f"{check['circuit_peak_at_s']:.4g} s, {check['margin_k']:.3f} K under t_max")
    elif check is not None:
        runs = "one run" if check["pieces"] == 1 else f"{check['pieces']} parallel runs"
        line = (f"{check['engine']} (switched, first {check['window_s']:.4g} s in {runs}): "
                f"junction peak "
                f"{check['ngspice_peak_junction_c']:.4f} °C at {check['ngspice_peak_at_s']:.4g} s")
        if "predicted_peak_junction_c" in check:
            line += (f"; predicted {check['predicted_peak_junction_c']:.4f} °C; pieces join "
                     f"within {check['join_k']:.2g} K")
        print(line)
    if written:
        print("wrote " + " and ".join(written))
    return 0
