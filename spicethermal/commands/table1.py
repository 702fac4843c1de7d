"""``spicethermal table1 SOURCE [--json]``: the paper's Table 1 for a measured curve.

SOURCE is a bundle directory (its first cooling curve, converted to Zth(t) with the
early-time correction, or its first zth table; ``--curve`` picks another), a CSV file — a
Zth curve (``t_s`` and ``zth_k_per_w``, or ``r``) or a cooling curve (``t_s``, ``tj_c``,
optional ``tref_c``; ``--tref-steady`` when it has no ``tref_c``) — or a PyRth ``.txt`` /
T3Ster ``.raw`` transient. The measured r(t) is compared with the MUR880E datasheet points
shipped with the package (or ``--datasheet`` CSV with ``t_s`` and ``r``, and ``--rth``).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from ..errors import DataFormatError
from ..files import dumps_json
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
    parser.add_argument("source", metavar="SOURCE",
                        help="bundle directory, Zth or cooling CSV, PyRth .txt or T3Ster .raw")
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    parser.add_argument("--curve", type=int, default=0, metavar="INDEX",
                        help="which curve of a bundle: cooling curves first, then zth tables")
    parser.add_argument("--power", type=_positive, default=1.0, metavar="W",
                        help="power before the cut for a cooling CSV (r(t) does not depend "
                             "on it; default 1)")
    parser.add_argument("--tj-steady", type=_number, metavar="DEGC",
                        help="junction temperature at the cut for a cooling CSV (default: "
                             "sqrt(t) extrapolation)")
    parser.add_argument("--tref-steady", type=_number, metavar="DEGC",
                        help="reference temperature for a cooling CSV without tref_c")
    parser.add_argument("--mask", type=_mask, default="auto", metavar="S|auto|none",
                        help="electrical transient to mask, s (default: auto-detect)")
    parser.add_argument("--datasheet", metavar="CSV",
                        help="datasheet r(t) points (t_s, r); default: the MUR880E of the paper")
    parser.add_argument("--rth", type=_positive, metavar="K_PER_W",
                        help="datasheet Rth for --datasheet (default 1.51, the MUR880E)")
    parser.add_argument("--normalize", choices=("measured", "datasheet"), default="measured",
                        help="divide Zth by the measured Rth (eq. 2, default) or the datasheet's")


def _curve(args: argparse.Namespace, rth_default: float):
    from ..bundle import Bundle, read_columns
    from ..curves import ZthCurve
    from ..importers import read_pyrth, read_t3ster

    path = Path(args.source)
    options = {"mask_s": args.mask}
    if path.is_dir() or path.name == "bundle.json":
        return Bundle.read(path), options
    if not path.exists():
        raise DataFormatError(f"{path}: no such file or bundle directory")
    suffix = path.suffix.lower()
    if suffix == ".raw":
        return read_t3ster(path), options
    if suffix == ".txt":
        return read_pyrth(path), options
    cols = read_columns(path, ["t_s", ("zth_k_per_w", "r", "tj_c", "v_tsp_v")],
                        ["tref_c"])
    if "zth_k_per_w" in cols or "r" in cols:
        return ZthCurve.from_points(cols["t_s"], cols.get("zth_k_per_w"), r=cols.get("r"),
                                    rth_k_per_w=rth_default if "r" in cols else None,
                                    label=path.name), options
    if "tj_c" not in cols:
        raise DataFormatError(f"{path}: raw v_tsp_v needs a calibration; put the curve in a "
                              f"bundle with one")
    if "tref_c" not in cols and args.tref_steady is None:
        raise DataFormatError(f"{path}: a cooling curve needs a reference: a tref_c column "
                              f"or --tref-steady")
    return ZthCurve.from_cooling(cols["t_s"], cols["tj_c"], args.power, args.tj_steady,
                                 cols.get("tref_c"), args.tref_steady, mask_s=args.mask,
                                 label=path.name), options


def run(args: argparse.Namespace) -> int:
    from ..bundle import Bundle
    from ..curves import ZthCurve
    from ..datasheet import Datasheet, mur880e, read_zth_points, table1

    if args.datasheet:
        rth = args.rth if args.rth is not None else 1.51
        pts = read_zth_points(args.datasheet, rth_k_per_w=rth)
        ds = Datasheet(Path(args.datasheet).stem, pts.t_s, pts.r, pts.rth_k_per_w)
    else:
        ds = mur880e()
    source, options = _curve(args, ds.rth_k_per_w)
    if isinstance(source, Bundle):
        curves = ZthCurve.from_bundle(source, **options)
        if not 0 <= args.curve < len(curves):
            raise DataFormatError(f"{args.source}: --curve {args.curve} does not exist (the "
                                  f"bundle has {len(curves)} curves)")
        source = curves[args.curve]
    result = table1(source, ds, normalize=args.normalize)
    if args.json:
        print(dumps_json(result.to_json(), indent=2))
    else:
        print(result.format())
    return 0
