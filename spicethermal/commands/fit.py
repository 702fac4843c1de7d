"""``spicethermal fit SOURCE [--order N|auto] [--effect NAME]... -o MODEL.json``.

SOURCE is a measurement bundle directory (its first cooling curve, converted to Zth(t) with the
early-time correction, or its first ``zth`` table; ``--curve`` picks another) or a Zth CSV file
with columns ``t_s`` and ``zth_k_per_w`` (absolute) or ``r`` (normalized; needs ``--rth``).
ΣR = Rth is held whenever Rth is known: measured by a cooling curve (eq. 1), given in the
bundle or by ``--rth``. The fit's report (order, criterion, R ± u, τ ± u) goes into the model's
provenance and its table to stdout.
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import replace
from pathlib import Path
from typing import Any

from ..errors import DataFormatError
from ._types import count as _count
from ._types import positive as _positive

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
    parser.add_argument("source", metavar="SOURCE",
                        help="bundle directory, or Zth CSV (t_s and zth_k_per_w, or r with --rth)")
    parser.add_argument("-o", "--output", metavar="MODEL.json", required=True,
                        help="model file to write (spicethermal-model/2)")
    parser.add_argument("--order", type=_order, default="auto", metavar="N|auto",
                        help="number of RC stages, or auto (default: chosen by BIC)")
    parser.add_argument("--max-order", type=_count, default=10, metavar="N",
                        help="largest order tried by --order auto (default 10)")
    parser.add_argument("--rth", type=_positive, metavar="K_PER_W",
                        help="known Rth (K/W), held as ΣR = Rth; needed for a normalized r column")
    parser.add_argument("--curve", type=int, default=0, metavar="INDEX",
                        help="which curve of a bundle to fit: cooling curves first, then zth "
                             "tables (default 0)")
    parser.add_argument("--effect", action="append", default=[], metavar="NAME",
                        help="an effect to fit with the ladder (repeatable)")
    parser.add_argument("--topology", choices=("foster", "cauer"), default="foster",
                        help="topology stored in the model file (exact conversion; default foster)")
    parser.add_argument("--reference", choices=("case", "ambient"),
                        help="what the curve is measured to: junction-to-case or -ambient "
                             "(default: the bundle's reference; ambient for a CSV)")
    parser.add_argument("--plot", metavar="FIG.png",
                        help="also write the fit figure (paper Fig. 7: fit, residuals, ladder)")
    parser.add_argument("-q", "--quiet", action="store_true", help="do not print the fit table")


def _from_csv(path: Path, rth: float | None) -> tuple[Any, bool, str]:
    from ..bundle import ZthTable, read_columns
    from ..curves import ZthCurve

    cols = read_columns(path, ["t_s", ("zth_k_per_w", "r")], label=path.name)
    table = ZthTable(cols["t_s"], zth_k_per_w=cols.get("zth_k_per_w"), r=cols.get("r"),
                     rth_k_per_w=rth, file=path.name, rows=cols.rows)
    if table.normalized and rth is None:
        raise DataFormatError(f"{path.name}: column r is normalized (Zth/Rth): give --rth")
    return ZthCurve.from_table(table, label=path.name), rth is not None, "ambient"


def _from_bundle(path: Path, index: int, rth: float | None) -> tuple[Any, bool, str]:
    from ..bundle import Bundle
    from ..curves import ZthCurve

    bundle = Bundle.read(path)
    n_cool, n_zth = len(bundle.cooling), len(bundle.zth)
    if n_cool + n_zth == 0:
        raise DataFormatError(f"{path}: the bundle has no cooling curve and no zth table to fit")
    if not 0 <= index < n_cool + n_zth:
        raise DataFormatError(f"--curve {index}: the bundle has {n_cool} cooling curve(s) and "
                              f"{n_zth} zth table(s) (valid: 0..{n_cool + n_zth - 1})")
    if index < n_cool:
        c = bundle.cooling[index]
        tref, tref_steady = bundle.cooling_reference_c(index)
        curve = ZthCurve.from_cooling(c.t_s, bundle.cooling_tj_c(index), c.power_w,
                                      c.tj_steady_c, tref, tref_steady,
                                      label=c.file or f"cooling[{index}]")
        held = True  # Rth measured from the steady state (eq. 1)
    else:
        z = bundle.zth[index - n_cool]
        if z.normalized and z.rth_k_per_w is None and rth is None:
            raise DataFormatError(f"{path}: zth table {z.file}: normalized r needs rth_k_per_w "
                                  f"(in bundle.json or --rth)")
        if rth is not None and z.rth_k_per_w is None:
            from dataclasses import replace

            z = replace(z, rth_k_per_w=rth)
        curve = ZthCurve.from_table(z, label=z.file or f"zth[{index - n_cool}]")
        held = z.rth_k_per_w is not None
    return curve, held or rth is not None, bundle.reference


def _run_with_effects(args: argparse.Namespace, source: Path) -> int:
    """``--effect``: the ladder and the named effects fitted to every data set of a bundle
    (:func:`spicethermal.diagnose.fit_with_effects`)."""
    from .. import __version__
    from ..bundle import Bundle
    from ..diagnose import fit_with_effects
    from ..effects import spec

    for name in args.effect:
        spec(name)
    if not source.is_dir():
        raise DataFormatError(f"{source}: --effect needs a bundle directory (the effects are "
                              f"fitted to its cooling curves, PWM grid and calibration)")
    model = fit_with_effects(Bundle.read(source), args.effect, order=args.order,
                             provenance={"tool": f"spicethermal {__version__} fit",
                                         "source": str(source)})
    if args.topology != model.ladder.topology:
        model = model.with_topology(args.topology)
    out = model.save(args.output)
    if not args.quiet:
        print(f"{model.ladder.order}-stage ladder, Rth = {model.rth:.5g} K/W; effects: "
              + "; ".join(f"{e.name} (" + ", ".join(f"{k} = {v:.4g}" for k, v in
                                                     e.params.items()) + ")"
                          for e in model.effects))
        print(f"wrote {out}")
    return 0


def run(args: argparse.Namespace) -> int:
    from .. import __version__
    from ..fit import fit_model

    source = Path(args.source)
    if args.effect:
        return _run_with_effects(args, source)
    if source.is_dir():
        curve, held, reference = _from_bundle(source, args.curve, args.rth)
    elif source.exists():
        curve, held, reference = _from_csv(source, args.rth)
    else:
        raise DataFormatError(f"{source}: no such file or bundle directory")
    rth = args.rth if args.rth is not None else (curve.rth_k_per_w if held else None)
    model, result = fit_model(
        curve, effects=args.effect, order=args.order, rth_k_per_w=rth, hold_rth=held,
        max_order=args.max_order, reference=args.reference or reference,
        provenance={"tool": f"spicethermal {__version__} fit", "source": str(source),
                    "curve": getattr(curve, "label", "") or str(source)})
    if args.topology != model.ladder.topology:
        model = model.with_topology(args.topology)
    t = [float(x) for x in curve.t_s if x > 0]
    if t:  # the data's time range, where the ladder holds: the .lib header states it
        model = replace(model, provenance={**model.provenance, "valid_t_s": [min(t), max(t)]})
    out = model.save(args.output)
    if args.plot:
        from ..plots import fig7

        fig7(result, args.plot, title=getattr(curve, "label", None) or source.name)
    if not args.quiet:
        print(result)
        print(f"wrote {out}" + (f" and {args.plot}" if args.plot else ""))
    if not result.converged:  # pragma: no cover - fit_foster raises instead
        print(f"warning: {result.message}", file=sys.stderr)
    return 0
