"""``spicethermal table1 SOURCE --datasheet CSV|mur880e [--json]``: the paper's Table 1 for a curve.

SOURCE is any curve source (:mod:`spicethermal.identify.sources`): a bundle directory (its first
cooling curve, converted to Zth(t) with the early-time correction, or its first zth table;
``--curve`` picks another), a Zth CSV (``t_s`` and ``zth_k_per_w``, or ``r``), a cooling CSV
(``t_s``, ``tj_c``, optional ``tref_c``; ``--ambient`` when it has no ``tref_c``), or a PyRth
``.txt`` / T3Ster ``.raw`` transient. The measured r(t) is compared with the datasheet named
by ``--datasheet``: a CSV of ``t_s`` and ``r`` (with ``--rth``), or ``mur880e`` for the
MUR880E points of the paper shipped with the package. There is no default device.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from ...core.errors import DataFormatError
from ...identify.datasheet import read_zth_points, table1
from ...identify.sources import early_time_json
from ...io.datasheet import Datasheet, mur880e
from ...io.files import dumps_json
from ._source import SOURCE_HELP, add_source_arguments, read_source_args
from ._types import add_option
from ._types import number as _number
from ._types import positive as _positive

NAME = "table1"
HELP = "measured vs datasheet r(t) with the error in percent (the paper's Table 1)"






def _mask(text: str) -> float | str | None:
    if text in ("auto", "none"):
        return None if text == "none" else text
    value = _number(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f"{text!r} must be >= 0, 'auto' or 'none'")
    return value


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("source", metavar="SOURCE", help=SOURCE_HELP)
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    parser.add_argument("--tj-steady", type=_number, metavar="DEGC",
                        help="junction temperature at the cut for a cooling CSV (default: "
                             "sqrt(t) extrapolation)")
    add_option(parser, "--ambient", old=("--tref", "--tref-steady"), type=_number, dest="tref",
               metavar="DEGC",
                        help="reference temperature of a cooling CSV without tref_c, or the "
                             "temperature at the end of a raw record (anchors the calibration)")
    parser.add_argument("--mask", type=_mask, default="auto", metavar="S|auto|none",
                        help="electrical transient to mask, s (default: auto-detect)")
    parser.add_argument("--datasheet", metavar="CSV|mur880e",
                        help="datasheet r(t) points (t_s, r), or mur880e: the paper's MUR880E "
                             "(required: no device is assumed)")
    parser.add_argument("--rth", type=_positive, metavar="K_PER_W",
                        help="datasheet Rth for a --datasheet CSV with r, also the Rth of a "
                             "normalized SOURCE")
    parser.add_argument("--normalize", choices=("measured", "datasheet"), default="measured",
                        help="divide Zth by the measured Rth (eq. 2, default) or the datasheet's")
    add_source_arguments(parser, rth=False, tref=False)


def run(args: argparse.Namespace) -> int:
    if args.datasheet is None:
        raise DataFormatError("give --datasheet CSV (t_s, r, with --rth) or --datasheet mur880e "
                              "(the paper's MUR880E): no device is assumed")
    if args.datasheet.lower() == "mur880e":
        ds = mur880e()
    else:
        pts = read_zth_points(args.datasheet, rth_k_per_w=args.rth)
        ds = Datasheet(Path(args.datasheet).stem, pts.t_s, pts.r, pts.rth_k_per_w)
    args.rth = ds.rth_k_per_w  # a normalized SOURCE is scaled by the datasheet's Rth
    src = read_source_args(args)
    curve = src.curve(args.curve, early_window_s=args.early_window, mask_s=args.mask,
                      tj_steady_c=args.tj_steady)
    result = table1(curve, ds, normalize=args.normalize)
    if args.json:
        doc = result.to_dict()
        doc["early_time"] = early_time_json(curve)
        print(dumps_json(doc, indent=2))
    else:
        print(result.format())  # the early-time correction included
    return 0
