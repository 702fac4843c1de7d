"""``spicethermal bench ACTION --port URL -o BUNDLE``: measure on the bench (or its simulator).

ACTION is ``run`` (calibration, Rth, two cooling curves, the PWM grid) or one procedure:
``calibrate``, ``rth``, ``cooling``, ``pwm``; ``coupling`` on an array board (``sim://array``):
heat one, read all, for every heater. The data sets measured are added to an existing
bundle (a rerun gets new file names; ``--replace NAME`` replaces one); a second process
writing the same bundle stops with a one-line error, or waits with ``--wait``.
URL is any pyserial URL (``/dev/ttyUSB0``, ``socket://host:port``) or the simulated bench,
``sim://actuator`` / ``sim://mur880e`` with options such as
``?seed=3&noise=0.05&effects=sample-window,temperature-coefficient&faults=1e-3``.
"""

from __future__ import annotations

import argparse

from ...bench.session import ACTIONS, run_bench
from ._types import (
    add_option,
    frequency,
    listed,
    number,
    positive,
    positive_duration,
    positive_power,
)

NAME = "bench"
HELP = ("measure on the bench or the simulated bench (sim://actuator, sim://mur880e, sim://array) "
        "into a bundle")

ACTION_HELP = {
    "run": "the whole run: calibrate, rth, cooling (two powers), pwm (the 18-point grid)",
    "calibrate": "TSP calibration on the hot plate at several temperatures, with the heater's "
                 "forward voltage at a few currents (firmware 1.2 on, bench protocol 3)",
    "rth": "thermal resistance at 99.9 %% duty with sample windows",
    "cooling": "cooling curves at log-spaced times after power cut-off, one per power",
    "pwm": "PWM readings at a grid of frequencies and duty cycles",
    "coupling": "array boards (firmware 1.3, bench protocol 4): heat each heater in turn, read "
                "every port (heat one, read all)",
}


def _common(p: argparse.ArgumentParser, action: str) -> None:
    p.add_argument("--port", required=True, metavar="URL",
                   help="pyserial URL of the bench, or sim://actuator, sim://mur880e, "
                        "sim://array (?rows=R&cols=C&pitch=MM&coupling=X&seed=N)")
    add_option(p, "-o", "--output", old=("--out",), dest="out", required=True, metavar="BUNDLE",
                   help="bundle directory to write (an existing bundle is updated)")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    p.add_argument("--wait", action="store_true",
                   help="wait while another process writes the bundle (default: exit 2)")
    p.add_argument("--replace", action="append", default=[], metavar="NAME",
                   help="replace this data file of the bundle (e.g. cooling_1.csv) with the "
                        "new data set of its kind (repeatable; default none: nothing is ever "
                        "dropped)")
    add_option(p, "--settle", old=("--settle-s",), type=positive_duration, dest="settle_s",
               metavar="S",
                   help="heating time to the steady state (default from the board's plan)")
    add_option(p, "--window", old=("--window-s",), type=positive_duration, dest="window_s",
               metavar="S",
                   help="sample window, s (default 1e-4, the paper's 100 us)")
    if action in ("run", "calibrate"):
        add_option(p, "--setpoint", old=("--setpoints",), type=listed(number),
                   dest="calibration_c", metavar="C,...",
                   help="calibration temperatures, degC (default from the board's plan)")
    if action in ("run", "rth"):
        p.add_argument("--rth-power", type=positive_power, dest="rth_power_w", metavar="W",
                       help="power of the Rth measurement, W (default from the board's plan)")
    if action == "coupling":
        p.add_argument("--coupling-power", type=positive_power, dest="coupling_power_w",
                       metavar="W", help="power of each heater, W (default from the board's plan)")
        p.add_argument("--grid", type=_grid, dest="grid", metavar="ROWSxCOLS",
                       help="the cells' grid (default: a Braille cell for 6 or 8 heaters)")
        p.add_argument("--pitch", type=positive, dest="array_pitch_mm", metavar="MM",
                       help="distance between neighbouring cells, mm (default 2.5)")
    if action in ("run", "cooling"):
        add_option(p, "--cooling-power", old=("--powers",), type=listed(positive_power),
                   dest="cooling_powers_w", metavar="W,...",
                   help="powers of the cooling curves, one curve each, W (default from the "
                        "board's plan)")
    if action in ("run", "cooling", "coupling"):
        p.add_argument("--t-last", type=positive_duration, dest="cooling_t_last_s", metavar="S",
                       help="last cooling sample, s after the cut (default from the board's "
                            "plan)")
    if action in ("run", "pwm"):
        p.add_argument("--pwm-power", type=positive_power, dest="pwm_power_w", metavar="W",
                       help="pulse power of the PWM runs, W (default from the board's plan)")
        add_option(p, "--freq", old=("--freqs",), type=listed(frequency), dest="pwm_freqs_hz",
                   metavar="HZ,...", help="PWM frequencies, Hz (default from the board's plan)")
        add_option(p, "--duty", old=("--duties",), type=listed(positive), dest="pwm_duties",
                   metavar="D,...", help="PWM duty cycles in (0, 1] (default from the board's "
                                         "plan)")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    sub = parser.add_subparsers(dest="action", metavar="ACTION", required=True,
                                parser_class=type(parser))
    for action, text in ACTION_HELP.items():
        _common(sub.add_parser(action, help=text, description=text), action)


PLAN_KEYS = ("settle_s", "window_s", "calibration_c", "rth_power_w", "cooling_powers_w",
             "cooling_t_last_s", "pwm_power_w", "pwm_freqs_hz", "pwm_duties",
             "coupling_power_w", "array_pitch_mm")


def _grid(text: str) -> tuple[int, int]:
    parts = text.lower().split("x")
    if len(parts) != 2 or not all(x.strip().isdigit() and int(x) > 0 for x in parts):
        raise argparse.ArgumentTypeError(f"{text!r}: expected ROWSxCOLS, e.g. 4x2")
    return int(parts[0]), int(parts[1])


def run(args: argparse.Namespace) -> int:
    overrides = {k: getattr(args, k) for k in PLAN_KEYS if getattr(args, k, None) is not None}
    if getattr(args, "grid", None) is not None:
        overrides["array_rows"], overrides["array_cols"] = args.grid
    actions = ACTIONS if args.action == "run" else (args.action,)
    path = run_bench(args.port, args.out, progress=not args.quiet, actions=actions,
                     replace_names=args.replace, wait=args.wait, **overrides)
    print(f"bundle written: {path}")
    return 0
