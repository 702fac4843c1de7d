"""The array side of ``fit``, ``export`` and ``drive``: what they do when the input is an array
(a bundle with a ``coupling`` section, an ``spicethermal-array-model/1`` file). The commands
call in here; parsing their options stays in their modules.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from ... import __version__
from ...array.check import verify_line
from ...array.data import coupling_from_bundle
from ...array.drive import Limits
from ...array.fit import fit_array
from ...array.model import ArrayModel, is_array_document
from ...array.refresh import CellDrive, LineDrive, drive_patterns, drive_text
from ...array.result import cell_document, line_document, summary
from ...core.errors import DataFormatError
from ...io.bundle import Bundle
from ...io.files import atomic_write_text, dumps_json, read_json, write_json
from ...spice.array_lib import check_array_lib, export_array, pins
from ...spice.lib import check_name, default_name
from ...spice.templates import environment
from ...viz.array import fig_line_heatmap
from ._types import count, positive_duration, quantity
from ._types import number as _number

__all__ = ["add_drive_arguments", "is_array_bundle", "is_array_document", "run_drive",
           "run_export", "run_fit"]


# ------------------------------------------------------------------------------------- fit
def is_array_bundle(source: str) -> bool:
    """Whether ``source`` is a bundle directory whose curves are an array's coupling only.

    Parameters
    ----------
    source : str
        What ``fit`` was given.

    Returns
    -------
    bool
    """
    path = Path(source)
    if path.name == "bundle.json":
        path = path.parent
    if not (path / "bundle.json").is_file():
        return False
    doc = read_json(path / "bundle.json", root=path)
    return isinstance(doc, Mapping) and doc.get("coupling") is not None \
        and not doc.get("cooling") and not doc.get("zth")


def run_fit(args: argparse.Namespace) -> int:
    """``fit BUNDLE`` of an array: the N-port network, written as an array model.

    Parameters
    ----------
    args : argparse.Namespace
        ``fit``'s options.

    Returns
    -------
    int
    """
    for flag, given in (("--effect", args.effect), ("--bootstrap", args.bootstrap),
                        ("--foster-table", args.foster_table), ("--early-plot", args.early_plot),
                        ("--plot", args.plot)):
        if given:
            raise DataFormatError(f"{flag}: not for an array (its fit prints the error of every "
                                  f"element)")
    bundle = Bundle.read(args.source)
    data = coupling_from_bundle(bundle)
    fit = fit_array(data, order=args.order, max_order=args.max_order, provenance={
        "tool": f"spicethermal {__version__} fit", "source": str(args.source),
        "device": bundle.device})
    out = fit.model.save(args.output)
    if not args.quiet:
        print(fit)
        print(fit.table())
        for t in fit.trials:
            print(f"order {t.order}: BIC {t.bic:.1f}, rms {100 * t.rms:.3f} %, worst element "
                  f"{100 * t.max_error:.2f} %")
        print(f"wrote {out}")
    return 0


# ---------------------------------------------------------------------------------- export
def run_export(args: argparse.Namespace) -> int:
    """``export ARRAY.json``: the N-port ``.lib``.

    Parameters
    ----------
    args : argparse.Namespace
        ``export``'s options.

    Returns
    -------
    int
    """
    if args.topology is not None or args.pins != "TJ,TREF" or args.temperature != "absolute":
        raise DataFormatError("--topology, --pins and --temperature are not for an array: its "
                              ".lib is the fitted network itself, pins TJ1 ... TJN TREF (drive "
                              "TREF with the ambient, or 0 V for rises)")
    if args.name is not None:
        check_name(args.name)
    model = ArrayModel.load(args.model)
    name = args.name if args.name is not None else default_name(model, args.output)
    path = export_array(model, args.output, args.dialect, name)
    print(f"wrote {path}: .SUBCKT {name} {' '.join(pins(model))}, {len(model.nodes)} nodes, "
          f"{len(model.resistors)} resistors, {args.dialect} dialect")
    if args.verify:
        check = check_array_lib(model, args.dialect, lib_text=path.read_text(), name=name)
        worst = ", ".join(f"{k} {100 * v:.3f} %" for k, v in check["per_port"].items())
        print(f"ngspice ({args.dialect} dialect, {check['runs']} step runs, "
              f"{check['t_s'][0]:.3g}-{check['t_s'][1]:.3g} s): largest difference from the "
              f"model {100 * check['max_error']:.3f} % of Z_ii (per heated pin: {worst})")
    return 0


# ----------------------------------------------------------------------------------- drive
def add_drive_arguments(parser: argparse.ArgumentParser) -> None:
    """The options of ``drive`` for an array model.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        ``drive``'s parser.
    """
    group = parser.add_argument_group("an array model (spicethermal-array-model/1)")
    group.add_argument("--actuation", type=_number, metavar="C",
                       help="a dot is up at or above this temperature (needed for an array)")
    group.add_argument("--margin", type=quantity("K"), metavar="K",
                       help="a dot that must stay down stays this far below the actuation "
                            "temperature (default: --tol)")
    group.add_argument("--text", action="append", metavar="LINE",
                       help="a line of text to show in six-dot Braille (repeatable: one line "
                            "after the other)")
    group.add_argument("--patterns", metavar="FILE.json",
                       help='instead of --text: [{"up": ["D1", "D3"], "t_s": 0}, ...] (t_s '
                            'optional: each pattern as soon as the previous one is complete)')
    group.add_argument("--cells", type=count, default=40, metavar="N",
                       help="cells in the display line (default 40)")
    group.add_argument("--dwell", type=positive_duration, default=None, metavar="S",
                       help="reading time a completed line stays before the next (default 0)")
    group.add_argument("--report", metavar="DIR",
                       help="write the HTML report (heat maps, refresh times, violations)")


def _limits(args: argparse.Namespace, model: ArrayModel) -> Limits:
    if args.actuation is None:
        raise DataFormatError("--actuation C: an array drive needs the actuation temperature")
    p_max = args.p_max
    if p_max is None:  # the lone cell's DC power whose steady state is t_max
        p_max = (args.t_max - args.ambient) / float(np.max(np.diag(model.modes.dc())))
    return Limits(args.ambient, args.t_max, args.target, args.tol, args.actuation,
                  args.tol if args.margin is None else args.margin, p_max, args.f_pwm)


def _patterns(path: str, model: ArrayModel) -> tuple[list[tuple[bool, ...]], list[float] | None]:
    doc = read_json(path)
    names = [p.name for p in model.ports]
    if not isinstance(doc, list) or not doc:
        raise DataFormatError(f"{path}: a non-empty list of patterns ({{\"up\": [...]}})")
    ups, times = [], []
    for k, entry in enumerate(doc):
        up = entry.get("up") if isinstance(entry, dict) else None
        if not isinstance(up, list) or any(u not in names for u in up):
            raise DataFormatError(f"{path}, pattern {k + 1}: 'up' must list ports of the model "
                                  f"({', '.join(names)})")
        ups.append(tuple(n in up for n in names))
        times.append(entry.get("t_s"))
    if all(t is None for t in times):
        return ups, None
    if any(not isinstance(t, int | float) or isinstance(t, bool) for t in times) \
            or times[0] != 0 or any(b <= a for a, b in zip(times, times[1:], strict=False)):
        raise DataFormatError(f"{path}: give every pattern a t_s (the first 0, increasing) or "
                              f"none")
    return ups, [float(t) for t in times]


def _as_line(cd: CellDrive) -> LineDrive:
    names = tuple(f"pattern {k + 1}" for k in range(len(cd.starts)))
    return LineDrive(names, 1, cd.starts, cd.ours.refresh_s, {"cell": cd}, ("cell",))


def _report(directory: str, doc: dict, line: LineDrive) -> Path:
    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    figure = fig_line_heatmap(line, out / "heatmap.png")
    write_json(out / "drive.json", doc)
    page = environment().get_template("report/array.html.j2").render(
        version=__version__, doc=doc, text=summary(doc), figure=figure.name)
    return atomic_write_text(out / "index.html", page)


def run_drive(args: argparse.Namespace) -> int:
    """``drive ARRAY.json``: refresh patterns or lines of text, against the baselines.

    Parameters
    ----------
    args : argparse.Namespace
        ``drive``'s options.

    Returns
    -------
    int
    """
    for flag, bad in (("--node", args.node != 0), ("--release", args.release is not None),
                      ("--keep-warm", args.keep_warm != 0), ("--spice", args.spice),
                      ("--circuit", args.circuit)):
        if bad:
            raise DataFormatError(f"{flag}: not for an array (its dots are its ports)")
    if (args.text is None) == (args.patterns is None):
        raise DataFormatError("an array drive needs --text LINE (repeatable) or --patterns FILE")
    spice = "ngspice" if args.engine == "auto" else args.engine
    model = ArrayModel.load(args.model)
    lim = _limits(args, model)

    def progress(done: int, total: int) -> None:
        if not args.quiet:
            print(f"planned line {done} of {total}", file=sys.stderr)

    if args.text is not None:
        line = drive_text(model, args.text, lim, args.cells, args.dwell or 0.0, progress)
        checks = verify_line(line, spice) if args.verify else None
        doc = line_document(line, checks)
    else:
        ups, starts = _patterns(args.patterns, model)
        cd = drive_patterns(model, ups, lim, starts)
        line = _as_line(cd)
        checks = verify_line(line, spice) if args.verify else None
        doc = cell_document(cd, checks)
    written = []
    if args.plot:
        written.append(str(fig_line_heatmap(line, args.plot)))
    if args.report:
        written.append(str(_report(args.report, doc, line)))
    if args.json:
        print(dumps_json(doc, indent=2))
        return 0
    print(summary(doc))
    if written:
        print("wrote " + " and ".join(written))
    return 0
