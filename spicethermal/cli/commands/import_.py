"""``spicethermal import VENDOR.lib [--subckt NAME] -o MODEL.json``: a vendor's thermal model,
exactly as published (a SPICE subcircuit of R and C elements, or a datasheet Foster table in
CSV), as a model file to compare, convert (Foster <-> Cauer) or export to another dialect."""

from __future__ import annotations

import argparse
import sys

from ...core.errors import DataFormatError
from ...io.vendor import import_model, import_subckt, read_library

NAME = "import"
HELP = ("read a vendor's thermal subcircuit (.lib) or datasheet Foster table (.csv) into a "
        "model file, exactly (no refit)")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("source", metavar="VENDOR.lib|TABLE.csv",
                        help="SPICE library with R/C thermal subcircuits, or a CSV table with "
                             "r_k_per_w and tau_s (or c_j_per_k) per stage")
    parser.add_argument("--subckt", metavar="NAME",
                        help="subcircuit to import (any case); without it a library holding "
                             "several lists them")
    parser.add_argument("--reference", choices=("case", "ambient"),
                        help="what the reference pin is (default: from its name; case for "
                             "tables)")
    parser.add_argument("-o", "--output", required=True, metavar="MODEL.json",
                        help="model file to write (spicethermal-model/3)")


def run(args: argparse.Namespace) -> int:
    if args.subckt is None and not args.source.lower().endswith(".csv"):
        lib = read_library(args.source)
        if len(lib.subckts) > 1:
            for sub in lib.subckts:
                try:
                    import_subckt(lib, sub.name)
                    what = "R/C thermal network"
                except DataFormatError as exc:
                    what = f"not importable ({str(exc).split(': ', 1)[-1]})"
                print(f"{sub.name} {' '.join(sub.pins)}  (line {sub.number}): {what}")
            raise DataFormatError(f"{args.source}: {len(lib.subckts)} subcircuits (listed "
                                  "above); choose one with --subckt")
    model = import_model(args.source, args.subckt, args.reference)
    out = model.save(args.output)
    lad = model.ladder
    extra = f", case capacitance {model.case_c_j_per_k:.6g} J/K" if model.case_c_j_per_k else ""
    print(f"wrote {out}: {model.provenance.get('device')}, {lad.topology} ladder of "
          f"{lad.order} stages{extra}, Rth = {model.rth:.6g} K/W ({model.reference})",
          file=sys.stdout)
    return 0
