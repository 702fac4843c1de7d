"""``spicethermal batch SOURCES... -o OUTDIR [--workers N | --scheduler ADDRESS] [--resume]``.

Every bundle directory or Zth CSV under SOURCES is fitted (automatic order), diagnosed and
exported as a ``.lib`` on Dask: a local cluster of ``--workers`` processes (default one per
core), or any running scheduler (``--scheduler tcp://host:8786``). One row per input goes into
``OUTDIR/results.csv`` (and ``results.parquet`` with pyarrow); each device's model and ``.lib``
into ``OUTDIR/devices/NAME/`` as it finishes. Then the population's outliers (and why), its
typical and worst-case ladders, a PWM peak table and an HTML report (``OUTDIR/index.html``).
``--simulate N`` first writes a simulated population (manufacturing spread, planted voided die
attaches) into ``OUTDIR/population/`` and characterizes it. Needs ``pip install
'spicethermal[batch]'``.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from ...batch.device import Options
from ...batch.population import write_population
from ...batch.runner import check_output, cluster_client, find_sources, run_batch
from ...batch.summary import summarize
from ...core.errors import DataFormatError
from ...effects import plugin
from ...spice.lib import DIALECTS, TOPOLOGIES
from ._types import count as _count
from ._types import frequency, positive_power
from ._types import index as _index
from ._types import listed as _listed
from ._types import positive as _positive

NAME = "batch"
HELP = ("characterize many devices at once on Dask: fit, diagnose, export each, then the "
        "population's outliers, typical/worst-case ladders and PWM peak spread")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("sources", metavar="SOURCES", nargs="*",
                        help="bundle directories, Zth CSV files, or directories holding them")
    parser.add_argument("-o", "--output", metavar="OUTDIR", required=True,
                        help="output directory (results.csv, devices/, spread/, index.html)")
    where = parser.add_mutually_exclusive_group()
    where.add_argument("--workers", type=_count, metavar="N",
                       help="processes of the local Dask cluster (default: one per core)")
    where.add_argument("--scheduler", metavar="ADDRESS",
                       help="run on this Dask scheduler instead (e.g. tcp://host:8786)")
    parser.add_argument("--resume", action="store_true",
                        help="continue an interrupted batch in OUTDIR: inputs whose content "
                             "already has a result are not redone")
    parser.add_argument("--max-order", type=_count, default=10, metavar="N",
                        help="largest ladder order tried (default 10)")
    parser.add_argument("--effect", action="append", metavar="NAME",
                        help="candidate effect of the diagnosis (repeatable; default every "
                             "catalogued effect)")
    parser.add_argument("--no-diagnose", action="store_true", help="fit and export only")
    parser.add_argument("--dialect", choices=DIALECTS, default="ngspice",
                        help="syntax of the .lib files: ngspice (default), pspice or ltspice")
    parser.add_argument("--topology", choices=TOPOLOGIES, default=None,
                        help="network of the models and .lib files (default foster)")
    pwm = parser.add_argument_group("PWM peak table over the population")
    pwm.add_argument("--power", type=positive_power, metavar="W",
                     help="pulse power, W (default: the devices' own, the median of the powers "
                          "of their fitted cooling curves; 1 W when no input gives one)")
    pwm.add_argument("--freq", type=_listed(frequency), default=(100.0, 1e3, 1e4),
                     metavar="HZ,...", help="frequencies (default 100,1000,10000)")
    pwm.add_argument("--duty", type=_listed(_positive), default=(0.1, 0.5, 0.9),
                     metavar="D,...", help="duty cycles in (0, 1] (default 0.1,0.5,0.9)")
    sim = parser.add_argument_group("simulated population")
    sim.add_argument("--simulate", type=_count, metavar="N",
                     help="write N simulated devices into OUTDIR/population and use them")
    sim.add_argument("--seed", type=_index, default=0, help="seed of --simulate (default 0)")
    parser.add_argument("-q", "--quiet", action="store_true",
                        help="no progress bar and no summary")


def run(args: argparse.Namespace) -> int:
    t0 = time.perf_counter()
    if any(d > 1 for d in args.duty):
        raise DataFormatError(f"--duty {max(args.duty):g}: a duty cycle is at most 1")
    for name in args.effect or ():
        plugin(name)
    sources = list(args.sources)
    out = Path(args.output)
    if sources:
        find_sources(sources, exclude=out)  # every source exists, before anything is written
    check_output(out, args.resume)
    if args.simulate:

        population = out / "population"
        if not (args.resume and (population / "population.json").exists()):
            write_population(population, args.simulate, args.seed)
        sources.append(str(population))
    if not sources:
        raise DataFormatError("give SOURCES (bundle directories or Zth CSV files) or "
                              "--simulate N")
    options = Options(max_order=args.max_order, diagnose=not args.no_diagnose,
                      effects=tuple(args.effect) if args.effect else None,
                      dialect=args.dialect, topology=args.topology)
    with cluster_client(args.scheduler, args.workers) as client:
        batch = run_batch(sources, out, client=client, options=options, resume=args.resume,
                          progress=not args.quiet)
    summary = summarize(batch.results, out, power_w=args.power, freqs_hz=args.freq,
                        duties=args.duty, dialect=args.dialect,
                        elapsed_s=time.perf_counter() - t0)
    errors = sum(1 for r in batch.rows if r.get("error"))
    if not args.quiet:
        twins = [r for r in batch.rows if r.get("duplicate_of")]
        print(f"{len(batch.rows)} inputs ({batch.computed} computed, {batch.reused} reused), "
              f"{errors} with an error, {len(twins)} duplicate{'' if len(twins) == 1 else 's'}"
              f", {len(summary.outliers)} outlier{'' if len(summary.outliers) == 1 else 's'}")
        for r in twins:
            print(f"  duplicate {r['name']}: the same content as {r['duplicate_of']} (counted "
                  f"once)")
        print(f"PWM peaks at {summary.power_w:.4g} W ({summary.power_origin})")
        for o in summary.outliers:
            print(f"  outlier {summary.names[o.index]}: {o.reason}")
        print(f"wrote {out / 'results.csv'} and {summary.page}")
    if errors and not args.quiet:
        print(f"{errors} input(s) failed: see the error column of results.csv",
              file=sys.stderr)
    return 0
