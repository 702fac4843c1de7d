"""``spicethermal export``: write a model as a SPICE subcircuit library: the thermal network
(``.SUBCKT NAME TJ TREF``), or with ``--electrothermal`` the heater as an electrothermal part
(``.SUBCKT NAME A K TJ TREF``: the diode's current follows its fitted Vf(I, T), its I·V heats
the ladder, :mod:`spicethermal.spice.electrothermal`)."""

from __future__ import annotations

import argparse

from ...core.errors import DataFormatError
from ...model import ThermalModel
from ...spice.electrothermal import export_electrothermal, missing_law
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
HELP = ("write MODEL.json as a .lib subcircuit (.SUBCKT NAME TJ TREF, or NAME A K TJ TREF with "
        "--electrothermal; pins and temperature convention as you choose) for ngspice, PSPICE "
        "or LTspice")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("model", metavar="MODEL.json",
                        help="spicethermal-model/4 (/3, /2, /1) file, or an array model "
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
                             "role=NAME items, e.g. case=TC,junction=TJ (default TJ,TREF); with "
                             "--electrothermal anode and cathode first (A,K,TJ,TREF; roles "
                             "anode, cathode), A and K when not named")
    parser.add_argument("--electrothermal", action="store_true",
                        help="the heater as an electrothermal part: the diode's current follows "
                             "the model's fitted Vf(I, T) at the junction temperature and its "
                             "I*V heats the ladder (needs a model with a diode law, "
                             "spicethermal-model/4)")
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
        if args.electrothermal:
            raise DataFormatError("--electrothermal: for a single heater's model with a diode "
                                  "law (an array model is thermal only)")
        return run_export(args)
    if args.verify:
        raise DataFormatError("--verify: for an array model (a single model's .lib is checked "
                              "by the tests and by compare)")
    # before reading anything: bad options write nothing
    pins = Pins.parse(args.pins, electrical=args.electrothermal)
    if args.name is not None:
        check_name(args.name)
    model = ThermalModel.load(args.model)
    if args.electrothermal and missing_law(model, args.model):
        raise DataFormatError(missing_law(model, args.model))
    name = args.name if args.name is not None else default_name(model, args.output)
    write = export_electrothermal if args.electrothermal else export
    path = write(model, args.output, args.dialect, args.topology, name, pins=pins,
                 temperature=args.temperature)
    ladder = model.with_topology(written_topology(model, args.topology)).ladder
    what = "electrothermal part: diode law Vf(I, T) and a " if args.electrothermal else ""
    print(f"wrote {path}: .SUBCKT {name} {' '.join(pins.names)}, {what}{ladder.topology} "
          f"ladder of {ladder.order} stages, Rth = {model.rth:.6g} K/W ({model.reference}), "
          f"{args.dialect} dialect, {args.temperature} temperatures")
    return 0
