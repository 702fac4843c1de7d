"""``spicethermal export``: write a model as a SPICE subcircuit library."""

from __future__ import annotations

import argparse

from ...core.errors import DataFormatError
from ...model import ThermalModel
from ...spice.lib import (
    DIALECTS,
    TEMPERATURES,
    TOPOLOGIES,
    Pins,
    check_name,
    default_name,
    export,
    written_topology,
)
from ._array import is_array_document, run_export

NAME = "export"
HELP = ("write MODEL.json as a .lib subcircuit (.SUBCKT NAME TJ TREF, pins and temperature "
        "convention as you choose) for ngspice, PSPICE or LTspice")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("model", metavar="MODEL.json",
                        help="spicethermal-model/3 (/2, /1) file, or an array model "
                             "(spicethermal-array-model/1: .SUBCKT NAME TJ1 ... TJN TREF)")
    parser.add_argument("--dialect", choices=DIALECTS, default="ngspice",
                        help="the simulator's syntax: ngspice (default), pspice or ltspice")
    parser.add_argument("--topology", choices=TOPOLOGIES, default=None,
                        help="network to write (default: the model's own; converted exactly). "
                             "cauer: capacitors to the thermal ground, right when coupled to a "
                             "heatsink model; foster: valid only with an ideal reference")
    parser.add_argument("--name", default=None,
                        help="subcircuit name as vendors spell parts (letters, digits, _, -, .); "
                             "default: the model's device, else the output file's stem")
    parser.add_argument("--pins", default="TJ,TREF", metavar="J,REF[,AMB]",
                        help="pin names in .SUBCKT order: junction, reference (case or "
                             "ambient)[, ambient = thermal ground of a Cauer ladder]; or "
                             "role=NAME items, e.g. case=TC,junction=TJ (default TJ,TREF)")
    parser.add_argument("--temperature", choices=TEMPERATURES, default="absolute",
                        help="absolute (default): node voltages are temperatures in degC, you "
                             "drive the reference pin; rise: rises in K over node 0 = ambient")
    parser.add_argument("-o", "--output", required=True, metavar="FILE.lib",
                        help="the .lib file to write")
    parser.add_argument("--verify", action="store_true",
                        help="an array model: step every pin of the written .lib in ngspice "
                             "and print its largest difference from the model (%% of Z_ii)")


def run(args: argparse.Namespace) -> int:
    if is_array_document(args.model):  # an N-port array model: TJ1 ... TJN TREF
        return run_export(args)
    if args.verify:
        raise DataFormatError("--verify: for an array model (a single model's .lib is checked "
                              "by the tests and by compare)")
    pins = Pins.parse(args.pins)  # before reading anything: bad options write nothing
    if args.name is not None:
        check_name(args.name)
    model = ThermalModel.load(args.model)
    name = args.name if args.name is not None else default_name(model, args.output)
    path = export(model, args.output, args.dialect, args.topology, name, pins=pins,
                  temperature=args.temperature)
    ladder = model.with_topology(written_topology(model, args.topology)).ladder
    print(f"wrote {path}: .SUBCKT {name} {' '.join(pins.names)}, {ladder.topology} ladder of "
          f"{ladder.order} stages, Rth = {model.rth:.6g} K/W ({model.reference}), "
          f"{args.dialect} dialect, {args.temperature} temperatures")
    return 0
