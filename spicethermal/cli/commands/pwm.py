"""``spicethermal pwm MODEL.json --freq HZ --duty D --power W [--window S] [--engine E] [--json]``.

The periodic steady state of a model under a PWM power train: peak, mean, valley and the bench
reading (the rise at the end of a power-off sample window that starts when an on-phase ends),
all as rises in K over the reference. ``analytic`` is the closed form (shooting for a model with
device effects); ``ngspice`` and ``pyspice`` run the exported subcircuit from the periodic
steady state (:mod:`spicethermal.engines.pwmsim`).
"""

from __future__ import annotations

import argparse
import sys

from ...core.plausible import implausible_rise
from ...engines.interface import NAMES
from ...engines.pwmsim import pwm_state
from ...io.files import dumps_json
from ...model import ThermalModel
from ._types import add_option, duration, duty, frequency, number, power

NAME = "pwm"
HELP = "periodic steady state under PWM: peak, mean, valley and the bench reading"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("model", metavar="MODEL.json", help="a spicethermal-model/3 (/2, /1) file")
    parser.add_argument("--freq", required=True, metavar="HZ",
                        type=frequency, help="PWM frequency, Hz")
    parser.add_argument("--duty", required=True, metavar="D",
                        type=duty, help="duty cycle, 0..1")
    parser.add_argument("--power", required=True, metavar="W", type=power,
                        help="power during the on-phase, W")
    parser.add_argument("--window", default=0.0, metavar="S", type=duration,
                        help="power-off sample window before the reading, s (default 0: the "
                             "reading is the peak)")
    parser.add_argument("--engine", choices=NAMES, default="analytic",
                        help="closed form/shooting (default), ngspice (binary or PySpice), or "
                             "auto (closed form for a linear model, else ngspice)")
    add_option(parser, "--ambient", old=("--tref",), dest="tref", default=25.0, metavar="DEGC",
               type=number,
                        help="reference temperature, degC (matters for device effects; "
                             "default 25)")
    parser.add_argument("--json", action="store_true",
                        help='print {"peak_k", "mean_k", "valley_k", "reading_k"}')


def run(args: argparse.Namespace) -> int:
    model = ThermalModel.load(args.model)
    state = pwm_state(model, args.power, args.freq, args.duty, args.window,
                      engine=args.engine, tref_c=args.tref)
    warning = implausible_rise(state.peak_k, f"--power {args.power:g} W")
    if warning:
        print(f"spicethermal pwm: warning: {warning}", file=sys.stderr)
    if args.json:
        print(dumps_json(state.to_dict()))
        return 0
    print(f"# {args.model}: {args.power:g} W at {args.freq:g} Hz, duty {args.duty:g}, "
          f"window {args.window:g} s, engine {args.engine}; rises over the reference, K")
    for key, value in state.to_dict().items():
        print(f"{key[:-2]:<8} {value:.6f}")
    return 0
