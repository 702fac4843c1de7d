"""``spicethermal export``: write a model as a SPICE subcircuit library."""

from __future__ import annotations

import argparse

NAME = "export"
HELP = "write MODEL.json as a .lib subcircuit (.SUBCKT NAME TJ TREF) for ngspice, PSPICE or LTspice"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from ..spice import DIALECTS, TOPOLOGIES

    parser.add_argument("model", metavar="MODEL.json", help="spicethermal-model/1 file")
    parser.add_argument("--dialect", choices=DIALECTS, default="ngspice")
    parser.add_argument("--topology", choices=TOPOLOGIES, default=None,
                        help="network to write (default: the model's own; converted exactly)")
    parser.add_argument("--name", default="THERMAL",
                        help="subcircuit name: a letter, then letters, digits or _")
    parser.add_argument("-o", "--output", required=True, metavar="FILE.lib")


def run(args: argparse.Namespace) -> int:
    from ..model import ThermalModel
    from ..spice import check_name, export

    check_name(args.name)  # before reading anything: a bad name writes nothing
    model = ThermalModel.load(args.model)
    path = export(model, args.output, args.dialect, args.topology, args.name)
    ladder = model.with_topology(args.topology or model.ladder.topology).ladder
    print(f"wrote {path}: .SUBCKT {args.name} TJ TREF, {ladder.topology} ladder of "
          f"{ladder.order} stages, Rth = {model.rth:.6g} K/W, {args.dialect} dialect")
    return 0
