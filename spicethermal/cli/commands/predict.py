"""``spicethermal predict MODEL.json --profile PROFILE.csv -o TJ.csv [--plot TJ.png]``.

The junction temperature under a measured power profile (CSV ``t_s, power_w`` from t = 0,
linear between samples, held after the last): the analytic engine (exact, mode by mode) for
linear models, ngspice with device effects (:mod:`spicethermal.predict`). Writes ``t_s``,
``power_w``, ``tj_c`` at the profile's times and ``--points`` even ones, and prints the peak.
"""

from __future__ import annotations

import argparse
import sys

from ...core.plausible import implausible_rise
from ...io.bundle import format_columns
from ...io.files import atomic_write_text
from ...model import ThermalModel
from ...predict import (
    DEFAULT_POINTS,
    ENGINES,
    PowerProfile,
    output_times,
    plot_prediction,
    predict,
)
from ._types import add_engine_options, add_option, count, number, positive_duration

NAME = "predict"
HELP = "junction temperature under a measured power profile (analytic, or ngspice with effects)"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("model", metavar="MODEL.json", help="a spicethermal model file")
    add_option(parser, "--profile", old=("--power",), required=True, metavar="PROFILE.csv",
               help="power profile: columns t_s (from 0) and power_w in W")
    parser.add_argument("-o", "--output", required=True, metavar="TJ.csv",
                        help="where to write t_s, power_w, tj_c")
    parser.add_argument("--plot", metavar="TJ.png", help="also draw Tj and power against time")
    add_option(parser, "--ambient", old=("--tref",), dest="tref", type=number, default=25.0,
               metavar="DEGC", help="reference (ambient or case) temperature, degC (default 25)")
    parser.add_argument("--until", type=positive_duration, metavar="S",
                        help="predict until this time, s (default: the profile's last sample; "
                             "after it the power is held)")
    parser.add_argument("--points", type=count, default=DEFAULT_POINTS, metavar="N",
                        help=f"even output points besides the profile's own times (default "
                             f"{DEFAULT_POINTS})")
    add_engine_options(parser, ENGINES, "auto (analytic for linear models, ngspice with device "
                       "effects), analytic, ngspice or pyspice")


def run(args: argparse.Namespace) -> int:
    model = ThermalModel.load(args.model)
    profile = PowerProfile.read(args.profile)
    times = output_times(profile, args.until, args.points)
    result = predict(model, profile, times, tref_c=args.tref, engine=args.engine,
                     quiet=args.quiet)
    atomic_write_text(args.output, format_columns(result.columns(), [
        f"spicethermal predict: {args.model} under {args.profile}, Tref {args.tref:g} degC, "
        f"engine {result.engine}"]))
    warning = implausible_rise(result.peak[1] - args.tref, f"the power profile {args.profile} "
                               f"(power_w in W)")
    if warning:
        print(f"spicethermal predict: warning: {warning}", file=sys.stderr)
    if args.plot:
        plot_prediction(result, args.plot)
    print(result)
    print(f"wrote {args.output}" + (f" and {args.plot}" if args.plot else ""))
    return 0
