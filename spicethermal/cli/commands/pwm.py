"""``spicethermal pwm MODEL.json --freq HZ --duty D --power W [--window S] [--engine E] [--json]``.

The periodic steady state of a model under a PWM power train: peak, mean, valley and the bench
reading (the rise at the end of a power-off sample window that starts when an on-phase ends),
all as rises in K over the reference. ``analytic`` is the closed form (shooting for a model with
device effects); ``ngspice`` and ``pyspice`` run the exported subcircuit from the periodic
steady state (:mod:`spicethermal.engines.pwmsim`). ``--circuit`` runs the paper's bench circuit
(Fig. 3) around the electrothermal part instead (a model with a diode law): the heating current
the power loop sets, the TSP read through the sense current at the end of the window
(:mod:`spicethermal.engines.circuit`). Several ``--freq`` and ``--duty`` values make a grid,
printed as the paper's Table 2 (the readings in °C).
"""

from __future__ import annotations

import argparse
import sys

from ...core.errors import DataFormatError
from ...core.plausible import implausible_rise
from ...engines.circuit import CircuitPwm, pwm_points
from ...engines.interface import NAMES
from ...io.files import dumps_json
from ...model import ThermalModel
from ...spice.lib import DIALECTS
from ...viz.plots import fig_circuit
from ._types import add_option, duration, duty, frequency, listed, number, power

NAME = "pwm"
HELP = "periodic steady state under PWM: peak, mean, valley and the bench reading"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("model", metavar="MODEL.json", help="a spicethermal-model file (/1 to /4)")
    parser.add_argument("--freq", required=True, metavar="HZ[,HZ...]", type=listed(frequency),
                        help="PWM frequency, Hz (several: a grid, e.g. 500,1k,3k,5k,10k,25k)")
    parser.add_argument("--duty", required=True, metavar="D[,D...]", type=listed(duty),
                        help="duty cycle, 0..1 (several: a grid, e.g. 0.2,0.5,0.8)")
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
    parser.add_argument("--circuit", action="store_true",
                        help="run the paper's bench circuit (Fig. 3) around the electrothermal "
                             "part (needs --engine ngspice or pyspice and a model with a diode "
                             "law): the reading as the bench takes it, through the TSP")
    parser.add_argument("--dialect", choices=DIALECTS, default="ngspice",
                        help="the .lib dialect an ngspice run uses (pspice and ltspice under "
                             "ngspice's compatibility modes; default ngspice)")
    parser.add_argument("--plot", metavar="FIG.png",
                        help="with --circuit and one point: Vf, I and Tj over the simulated "
                             "periods and the sample window")
    parser.add_argument("--json", action="store_true",
                        help='print {"peak_k", "mean_k", "valley_k", "reading_k"} (a grid: '
                             '{"points": [...]} with freq_hz and duty)')


def run(args: argparse.Namespace) -> int:
    grid = [(f, d) for d in args.duty for f in args.freq]
    if args.plot and (not args.circuit or len(grid) > 1):
        raise DataFormatError("--plot: draws one point's run of the bench circuit (give "
                              "--circuit and one --freq and --duty)")
    model = ThermalModel.load(args.model)
    if args.plot:  # one point through the circuit, and its waveforms
        if args.engine not in ("ngspice", "pyspice"):
            raise DataFormatError("--circuit runs the bench circuit in ngspice: use --engine "
                                  "ngspice or pyspice")
        sim = CircuitPwm(model, args.engine, args.dialect, tref_c=args.tref)
        circuit_run = sim.run(args.power, grid[0][0], grid[0][1], args.window)
        states = [circuit_run.state]
        written = fig_circuit(circuit_run, args.plot)
    else:
        states = pwm_points(model, args.power, [f for f, _ in grid], [d for _, d in grid],
                            args.window, engine=args.engine, tref_c=args.tref,
                            dialect=args.dialect, circuit=args.circuit)
        written = None
    warning = implausible_rise(max(s.peak_k for s in states), f"--power {args.power:g} W")
    if warning:
        print(f"spicethermal pwm: warning: {warning}", file=sys.stderr)
    how = f"engine {args.engine}" + (f", bench circuit ({args.dialect})" if args.circuit else "")
    if args.json:
        if len(states) == 1:
            print(dumps_json(states[0].to_dict()))
        else:
            print(dumps_json({"points": [{"freq_hz": s.freq_hz, "duty": s.duty,
                                          **s.to_dict()} for s in states]}))
    elif len(states) == 1:
        print(f"# {args.model}: {args.power:g} W at {grid[0][0]:g} Hz, duty {grid[0][1]:g}, "
              f"window {args.window:g} s, {how}; rises over the reference, K")
        for key, value in states[0].to_dict().items():
            print(f"{key[:-2]:<8} {value:.6f}")
    else:
        print(f"# {args.model}: {args.power:g} W, window {args.window:g} s, {how}; the "
              f"readings in degC ({args.tref:g} degC + the rise), as the paper's Table 2")
        print("freq_khz  " + "  ".join(f"D={100 * d:g}%".rjust(8) for d in args.duty))
        by = {(s.freq_hz, s.duty): s.reading_k for s in states}
        for f in args.freq:
            print(f"{f / 1e3:<8g}  " + "  ".join(f"{args.tref + by[(f, d)]:8.3f}"
                                                for d in args.duty))
    if written is not None and not args.json:
        print(f"wrote {written}")
    return 0
