"""``spicethermal spectrum SOURCE [--plot FIG.png] [-o MODEL.json] [--json]``: the spectrum (NID).

SOURCE is a measurement bundle directory (its first cooling curve with the early-time
correction, or first ``zth`` table; ``--curve`` picks another), a Zth CSV file (``t_s`` and
``zth_k_per_w``), a PyRth transient ``.txt`` file (time and sensor voltage, converted through
``--calibration CSV`` — default: the calibration of the PyRth MOSFET files — at ``--power W``,
default 1 W) or a T3Ster ``.raw`` record (with its ``.pwr`` and ``.tco`` beside it).

Prints the spectrum's summary, its peaks and the lumped Foster ladder; ``--json`` prints the
spectrum (``spicethermal-spectrum/1``: ``tau_s``, ``r_density_k_per_w`` in K/W per unit ln τ,
``method``, ``resolution_decades``, ``t_resolved_s``, ``rth_k_per_w``) plus the lumped Foster
stages; ``-o MODEL.json`` writes that ladder as a model file for ``export`` (an ``-o`` path
ending in .png, .svg or .pdf is the figure, as before ``--plot``; ``--model`` is ``-o``'s old
spelling).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..errors import DataFormatError
from ._types import add_option
from ._types import count as _count
from ._types import positive as _positive

if TYPE_CHECKING:  # pragma: no cover
    from ..curves import ZthCurve

NAME = "spectrum"
HELP = "time-constant spectrum of a Zth curve by deconvolution (NID, as T3Ster and PyRth)"






def add_source_arguments(parser: argparse.ArgumentParser) -> None:
    """Options shared by ``spectrum`` and ``structure``: how to read SOURCE and deconvolve."""
    parser.add_argument("--curve", type=int, default=0, metavar="INDEX",
                        help="which curve of a bundle: cooling curves first, then zth tables "
                             "(default 0)")
    parser.add_argument("--calibration", metavar="CSV",
                        help="TSP calibration (temp_c, v_tsp_v) for a PyRth .txt source "
                             "(default: the PyRth MOSFET files' calibration)")
    parser.add_argument("--power", type=_positive, metavar="W",
                        help="heating power step for a PyRth .txt source (default 1 W)")
    parser.add_argument("--method", choices=("bayes", "nnls"), default="bayes",
                        help="deconvolution: Bayesian iteration (default) or NNLS + Tikhonov "
                             "(L-curve)")
    parser.add_argument("--iterations", type=_count, metavar="N",
                        help="Bayesian iterations (default 2000)")
    parser.add_argument("--points-per-decade", type=_count, metavar="N",
                        help="log-time grid density (default 40)")


def spectrum_options(args: argparse.Namespace) -> dict[str, Any]:
    """Keyword arguments of :func:`~spicethermal.spectrum.time_constant_spectrum`."""
    options: dict[str, Any] = {"method": args.method}
    if args.iterations is not None:
        options["iterations"] = args.iterations
    if args.points_per_decade is not None:
        options["points_per_decade"] = args.points_per_decade
    return options


def load_curve(source: str | Path, *, curve: int = 0, calibration: str | Path | None = None,
               power_w: float | None = None) -> ZthCurve:
    """The Zth curve of SOURCE: a bundle directory, a Zth CSV, a PyRth ``.txt`` or a T3Ster
    ``.raw`` file (see the module docstring)."""
    from dataclasses import replace

    from ..curves import ZthCurve
    from .fit import _from_bundle, _from_csv

    path = Path(source)
    if not path.exists():
        raise DataFormatError(f"{path}: no such file or bundle directory")
    if path.is_dir():
        zc = _from_bundle(path, curve, None)[0]
        return replace(zc, label=f"{path.name}/{zc.label}" if zc.label else path.name)
    suffix = path.suffix.lower()
    if suffix in (".txt", ".raw"):
        from ..importers import PYRTH_MOSFET_CALIBRATION, read_pyrth, read_t3ster

        if suffix == ".raw":
            bundle = read_t3ster(path)
        else:
            cal: Any = PYRTH_MOSFET_CALIBRATION
            if calibration is not None:
                from ..bundle import CalibrationTable, read_columns

                cols = read_columns(calibration, ["temp_c", "v_tsp_v"],
                                    label=Path(calibration).name)
                cal = CalibrationTable(cols["temp_c"], cols["v_tsp_v"],
                                       file=Path(calibration).name, rows=cols.rows)
            bundle = read_pyrth(path, calibration=cal,
                                power_w=1.0 if power_w is None else power_w)
        (zc,) = ZthCurve.from_bundle(bundle)
        return replace(zc, label=path.stem)
    return _from_csv(path, None)[0]


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("source", metavar="SOURCE",
                        help="bundle directory, Zth CSV (t_s, zth_k_per_w), PyRth .txt or "
                             "T3Ster .raw")
    parser.add_argument("--plot", metavar="FIG.png",
                        help="write the figure (Zth and model, derivative, spectrum)")
    parser.add_argument("--json", action="store_true", help="print the spectrum as JSON")
    parser.add_argument("--stages-per-decade", type=_positive, default=10.0, metavar="N",
                        help="Foster stages per decade of τ when lumping (default 10)")
    parser.add_argument("--order", type=_count, metavar="N",
                        help="lump into exactly N Foster stages instead (Ward merging)")
    add_option(parser, "-o", "--output", old=("--model",), metavar="MODEL.json",
               action="append", help="write the lumped Foster ladder as a model file")
    add_source_arguments(parser)


def run(args: argparse.Namespace) -> int:
    from ..spectrum import time_constant_spectrum

    curve = load_curve(args.source, curve=args.curve, calibration=args.calibration,
                       power_w=args.power)
    spec = time_constant_spectrum(curve, **spectrum_options(args))
    foster = spec.to_foster(args.stages_per_decade, order=args.order)
    model_path = None
    for path in args.output or ():  # -o FIG.png: the figure, as before --plot
        if Path(path).suffix.lower() in (".png", ".svg", ".pdf"):
            args.plot = args.plot or path
        else:
            model_path = path
    if args.plot:
        from ..plots import fig_spectrum

        fig_spectrum(spec, args.plot)
    if model_path:
        from .. import __version__
        from ..model import ThermalModel

        ThermalModel(foster, reference="ambient", provenance={
            "tool": f"spicethermal {__version__} spectrum", "source": str(args.source),
            "method": spec.method, "resolution_decades": spec.resolution_decades}
        ).save(model_path)
    if args.json:
        out = spec.to_dict()
        out["foster"] = {"r_k_per_w": list(foster.r), "tau_s": list(foster.tau)}
        print(json.dumps(out))
        return 0
    print(spec)
    peaks = ", ".join(f"{x:.3g}" for x in spec.peaks_s())
    print(f"peaks at τ = {peaks or '-'} s")
    print(f"Foster ladder: {foster.order} stages, ΣR = {foster.rth:.4g} K/W")
    for what, path in (("figure", args.plot), ("model", model_path)):
        if path:
            print(f"wrote {what} {path}")
    return 0
