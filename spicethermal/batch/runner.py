"""Running a batch on Dask: find the inputs, skip those already done (``--resume``), send the
rest to a cluster, write each device's results atomically as they arrive, and build the
results table.

Layout of the output directory::

    OUTDIR/devices/NAME/model.json     spicethermal-model/3
    OUTDIR/devices/NAME/NAME.lib       .SUBCKT NAME TJ TREF
    OUTDIR/devices/NAME/result.json    the row, the measured Zth(t); written last: its
                                       presence means the device is done
    OUTDIR/results.csv (+ .parquet)    one row per input (columns :data:`~.device.COLUMNS`)

Resuming is keyed by the content hash of each input: an input whose bytes have a finished,
error-free ``result.json`` under its name is not recomputed; an edited input is (and so is a
renamed one, whose results would live under another name).
A worker that dies (killed, out of memory) is replaced by its nanny and the scheduler retries
its task on another worker, up to ``distributed.scheduler.allowed-failures`` times (Dask's
default, 3); after that the device gets an error row.
"""

from __future__ import annotations

import csv
import io
import logging
import os
import sys
import uuid
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..core.errors import DataFormatError, SpiceThermalError
from ..io.bundle import MANIFEST
from ..io.files import atomic_open, atomic_write_text, dumps_json, read_json
from .device import COLUMNS, Options, Source, characterize, make_row

__all__ = ["BatchRun", "check_output", "cluster_client", "find_sources", "load_results",
           "mark_duplicates", "run_batch", "write_table"]

RESULT = "result.json"


@dataclass(frozen=True)
class BatchRun:
    """What :func:`run_batch` did: every result (``{"row", "model", "curve"}``, in input
    order), how many were computed now and how many reused from an earlier run."""

    results: tuple[dict[str, Any], ...]
    computed: int
    reused: int

    @property
    def rows(self) -> list[dict[str, Any]]:
        """The results table's rows."""
        return [r["row"] for r in self.results]


def find_sources(paths: Sequence[str | os.PathLike], exclude: Path | None = None
                 ) -> list[tuple[Path, str]]:
    """Every input under ``paths``, sorted, with a unique output name each.

    A directory with ``bundle.json`` is a bundle; any other directory is searched (hidden
    entries and ``exclude``, the output directory, are skipped) for bundles and ``.csv``
    curve files; a file named on the command line is a curve whatever its suffix.

    >>> import tempfile, pathlib
    >>> root = pathlib.Path(tempfile.mkdtemp())
    >>> for p in ("a/x.csv", "b/x.csv", "c/bundle.json"):
    ...     (root / p).parent.mkdir(parents=True, exist_ok=True); _ = (root / p).write_text("")
    >>> [(p.relative_to(root).as_posix(), n) for p, n in find_sources([root])]
    [('a/x.csv', 'x'), ('b/x.csv', 'x_2'), ('c', 'c')]
    """
    found: list[Path] = []
    skip = exclude.resolve() if exclude is not None else None
    for given in map(Path, paths):
        if not given.exists():
            raise DataFormatError(f"{given}: no such file or directory")
        if given.is_file() or (given / MANIFEST).is_file():
            found.append(given)
            continue
        for root, dirs, files in os.walk(given):
            here = Path(root)
            if skip is not None and here.resolve() == skip:
                dirs[:] = []
                continue
            if (here / MANIFEST).is_file():
                found.append(here)
                dirs[:] = []
                continue
            dirs[:] = sorted(d for d in dirs if not d.startswith("."))
            found += [here / f for f in sorted(files)
                      if f.lower().endswith(".csv") and not f.startswith(".")]
    if not found:
        raise DataFormatError(f"{', '.join(map(str, paths))}: no bundle directory or .csv "
                              f"curve found")
    names: dict[str, int] = {}
    out = []
    for path in found:
        stem = path.stem if path.is_file() else path.resolve().name
        names[stem] = names.get(stem, 0) + 1
        out.append((path, stem if names[stem] == 1 else f"{stem}_{names[stem]}"))
    return out


def load_results(out_dir: str | os.PathLike) -> dict[tuple[str, str], dict[str, Any]]:
    """The finished results in ``out_dir/devices``, keyed by (input content hash, output
    name): error rows are left out (they are recomputed on resume), and so is a result file
    that cannot be read (its device is recomputed)."""
    done = {}
    for path in sorted(Path(out_dir, "devices").glob(f"*/{RESULT}")):
        try:
            record = read_json(path)
            row = record["row"]
        except (DataFormatError, KeyError, TypeError):
            continue
        if row.get("sha256") and not row.get("error"):
            done[row["sha256"], row["name"]] = record
    return done


def check_output(out_dir: str | os.PathLike, resume: bool) -> None:
    """Refuse an output directory that holds an earlier batch's results unless resuming."""
    if not resume and any(Path(out_dir, "devices").glob(f"*/{RESULT}")):
        raise DataFormatError(f"{out_dir}: holds the results of an earlier batch; give "
                              f"--resume to continue it, or another output directory")


def _save(out: Path, result: dict[str, Any]) -> dict[str, Any]:
    """Write one device's files atomically, ``result.json`` last; return the stored record."""
    row = result["row"]
    folder = out / "devices" / row["name"]
    if result.get("model") is not None:
        atomic_write_text(folder / "model.json", dumps_json(result["model"], indent=2) + "\n")
    if result.get("lib") is not None:
        atomic_write_text(folder / f"{row['name']}.lib", result["lib"])
    record = {"row": row, "model": result.get("model"), "curve": result.get("curve")}
    atomic_write_text(folder / RESULT, dumps_json(record) + "\n")
    return record


def write_table(rows: Sequence[dict[str, Any]], out_dir: str | os.PathLike) -> list[Path]:
    """``results.csv`` (and ``results.parquet`` when pyarrow is installed), atomically."""
    out = Path(out_dir)
    text = io.StringIO()
    writer = csv.DictWriter(text, fieldnames=COLUMNS, extrasaction="ignore", lineterminator="\n")
    writer.writeheader()
    for row in rows:
        writer.writerow({k: ("" if row.get(k) is None else row[k]) for k in COLUMNS})
    paths = [atomic_write_text(out / "results.csv", text.getvalue())]
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        return paths
    table = pa.Table.from_pylist([{k: row.get(k) for k in COLUMNS} for row in rows])
    with atomic_open(out / "results.parquet", "wb") as handle:
        pq.write_table(table, handle)
    return paths + [out / "results.parquet"]


@contextmanager
def cluster_client(scheduler: str | None = None, workers: int | None = None) -> Iterator[Any]:
    """A ``dask.distributed`` client: on ``scheduler`` (``tcp://host:port``) if given, else
    on a new :class:`~distributed.LocalCluster` of ``workers`` single-threaded processes
    (default: one per core)."""
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        raise SpiceThermalError("batch needs Dask: pip install 'spicethermal[batch]'") from None
    if scheduler:
        try:
            client = Client(scheduler, timeout="10s")
        except (OSError, TimeoutError, ValueError) as exc:
            raise SpiceThermalError(f"--scheduler {scheduler}: cannot connect ({exc})"
                                    ) from None
        with client:
            yield client
        return
    import dask

    n = workers or os.cpu_count() or 1
    # one task per worker thread at a time: a device takes seconds, nothing is gained by
    # queueing more on a worker, and a worker that dies then takes no bystander with it.
    # No dashboard; the scheduler's HTTP endpoints on a free port (8787 may be taken).
    config = {"distributed.scheduler.worker-saturation": 1.0}
    with dask.config.set(config), \
            LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                         dashboard_address=None, silence_logs=logging.ERROR,
                         scheduler_kwargs={"dashboard_address": ":0"}) as cluster, \
            Client(cluster) as client:
        yield client


def run_batch(paths: Sequence[str | os.PathLike], out_dir: str | os.PathLike, *,
              client: Any, options: Options | None = None, resume: bool = False,
              progress: bool = False,
              task: Callable[[Source, Options], dict[str, Any]] = characterize) -> BatchRun:
    """Characterize every input under ``paths`` on the Dask ``client``.

    Parameters
    ----------
    paths : bundle directories, curve files, or directories holding them.
    out_dir : output directory (layout in the module docstring).
    client : a ``distributed.Client`` (see :func:`cluster_client`).
    options : what to do with each device (:class:`~.device.Options`).
    resume : reuse the finished results already in ``out_dir``; without it, an ``out_dir``
        that holds results is refused.
    progress : show a progress bar over the devices on stderr.
    task : the function applied to each :class:`~.device.Source` (default
        :func:`~.device.characterize`).

    Returns
    -------
    BatchRun
    """
    out = Path(out_dir)
    options = options or Options()
    check_output(out, resume)
    sources = [Source.read(p, name) for p, name in find_sources(paths, exclude=out)]
    done = load_results(out) if resume else {}
    records: dict[int, dict[str, Any]] = {}
    pending = []
    for i, src in enumerate(sources):
        old = done.get((src.sha256, src.name)) if src.sha256 else None
        if old is not None:
            old["row"].update(source=src.path)
            records[i] = old
        else:
            pending.append(i)
    bar = _progress_bar(len(sources), len(records), progress)
    # keys unique to this run: a key cancelled at the end of an earlier run may still be in
    # the scheduler's hands, and a new future under it would be cancelled with it
    run_id = uuid.uuid4().hex[:8]
    futures = {client.submit(task, sources[i], options, key=f"characterize-{sources[i].name}-"
                             f"{sources[i].sha256[:12]}-{run_id}", pure=False): i
               for i in pending}
    try:
        from distributed import as_completed

        for future in as_completed(futures):
            i = futures[future]
            try:
                result = future.result()
            except Exception as exc:  # noqa: BLE001 - a killed worker, or a task that raised
                result = {"row": _error_row(sources[i], exc)}
            records[i] = _save(out, result)
            bar.update(1)
    finally:
        bar.close()
        client.cancel([f for f in futures if not f.done()])  # only what an interrupt left
    results = tuple(records[i] for i in range(len(sources)))
    mark_duplicates([r["row"] for r in results])
    write_table([r["row"] for r in results], out)
    return BatchRun(results, len(pending), len(sources) - len(pending))


def mark_duplicates(rows: Sequence[dict[str, Any]]) -> None:
    """Set each row's ``duplicate_of`` to the name of the first input with the same content
    hash (empty for the first and for inputs of their own content): the same measurement
    given twice, counted once in the population's statistics.

    >>> rows = [{"name": n, "sha256": h} for n, h in (("a", "1"), ("b", "2"), ("c", "1"))]
    >>> mark_duplicates(rows)
    >>> [r["duplicate_of"] for r in rows]
    ['', '', 'a']
    """
    first: dict[str, str] = {}
    for row in rows:
        key = row.get("sha256") or ""
        row["duplicate_of"] = first.setdefault(key, row["name"]) if key else ""
        if row["duplicate_of"] == row["name"]:
            row["duplicate_of"] = ""


def _error_row(source: Source, exc: BaseException) -> dict[str, Any]:
    if type(exc).__name__ == "KilledWorker":
        return make_row(source, error=f"every worker that processed it died ({exc})")
    return make_row(source, error=f"{type(exc).__name__}: {exc}")


def _progress_bar(total: int, initial: int, show: bool) -> Any:
    from tqdm import tqdm

    return tqdm(total=total, initial=initial, unit="device", file=sys.stderr,
                disable=not (show and sys.stderr.isatty()), desc="batch")
