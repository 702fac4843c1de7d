"""``spicethermal demo``: the main job on the simulated bench, with the HTML report."""

from __future__ import annotations

import argparse

from ...demo import run_demo
from ._types import add_option

NAME = "demo"
HELP = ("run the whole job on the simulated bench: measure, fit, export, simulate the PWM "
        "table, diagnose, validate on the MUR880E, write the report")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_option(parser, "-o", "--output", old=("--out",), dest="out", default="out/demo",
               metavar="DIR",
                        help="directory for the bundles, models, .lib files and report "
                             "(default out/demo)")
    parser.add_argument("--seed", type=int, default=1,
                        help="seed of the simulated bench (default 1)")
    parser.add_argument("-q", "--quiet", action="store_true", help="no progress output")


def run(args: argparse.Namespace) -> int:
    result = run_demo(args.out, seed=args.seed, quiet=args.quiet)
    total = sum(result.timings.values())
    print(f"report:    {result.report}")
    print(f".lib files: {result.libs[0].parent} ({len(result.libs)} files)")
    print(f"done in {total:.1f} s")
    print()
    for line in result.summary:
        print(f"  {line}")
    return 0
