"""``spicethermal structure SOURCE [SOURCE2] [--plot FIG.png] [--json]``: structure functions.

Each SOURCE (as for ``spicethermal spectrum``: bundle directory, Zth CSV, PyRth ``.txt``,
T3Ster ``.raw``) goes Zth(t) → time-constant spectrum (NID) → Foster ladder
(``--stages-per-decade``) → exact Cauer ladder → cumulative structure function, ΣC against
ΣR from the junction outwards. With two sources the point where they separate is found
(:func:`spicethermal.identify.structure.separation`: the first ΣR from which
``|Δ log10 ΣC| > --threshold`` holds to the end of the range both resolve) and marked.

``--bootstrap N`` adds a 95 % band of ΣC against ΣR to the figure and, as ``"band"``
(``r_k_per_w``, ``c_j_per_k_lo``, ``c_j_per_k_hi``, ``level``), to each JSON object.

``--json`` output:

* one source: exactly ``{"cumulative": {"r_k_per_w": [...], "c_j_per_k": [...]}}``;
* two sources: a JSON **list** of two such objects, in the order given, each with two more
  keys: ``"source"`` (the argument) and ``"separation"`` (the same comparison in both:
  ``{"r_k_per_w", "c_j_per_k", "first_exceeds_r_k_per_w", "threshold_decades",
  "r_range_k_per_w", "max_difference_decades", "labels"}``, ``r_k_per_w`` null when they
  do not separate).
"""

from __future__ import annotations

import argparse

from ...core.errors import DataFormatError
from ...fit.bootstrap import spectrum_bootstrap
from ...identify.spectrum import time_constant_spectrum
from ...identify.structure import SEPARATION_THRESHOLD, StructureFunction, separation
from ...io.files import dumps_json
from ...viz.plots import fig_structure, fig_structure_band
from ._source import SOURCE_HELP
from ._types import add_option, positive
from .spectrum import add_spectrum_arguments, load_curve, spectrum_options

NAME = "structure"
HELP = "cumulative and differential structure functions; two sources: where they separate"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("sources", metavar="SOURCE", nargs="+",
                        help=f"one or two sources: {SOURCE_HELP}")
    add_option(parser, "--plot", old=("-o", "--output"), metavar="FIG.png",
               help="write the figure (cumulative and differential structure "
                             "functions, separation marked)")
    parser.add_argument("--json", action="store_true",
                        help="print ΣR and ΣC as JSON (a list of two objects for two sources)")
    parser.add_argument("--stages-per-decade", type=positive, default=10.0, metavar="N",
                        help="Foster stages per decade of τ from the spectrum (default 10)")
    parser.add_argument("--threshold", type=positive, default=None, metavar="DECADES",
                        help="separation threshold on |Δ log10 ΣC| (default 0.05)")
    add_spectrum_arguments(parser)  # with --bootstrap


def run(args: argparse.Namespace) -> int:
    if len(args.sources) > 2:
        raise DataFormatError(f"structure takes one or two sources, got {len(args.sources)}")
    functions, bands = [], []
    for source in args.sources:
        curve = load_curve(args, source)
        spec = time_constant_spectrum(curve, **spectrum_options(args))
        functions.append(StructureFunction.from_spectrum(spec, args.stages_per_decade))
        if args.bootstrap:
            bands.append(spectrum_bootstrap(curve, spec, args.bootstrap, args.seed,
                                            args.stages_per_decade, quiet=args.quiet,
                                            **spectrum_options(args)).structure)
    sep = None
    if len(functions) == 2:
        threshold = SEPARATION_THRESHOLD if args.threshold is None else args.threshold
        sep = separation(functions[0], functions[1], threshold_decades=threshold)
    if args.plot and bands:
        fig_structure_band(functions, bands, args.plot, sep)
    elif args.plot:
        fig_structure(functions, args.plot, sep)
    if args.json:
        docs = [sf.to_dict() for sf in functions]
        for doc, band in zip(docs, bands, strict=False):  # only with --bootstrap
            doc["band"] = band.to_dict("r_k_per_w", "c_j_per_k")
        if sep is None:
            print(dumps_json(docs[0]))
        else:
            print(dumps_json([{"source": src, **doc, "separation": sep.to_dict()}
                              for src, doc in zip(args.sources, docs, strict=True)]))
        return 0
    for sf in functions:
        print(sf)
    if sep is not None:
        print(sep)
    if args.plot:
        print(f"wrote figure {args.plot}")
    return 0
