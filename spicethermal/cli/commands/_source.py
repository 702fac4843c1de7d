"""Options shared by the commands that take a curve, and the reading of SOURCE through
:func:`spicethermal.identify.sources.read_source`."""

from __future__ import annotations

import argparse
import sys
from typing import TYPE_CHECKING

from ...core.errors import DataFormatError
from ...identify.sources import read_source
from ._types import (
    AliasFormatter,
    add_option,
    count,
    listed,
    number,
    positive,
    positive_duration,
    positive_power,
)

if TYPE_CHECKING:  # pragma: no cover
    from ...identify.sources import Source
    from ...io.bundle import Bundle

SOURCE_HELP = ("bundle directory, Zth or datasheet points CSV (t_s, zth_k_per_w or r), cooling "
               "CSV (t_s, tj_c or v_tsp_v), PyRth .txt or T3Ster .raw")


def window(text: str) -> tuple[float, float]:
    """``T1,T2`` in s, 0 < T1 < T2.

    >>> window("1e-4,4e-4")
    (0.0001, 0.0004)
    """
    values = listed(positive_duration)(text)
    if len(values) != 2 or not values[0] < values[1]:
        raise argparse.ArgumentTypeError(f"{text!r}: expected T1,T2 in s with 0 < T1 < T2")
    return values[0], values[1]


def add_source_arguments(parser: argparse.ArgumentParser, *, curve: bool = True,
                         power: bool = True, rth: bool = True, tref: bool = True,
                         early: bool = True) -> None:
    """Add ``--curve``, ``--calibration``, ``--k-factor``, ``--ambient``, ``--power``, ``--rth`` and
    ``--early-window`` (the flags leave out options a command already defines)."""
    group = parser.add_argument_group("reading SOURCE")
    parser.formatter_class = AliasFormatter  # old spellings added to the group stay hidden
    if curve:
        group.add_argument("--curve", type=int, default=0, metavar="INDEX",
                           help="which curve of a bundle: cooling curves first, then zth tables "
                                "(default 0)")
    group.add_argument("--calibration", metavar="CSV",
                       help="TSP calibration (temp_c, v_tsp_v) for a source with raw sensor "
                            "voltage (PyRth .txt, v_tsp_v column); replaces a bundle's or .tco")
    group.add_argument("--k-factor", type=number, dest="k_factor", metavar="MV_PER_K",
                       help="K-factor calibration instead, anchored with --ambient at the end of "
                            "the record")
    if tref:
        add_option(group, "--ambient", old=("--tref",), dest="tref", type=number,
                   metavar="DEGC",
                           help="temperature at the end of the record (anchors the "
                                "calibration), or the reference of a cooling CSV")
    if power:
        group.add_argument("--power", type=positive_power, metavar="W",
                           help="heating power of a PyRth .txt or cooling CSV (default 1 W "
                                "nominal, said in the output)")
    if rth:
        group.add_argument("--rth", type=positive, metavar="K_PER_W",
                           help="Rth of a normalized Zth CSV (column r), held as ΣR = Rth")
    if early:
        group.add_argument("--early-window", type=window, dest="early_window",
                           metavar="T1,T2",
                           help="√t fit window of the early-time correction, s (default: from "
                                "the end of the detected electrical transient)")


def read_source_args(args: argparse.Namespace, source: str | None = None, *,
                     rth: bool = True) -> Source:
    """SOURCE (``args.source`` unless given) read with the shared options; its notes are
    printed on stderr (on stdout they would spoil ``--json``)."""
    src = read_source(source if source is not None else args.source,
                      calibration=getattr(args, "calibration", None),
                      k_factor_mv_per_k=getattr(args, "k_factor", None),
                      tref_c=getattr(args, "tref", None), power_w=getattr(args, "power", None),
                      rth_k_per_w=getattr(args, "rth", None) if rth else None)
    for note in src.notes:
        print(f"{src.path}: {note}", file=sys.stderr)
    return src


def comparable_source(args: argparse.Namespace, source: str, *, rth: bool = True,
                      model_reference: str | None = None,
                      mask_transient: bool = False) -> Bundle:
    """SOURCE as ``compare`` and ``diagnose`` take it (:meth:`Source.comparable`), what was
    done on the way printed on stderr (``rth``: whether ``args.rth`` is the source's Rth;
    ``mask_transient``: leave out the samples fit masks as the electrical transient).

    With ``model_reference``, a source that does not state its reference (any file but a
    bundle, whose manifest does) is taken to ``args.reference``, else to the model's; a
    bundle keeps its own and ``args.reference`` may only repeat it."""
    src = read_source_args(args, source, rth=rth)
    bundle, notes = src.comparable(mask_transient=mask_transient)
    if model_reference is not None:
        given = getattr(args, "reference", None)
        if src.kind == "bundle":
            if given is not None and given != bundle.reference:
                raise DataFormatError(f"{src.path}: the bundle states its reference, "
                                      f"{bundle.reference}; --reference {given} contradicts it")
        else:
            bundle = bundle.with_(reference=given or model_reference)
            if given is None:
                notes.append(f"the file does not state its reference: the model's "
                             f"({model_reference}); --reference says otherwise")
    for note in notes:
        print(f"{src.path}: {note}", file=sys.stderr)
    return bundle


def add_bootstrap_arguments(parser: argparse.ArgumentParser) -> None:
    """``--bootstrap N`` and ``--seed`` (:mod:`spicethermal.fit.bootstrap`)."""
    group = parser.add_argument_group("uncertainty")
    group.add_argument("--bootstrap", type=count, metavar="N",
                       help="residual bootstrap with N resamples: 95 %% bands in the figure and "
                            "the JSON, parameter spreads (off by default; 50 is typical)")
    group.add_argument("--seed", type=int, default=0, help="seed of the bootstrap (default 0)")
