"""``spicethermal fit SOURCE [--order N|auto] [--effect NAME]... -o MODEL.json``.

SOURCE is any curve source (:mod:`spicethermal.identify.sources`): a measurement bundle
directory (its first cooling curve, converted to Zth(t) with the early-time correction, or its
first ``zth`` table; ``--curve`` picks another), a Zth or datasheet points CSV (``t_s`` and
``zth_k_per_w``, or ``r`` with ``--rth``), a cooling CSV, a PyRth ``.txt`` or a T3Ster ``.raw``
(with ``--calibration`` or ``--k-factor`` where the file has none). ΣR = Rth is held whenever
Rth is known: measured by a cooling curve (eq. 1), given in the bundle or by ``--rth``. The
fit's report (order, criterion, R ± u, τ ± u) goes into the model's provenance and its table to
stdout. A bundle with forward-voltage points (``spicethermal-bundle/3``) also gets its
heater's diode law Vf(I, T), fitted to them and the TSP calibration with the ladder's
self-heating (:func:`spicethermal.fit.diode.fit_electrical`): its parameters ± u and residuals
are printed, and the model (``spicethermal-model/4``) keeps it for ``export --electrothermal``.
A bundle whose only curves are an array's ``coupling`` section (heat one, read all,
``spicethermal-bundle/4``) gets the array's N-port network instead
(``docs/array-model-format.md``): ``--order`` and ``--max-order`` count the nodes of each
cell's chain, and the error of every element is printed.
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import replace
from pathlib import Path

from ... import __version__
from ...analysis.diagnose import fit_with_effects
from ...core.errors import DataFormatError
from ...effects import plugin
from ...fit.bootstrap import fit_bootstrap
from ...fit.diode import fit_electrical
from ...fit.ladder import check_rth, fit_model
from ...identify.readings import cooling_tj_c
from ...identify.sources import early_time_json
from ...io.bundle import Bundle
from ...io.files import atomic_write_text
from ...report.tables import foster_table_csv
from ...viz.early_figure import fig_early_time
from ...viz.plots import fig7, fig_fit_band
from ._array import is_array_bundle, run_fit
from ._source import SOURCE_HELP, add_bootstrap_arguments, add_source_arguments, read_source_args
from ._types import count as _count

NAME = "fit"
HELP = "fit an RC ladder (automatic order, ΣR = Rth) to a Zth curve and write a model file"


def _order(text: str) -> int | str:
    if text == "auto":
        return text
    try:
        return _count(text)
    except argparse.ArgumentTypeError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a positive integer or 'auto'") from None






def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("source", metavar="SOURCE", help=SOURCE_HELP)
    parser.add_argument("-o", "--output", metavar="MODEL.json", required=True,
                        help="model file to write (spicethermal-model/3; /4 with the heater's "
                             "diode law when the bundle has forward-voltage points)")
    parser.add_argument("--order", type=_order, default="auto", metavar="N|auto",
                        help="number of RC stages, or auto (default: chosen by BIC)")
    parser.add_argument("--max-order", type=_count, default=10, metavar="N",
                        help="largest order tried by --order auto (default 10)")
    parser.add_argument("--effect", action="append", default=[], metavar="NAME",
                        help="an effect to fit with the ladder (repeatable; default none: the "
                             "linear ladder alone)")
    parser.add_argument("--weighting", choices=("relative", "absolute"), default="relative",
                        help="relative (default: log-domain, every decade of time counts, as "
                             "datasheet and measured curves need) or absolute (K/W) residuals")
    parser.add_argument("--topology", choices=("foster", "cauer"), default="foster",
                        help="topology stored in the model file (exact conversion; default foster)")
    parser.add_argument("--reference", choices=("case", "ambient"),
                        help="what the curve is measured to: junction-to-case or -ambient "
                             "(default: the bundle's reference; ambient for a CSV)")
    parser.add_argument("--plot", metavar="FIG.png",
                        help="also write the fit figure (paper Fig. 7: fit, residuals, ladder)")
    parser.add_argument("--foster-table", metavar="CSV",
                        help="also write the Foster table (r_k_per_w, tau_s, c_j_per_k, "
                             "uncertainties) as CSV")
    parser.add_argument("--early-plot", metavar="FIG.png",
                        help="also draw the early-time (√t) correction: record, masked span, "
                             "fit window, Tj(0)")
    parser.add_argument("-q", "--quiet", action="store_true", help="do not print the fit table")
    add_source_arguments(parser)
    add_bootstrap_arguments(parser)


def _run_with_effects(args: argparse.Namespace, source: Path) -> int:
    """``--effect``: the ladder and the named effects fitted to every data set of a bundle
    (:func:`spicethermal.analysis.diagnose.fit_with_effects`)."""
    for name in args.effect:
        plugin(name)
    if not source.is_dir():
        raise DataFormatError(f"{source}: --effect needs a bundle directory (the effects are "
                              f"fitted to its cooling curves, PWM grid and calibration)")
    bundle = Bundle.read(source)
    model = fit_with_effects(bundle, args.effect,
                             provenance={"tool": f"spicethermal {__version__} fit",
                                         "source": str(source)})
    if args.topology != model.ladder.topology:
        model = model.with_topology(args.topology)
    model, electrical = _with_electrical(model, bundle)
    out = model.save(args.output)
    if not args.quiet:
        print(f"{model.ladder.order}-stage ladder, Rth = {model.rth:.5g} K/W; effects: "
              + "; ".join(f"{e.name} ({e.form}): {e.describe()}" for e in model.effects))
        if electrical is not None:
            print(electrical)
        print(f"wrote {out}")
    return 0


def _with_electrical(model, bundle: Bundle):
    """``model`` with the diode law of the bundle's forward points (and the fit), or as it is."""
    fit = fit_electrical(bundle, model)
    return (model, None) if fit is None else (replace(model, electrical=fit.law), fit)


def _early_plot(src, args: argparse.Namespace, curve) -> Path:
    """The √t figure of cooling curve ``--curve`` of the source (the record as read)."""
    if curve.early is None or args.curve >= len(src.bundle.cooling):
        raise DataFormatError(f"--early-plot: {curve.label} has no early-time correction (a "
                              f"cooling curve with Tj at the cut given, or a Zth table)")
    c = src.bundle.cooling[args.curve]
    return fig_early_time(c.t_s, cooling_tj_c(src.bundle, args.curve), curve.early,
                          args.early_plot, title=f"{curve.label}: early-time correction")


def run(args: argparse.Namespace) -> int:
    if is_array_bundle(args.source):  # heat one, read all: the array's N-port model
        return run_fit(args)
    source = Path(args.source)
    if args.effect:
        return _run_with_effects(args, source)
    src = read_source_args(args)
    curve = src.curve(args.curve, early_window_s=args.early_window)
    held, reference = src.rth_held(args.curve) or args.rth is not None, src.bundle.reference
    rth = args.rth if args.rth is not None else (curve.rth_k_per_w if held else None)
    if args.rth is not None:
        check_rth(curve.t_s, curve.zth_k_per_w, args.rth, curve.label or str(source))
    model, result = fit_model(
        curve, effects=args.effect, order=args.order, rth_k_per_w=rth, hold_rth=held,
        max_order=args.max_order, reference=args.reference or reference, weighting=args.weighting,
        provenance={"tool": f"spicethermal {__version__} fit", "source": str(source),
                    "curve": curve.label or str(source), "early_time": early_time_json(curve)})
    fb = None
    if args.bootstrap:

        fb = fit_bootstrap(result, args.bootstrap, args.seed)
        prov = dict(model.provenance)
        prov["fit"] = {**prov["fit"], "bootstrap": fb.to_dict()}
        model = replace(model, provenance=prov)
    if args.topology != model.ladder.topology:
        model = model.with_topology(args.topology)
    t = [float(x) for x in curve.t_s if x > 0]
    if t:  # the data's time range, where the ladder holds: the .lib header states it
        model = replace(model, provenance={**model.provenance, "valid_t_s": [min(t), max(t)]})
    model, electrical = _with_electrical(model, src.bundle)
    out = model.save(args.output)
    written = [str(out)]
    if args.plot and fb is not None:

        written.append(str(fig_fit_band(result, fb, args.plot, title=curve.label)))
    elif args.plot:

        written.append(str(fig7(result, args.plot, title=curve.label or source.name)))
    if args.foster_table:

        written.append(str(atomic_write_text(args.foster_table, foster_table_csv(
            result.foster, result.u_r_k_per_w, result.u_tau_s))))
    if args.early_plot:
        written.append(str(_early_plot(src, args, curve)))
    if not args.quiet:
        if curve.early is not None:
            print(f"early time: {curve.early}")
        print(result)
        print(f"weighting: {result.weighting}")
        if electrical is not None:
            print(electrical)
        if fb is not None:
            print(f"bootstrap ({fb.n} resamples): u(R) = "
                  + ", ".join(f"{u:.3g}" for u in fb.u_r_k_per_w) + " K/W; u(tau) = "
                  + ", ".join(f"{u:.3g}" for u in fb.u_tau_s) + " s")
        print(f"wrote {', '.join(written)}")
    if not result.converged:  # pragma: no cover - fit_foster raises instead
        print(f"warning: {result.message}", file=sys.stderr)
    return 0
