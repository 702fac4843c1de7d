"""``spicethermal spectrum SOURCE [--plot FIG.png] [-o MODEL.json] [--json]``: the spectrum (NID).

SOURCE is any curve source (:mod:`spicethermal.identify.sources`): a measurement bundle
directory (its first cooling curve with the early-time correction, or first ``zth`` table;
``--curve`` picks another), a Zth CSV file (``t_s`` and ``zth_k_per_w``), a cooling CSV, a PyRth
transient ``.txt`` file (time and sensor voltage, converted through ``--calibration CSV`` or
``--k-factor MV_PER_K`` anchored with ``--ambient DEGC`` — there is no default — at
``--power W``, default 1 W nominal) or a T3Ster ``.raw`` record (with its ``.pwr`` and ``.tco``
beside it).

Prints the spectrum's summary, its peaks and the lumped Foster ladder; ``--json`` prints the
spectrum (``spicethermal-spectrum/1``: ``tau_s``, ``r_density_k_per_w`` in K/W per unit ln τ,
``method``, ``resolution_decades``, ``t_resolved_s``, ``rth_k_per_w``) plus the lumped Foster
stages; ``-o MODEL.json`` writes that ladder as a model file for ``export``, as ``fit -o``
does (deprecated: an ``-o`` path ending in .png, .svg or .pdf is the figure, as before
``--plot``; ``--model`` is ``-o``'s old spelling).
``--bootstrap N`` (residual bootstrap, :mod:`spicethermal.fit.bootstrap`) adds the 95 % band of
R(τ) to the figure and ``"bootstrap"`` to the JSON (``spectrum``: ``tau_s``,
``r_density_k_per_w_lo``, ``r_density_k_per_w_hi``, ``level``). The early-time correction (the
√t window and Tj at the cut) goes to stderr and to the JSON as ``"early_time"``.
"""

from __future__ import annotations

import argparse
import sys
from typing import TYPE_CHECKING, Any

from ... import __version__
from ...fit.bootstrap import spectrum_bootstrap
from ...identify.sources import early_time_json
from ...identify.spectrum import time_constant_spectrum
from ...io.files import dumps_json
from ...model import ThermalModel
from ...viz.plots import fig_spectrum, fig_spectrum_band
from ._source import SOURCE_HELP, add_bootstrap_arguments, add_source_arguments, read_source_args
from ._types import add_option, old_figure_output
from ._types import count as _count
from ._types import positive as _positive

if TYPE_CHECKING:  # pragma: no cover
    from ...identify.curves import ZthCurve

NAME = "spectrum"
HELP = "time-constant spectrum of a Zth curve by deconvolution (NID, as T3Ster and PyRth)"






def add_spectrum_arguments(parser: argparse.ArgumentParser) -> None:
    """Options shared by ``spectrum`` and ``structure``: how to read SOURCE, deconvolve and
    bootstrap."""
    add_source_arguments(parser)
    add_bootstrap_arguments(parser)
    parser.add_argument("--method", choices=("bayes", "nnls"), default="bayes",
                        help="deconvolution: Bayesian iteration (default) or NNLS + Tikhonov "
                             "(L-curve)")
    parser.add_argument("--iterations", type=_count, metavar="N",
                        help="Bayesian iterations (default 2000)")
    parser.add_argument("--points-per-decade", type=_count, metavar="N",
                        help="log-time grid density (default 40)")
    parser.add_argument("-q", "--quiet", action="store_true",
                        help="no progress bar on stderr (none either when it is not a terminal)")


def spectrum_options(args: argparse.Namespace) -> dict[str, Any]:
    """Keyword arguments of :func:`~spicethermal.identify.spectrum.time_constant_spectrum`."""
    options: dict[str, Any] = {"method": args.method}
    if args.iterations is not None:
        options["iterations"] = args.iterations
    if args.points_per_decade is not None:
        options["points_per_decade"] = args.points_per_decade
    return options


def load_curve(args: argparse.Namespace, source: str) -> ZthCurve:
    """The Zth curve of ``source`` read with the shared options
    (:mod:`spicethermal.identify.sources`); what was assumed goes to stderr, the early-time
    correction too."""
    curve = read_source_args(args, source).curve(args.curve, early_window_s=args.early_window)
    if curve.early is not None:
        print(f"{curve.label}: early time: {curve.early}", file=sys.stderr)
    return curve


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("source", metavar="SOURCE", help=SOURCE_HELP)
    parser.add_argument("--plot", metavar="FIG.png",
                        help="write the figure (Zth and model, derivative, spectrum)")
    parser.add_argument("--json", action="store_true", help="print the spectrum as JSON")
    parser.add_argument("--stages-per-decade", type=_positive, default=10.0, metavar="N",
                        help="Foster stages per decade of τ when lumping (default 10)")
    parser.add_argument("--order", type=_count, metavar="N",
                        help="lump into exactly N Foster stages instead (Ward merging)")
    add_option(parser, "-o", "--output", old=("--model",), metavar="MODEL.json",
               action="append", help="write the lumped Foster ladder as a model file")
    add_spectrum_arguments(parser)


def run(args: argparse.Namespace) -> int:
    curve = load_curve(args, args.source)
    spec = time_constant_spectrum(curve, **spectrum_options(args))
    foster = spec.to_foster(args.stages_per_decade, order=args.order)
    old_figure_output(args)  # -o FIG.png: the figure, as before --plot
    model_path = args.output[-1] if args.output else None
    sb = None
    if args.bootstrap:

        sb = spectrum_bootstrap(curve, spec, args.bootstrap, args.seed, quiet=args.quiet,
                                **spectrum_options(args))
    if args.plot and sb is not None:

        fig_spectrum_band(spec, sb, args.plot)
    elif args.plot:

        fig_spectrum(spec, args.plot)
    if model_path:

        ThermalModel(foster, reference="ambient", provenance={
            "tool": f"spicethermal {__version__} spectrum", "source": str(args.source),
            "method": spec.method, "resolution_decades": spec.resolution_decades}
        ).save(model_path)
    if args.json:

        out = spec.to_dict()
        out["early_time"] = early_time_json(curve)
        if sb is not None:
            out["bootstrap"] = sb.to_dict()
        out["foster"] = {"r_k_per_w": list(foster.r), "tau_s": list(foster.tau)}
        print(dumps_json(out))
        return 0
    print(spec)
    peaks = ", ".join(f"{x:.3g}" for x in spec.peaks_s())
    print(f"peaks at τ = {peaks or '-'} s")
    print(f"Foster ladder: {foster.order} stages, ΣR = {foster.rth:.4g} K/W")
    for what, path in (("figure", args.plot), ("model", model_path)):
        if path:
            print(f"wrote {what} {path}")
    return 0
