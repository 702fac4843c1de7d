"""``spicethermal import VENDOR.lib [--subckt NAME] -o MODEL.json``: a vendor's thermal model,
exactly as published: the thermal network cut out of any subcircuit (an electrothermal MOSFET
model, a standalone R/C network) or a datasheet Foster table in CSV, as a model file to
compare, compose, convert (Foster <-> Cauer) or export to another dialect.

Choices are explicit: ``--param NAME=VALUE`` (a ``PARAMS:`` value such as Infineon's
``Zthtype=1``), ``--network N`` (one of several networks, listed when none is chosen),
``--to NODE`` (a network that continues past the case). What was taken, left and why is printed
in one line and kept in the model's provenance.
"""

from __future__ import annotations

import argparse
import re

from ...core.errors import DataFormatError
from ...io.vendor import SeveralNetworks, describe, import_model, networks, read_library

NAME = "import"
HELP = ("cut the thermal network out of a vendor's SPICE library (.lib, .txt, .mod) or read a "
        "datasheet Foster table (.csv) into a model file, exactly (no refit)")


def _param(text: str) -> tuple[str, str]:
    m = re.fullmatch(r"\s*([a-z_][a-z0-9_]*)\s*=\s*(\S.*?)\s*", text, re.I)
    if not m:
        raise argparse.ArgumentTypeError(f"{text!r}: expected NAME=VALUE, e.g. Zthtype=1")
    return m.group(1), m.group(2)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("source", metavar="VENDOR.lib|TABLE.csv",
                        help="SPICE library (PSpice, LTspice, ngspice; .lib, .txt, .mod, ...) "
                             "holding the part's subcircuit, or a CSV table with r_k_per_w and "
                             "tau_s (or c_j_per_k) per stage")
    parser.add_argument("--subckt", metavar="NAME",
                        help="subcircuit to import (any case); without it a library holding "
                             "several lists them")
    parser.add_argument("--param", type=_param, action="append", default=[],
                        metavar="NAME=VALUE",
                        help="a parameter's value instead of the library's (repeatable; "
                             "default: the library's own values), e.g. --param Zthtype=1 for "
                             "Infineon's maximum network")
    parser.add_argument("--network", metavar="N|NODE",
                        help="which network when the subcircuit holds several (listed without "
                             "it): its number or its junction node")
    parser.add_argument("--to", metavar="NODE",
                        help="import to this node instead of the case pin, for a network that "
                             "continues past the case (e.g. to the ambient)")
    parser.add_argument("--reference", choices=("case", "ambient"),
                        help="what the reference is (default: from its name: an ambient pin or "
                             "source, or ground, is the ambient; else the case; case for tables)")
    parser.add_argument("-o", "--output", required=True, metavar="MODEL.json",
                        help="model file to write (spicethermal-model/3)")


def _list_subckts(source: str) -> None:
    lib = read_library(source)
    if len(lib.subckts) <= 1:
        return
    for sub in lib.subckts:
        try:
            ex = networks(lib, sub.name)
            what = "; ".join(describe(ex.circuit, f) for f in ex.found)
        except DataFormatError as exc:
            what = f"no thermal network ({str(exc).split(': ', 2)[-1]})"
        print(f"{sub.name} {' '.join(sub.pins)}  (line {sub.line.number}): {what}")
    raise DataFormatError(f"{source}: {len(lib.subckts)} subcircuits (listed above); choose one "
                          "with --subckt")


def run(args: argparse.Namespace) -> int:
    csv = args.source.lower().endswith(".csv")
    if args.subckt is None and not csv:
        _list_subckts(args.source)
    choices = {"params": dict(args.param) or None, "network": args.network, "to": args.to}
    try:
        model = import_model(args.source, args.subckt, args.reference, **choices)
    except SeveralNetworks as exc:
        for k, f in enumerate(exc.found, 1):
            print(f"{k}: {describe(exc.circuit, f)}")
        raise
    out = model.save(args.output)
    lad = model.ladder
    extra = f", case capacitance {model.case_c_j_per_k:.6g} J/K" if model.case_c_j_per_k else ""
    print(f"wrote {out}: {model.provenance.get('device')}, {lad.topology} ladder of "
          f"{lad.order} stages{extra}, Rth = {model.rth:.6g} K/W ({model.reference})")
    if "extraction" in model.provenance:
        print(model.provenance["extraction"])
    return 0
