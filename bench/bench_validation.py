"""Diagnosis on the independent validation set (issue 14, point 7): confusion matrix, breakdown
per form and strength, pairs, clean and uncatalogued bundles, runtime.

Plain script (not a test)::

    .venv/bin/python bench/bench_validation.py [--quick] [--cases TEXT] [--workers 2]
                                               [--timeout 60] [--out out/validation] [--fresh]

Phase 1 simulates every case of :func:`spicethermal.validation.cases.catalogue` (independent
generator, fixed seeds) into ``OUT/bundles/<case>/`` with its detectability mark (cached: a
bundle is regenerated only when its case changes, or with ``--fresh``). Phase 2 runs
:func:`spicethermal.analysis.diagnose.diagnose` (the Python API, default baseline, every catalogued
effect) on every bundle, each in its own process, at most ``--workers`` at a time, killed
after ``--timeout`` seconds of CPU time (a hang) — a crash and a hang both count as
failures. The summary
goes to ``OUT/summary.json``.

Scoring: an effect case is right when the verdict's first effect is the expected one (only
detectable cases count); a pair when both effects are named (only pairs whose truth is
detectable as a whole and whose effects are each detectable alone, on the same bench, count:
an effect that leaves no trace alone cannot be asked for beside another); a clean or
uncatalogued bundle when nothing is named.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # one thread per worker: --workers is the cores

import argparse  # noqa: E402
import hashlib  # noqa: E402
import json  # noqa: E402
import multiprocessing as mp  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402
import traceback  # noqa: E402
from collections import Counter, defaultdict  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from spicethermal.validation.cases import Case, catalogue  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
QUICK = ("clean/actuator-1", "clean/mosfet-2", "uncatalogued/ambient-drift",
         "temperature-coefficient/junction-linear/strong", "phase-change/gaussian-outer/strong",
         "electrical-transient/fixed/strong", "tsp-nonlinearity/quadratic/strong",
         "sample-window/end/strong", "pair/temperature-coefficient+sample-window")


#: Bump when the generator changes in a way the cases' repr does not show.
GENERATOR = 2


def _key(case: Case) -> str:
    return hashlib.sha1(f"{GENERATOR} {case!r}".encode()).hexdigest()[:16]


def _folder(out: Path, case: Case) -> Path:
    return out / "bundles" / case.name.replace("/", "__")


def _generate(args: tuple[Case, str, bool]) -> tuple[str, dict]:
    case, out, fresh = args
    folder = _folder(Path(out), case)
    meta = folder.parent / (folder.name + ".json")
    if not fresh and meta.exists():
        doc = json.loads(meta.read_text())
        if doc.get("key") == _key(case) and folder.exists():
            return case.name, doc
    t0 = time.perf_counter()
    doc = {"key": _key(case), **mark(case, folder),
           "generate_s": round(time.perf_counter() - t0, 2)}
    meta.write_text(json.dumps(doc, indent=1, default=str))
    return case.name, doc


def mark(case: Case, folder: Path) -> dict:
    """Simulate ``case`` into the bundle ``folder``; its description and detectability (a
    pair's also each effect's alone, ``parts_detectable``)."""
    from spicethermal.validation.detect import detectability

    record = case.record()
    det = detectability(record)
    record.bundle.write(folder)
    doc = {**case.describe(), **det.to_json()}
    if case.parts:
        doc["parts_detectable"] = [detectability(p.record()).detectable for p in case.parts]
    return doc


def _diagnose(folder: str, conn) -> None:
    try:
        from spicethermal.analysis.diagnose import diagnose
        from spicethermal.io.bundle import Bundle

        bundle = Bundle.read(folder)
        t0, c0 = time.perf_counter(), time.process_time()
        result = diagnose(bundle)
        elapsed, cpu = time.perf_counter() - t0, time.process_time() - c0
        conn.send({"named": named_effects(result), "elapsed_s": elapsed, "cpu_s": cpu,
                   "reason": str(result.verdict_reason), "left": left(result)})
    except BaseException as exc:  # a crash is a result here
        conn.send({"crash": f"{type(exc).__name__}: {exc}"[:300],
                   "trace": traceback.format_exc()[-1500:]})
    finally:
        conn.close()


def left(result) -> dict[str, float]:
    """Per data set, the noise-weighted ``χ²/n`` the named effects leave (the baseline's when
    none is named): how far from its noise each data set stays."""
    final = result.steps[-1].chosen.comparison if result.steps else result.baseline
    return {name: round(float(np.sum(sub.residuals_k ** 2)) / result.noise_k[name] ** 2
                        / max(len(sub.points), 1), 3)
            for name, sub in final.by_dataset().items()}


def named_effects(result) -> list[str]:
    """Every effect the diagnosis names, in order (``verdict.effects`` when present)."""
    verdict = result.to_json().get("verdict")
    if isinstance(verdict, dict):
        names = verdict.get("effects") or ([verdict["effect"]] if verdict.get("effect") else [])
        return [str(n) for n in names]
    return [result.verdict_effect] if result.verdict_effect else []


#: A diagnosis is also stopped after this many times its CPU limit in wall time.
WALL_FACTOR = 8.0


def _cpu_s(pid: int) -> float:
    """CPU time (s) used so far by process ``pid`` (Linux ``/proc``; 0 elsewhere)."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    except (OSError, IndexError, ValueError):
        return 0.0


def run_diagnoses(folders: dict[str, Path], workers: int, timeout_s: float) -> dict[str, dict]:
    """Diagnose every bundle in its own process, ``workers`` at a time, stopped (a hang) past
    ``timeout_s`` of CPU time — the machine is shared, wall time measures the others too — or
    :data:`WALL_FACTOR` times that in wall time."""
    ctx = mp.get_context("fork")
    pending = list(folders.items())
    running: dict[str, tuple] = {}
    results: dict[str, dict] = {}
    while pending or running:
        while pending and len(running) < workers:
            name, folder = pending.pop(0)
            recv, send = ctx.Pipe(duplex=False)
            proc = ctx.Process(target=_diagnose, args=(str(folder), send), daemon=True)
            proc.start()
            send.close()
            running[name] = (proc, recv, time.perf_counter())
        for name, (proc, recv, start) in list(running.items()):
            wall = time.perf_counter() - start
            if recv.poll():
                try:
                    results[name] = {**recv.recv(), "wall_s": wall}
                except EOFError:
                    results[name] = {"crash": f"process died (exit code {proc.exitcode})",
                                     "wall_s": wall}
            elif not proc.is_alive():
                results[name] = {"crash": f"process died (exit code {proc.exitcode})",
                                 "wall_s": wall}
            elif _cpu_s(proc.pid) > timeout_s or wall > WALL_FACTOR * timeout_s:
                proc.kill()
                results[name] = {"hang": True, "wall_s": wall, "cpu_s": _cpu_s(proc.pid)}
            else:
                continue
            proc.join(5)
            recv.close()
            del running[name]
            print(f"  {name:58s} {_outcome(results[name]):40s} {wall:6.1f} s", flush=True)
        time.sleep(0.05)
    return results


def _outcome(res: dict) -> str:
    if res.get("hang"):
        return "HANG"
    if "crash" in res:
        return "CRASH " + res["crash"][:40]
    return "+".join(res["named"]) or "none"


def _predicted(res: dict) -> str:
    if res.get("hang"):
        return "hang"
    if "crash" in res:
        return "crash"
    return res["named"][0] if res["named"] else "none"


def score(meta: dict[str, dict], results: dict[str, dict]) -> dict:
    """Confusion matrix, breakdowns and runtime (module docstring)."""
    confusion: dict[str, Counter] = defaultdict(Counter)
    per_form: dict[str, list[int]] = defaultdict(lambda: [0, 0])
    per_strength: dict[str, list[int]] = defaultdict(lambda: [0, 0])
    undetectable, pairs, nulls, rows = [], [], [], []
    for name, m in meta.items():
        res = results[name]
        pred = _predicted(res)
        named = res.get("named", [])
        fam = m["family"]
        row = {"case": name, "family": fam, "expected": m["expected"], "named": named,
               "outcome": _outcome(res), "detectable": m["detectable"],
               "elapsed_s": res.get("elapsed_s"), "cpu_s": res.get("cpu_s"),
               "max_gain": m["max_gain"]}
        if fam == "effect":
            want = m["expected"][0]
            row["right"] = pred == want
            if not m["detectable"]:
                undetectable.append(row)
                rows.append(row)
                continue
            confusion[want][pred] += 1
            for key, table in ((f"{want}/{m['form']}", per_form), (m["strength"], per_strength)):
                table[key][0] += row["right"]
                table[key][1] += 1
        elif fam == "pair":
            row["right"] = set(m["expected"]) <= set(named)
            row["one"] = bool(set(m["expected"]) & set(named))
            if not m["detectable"] or not all(m.get("parts_detectable", [True])):
                # the pair, or one of its effects alone, leaves no trace the linear ladder misses
                undetectable.append(row)
                rows.append(row)
                continue
            pairs.append(row)
        else:
            row["right"] = not named and pred == "none"
            confusion["none"][pred] += 1
            nulls.append(row)
        rows.append(row)
    counted = [r for r in rows if r["family"] == "effect" and r["detectable"]]
    times = [r["elapsed_s"] for r in rows if r["elapsed_s"] is not None]
    cpu = [r["cpu_s"] for r in rows if r["cpu_s"] is not None]
    return {
        "detectable_right": sum(r["right"] for r in counted), "detectable_n": len(counted),
        "pairs_both": sum(r["right"] for r in pairs), "pairs_one": sum(r["one"] for r in pairs),
        "pairs_n": len(pairs), "null_right": sum(r["right"] for r in nulls),
        "null_n": len(nulls),
        "crashes": sum("crash" in results[n] for n in meta),
        "hangs": sum(bool(results[n].get("hang")) for n in meta),
        "median_s": statistics.median(times) if times else None,
        "max_s": max(times) if times else None,
        "median_cpu_s": statistics.median(cpu) if cpu else None,
        "max_cpu_s": max(cpu) if cpu else None,
        "confusion": {k: dict(v) for k, v in confusion.items()},
        "per_form": {k: v for k, v in sorted(per_form.items())},
        "per_strength": dict(per_strength),
        "undetectable": [r["case"] for r in undetectable], "cases": rows,
    }


SHORT = {"temperature-coefficient": "temp-coef", "phase-change": "phase", "sample-window":
         "window", "electrical-transient": "el-trans", "tsp-nonlinearity": "tsp"}


def report(s: dict) -> None:
    cols = sorted({p for row in s["confusion"].values() for p in row},
                  key=lambda p: (p in ("none", "crash", "hang"), p))
    width = max(len(c) for c in [*s["confusion"], "expected \\ named"]) + 1
    print("\nconfusion matrix (detectable single-effect cases, clean and uncatalogued as none;"
          " columns: first effect named)")
    print("expected \\ named".ljust(width) + "".join(SHORT.get(c, c).rjust(10) for c in cols))
    for want in sorted(s["confusion"], key=lambda w: (w == "none", w)):
        row = s["confusion"][want]
        print(want.ljust(width) + "".join(str(row.get(c, 0)).rjust(10) for c in cols))
    print("\nper form (right / detectable cases)")
    for form, (ok, n) in s["per_form"].items():
        print(f"  {form:52s} {ok}/{n}")
    print("per strength: " + ", ".join(f"{k} {ok}/{n}" for k, (ok, n)
                                       in sorted(s["per_strength"].items())))
    print("pairs: " + "; ".join(f"{r['case'].split('/', 1)[1]} -> {r['outcome']}"
                                for r in s["cases"] if r["family"] == "pair"))
    print("clean/uncatalogued named: " + (", ".join(
        f"{r['case']} -> {r['outcome']}" for r in s["cases"]
        if r["family"] in ("clean", "uncatalogued") and not r["right"]) or "none"))
    print(f"undetectable (not counted): {', '.join(s['undetectable']) or 'none'}")
    pct = 100.0 * s["detectable_right"] / max(s["detectable_n"], 1)
    print(f"\ndetectable cases right: {s['detectable_right']}/{s['detectable_n']} ({pct:.0f} %, "
          f"target >= 90 %)")
    print(f"no name on clean/uncatalogued: {s['null_right']}/{s['null_n']} (target all)")
    print(f"pairs with both effects named: {s['pairs_both']}/{s['pairs_n']} (target >= 4 of 6; "
          f"at least one named: {s['pairs_one']})")
    print(f"crashes: {s['crashes']}, hangs: {s['hangs']} (target 0, 0)")
    if s["median_s"] is not None:
        print(f"diagnosis time per bundle: median {s['median_s']:.2f} s, max {s['max_s']:.2f} s "
              f"wall; CPU median {s['median_cpu_s']:.2f} s, max {s['max_cpu_s']:.2f} s "
              f"(target median <= 5 s; a hang has no time)")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help=f"only {len(QUICK)} cases")
    ap.add_argument("--cases", metavar="TEXT", help="only cases whose name contains TEXT")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--timeout", type=float, default=60.0, metavar="S",
                    help="per-case diagnosis limit in CPU seconds (default 60; wall time "
                         f"{WALL_FACTOR:g}× that)")
    ap.add_argument("--out", default=str(ROOT / "out" / "validation"), metavar="DIR")
    ap.add_argument("--fresh", action="store_true", help="regenerate every bundle")
    ap.add_argument("--generate-only", action="store_true",
                    help="write the bundles and their truth, do not diagnose")
    args = ap.parse_args(argv)
    cases = catalogue()
    if args.quick:
        cases = [c for c in cases if c.name in QUICK]
    if args.cases:
        cases = [c for c in cases if args.cases in c.name]
    out = Path(args.out)
    (out / "bundles").mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    with mp.get_context("fork").Pool(args.workers) as pool:
        meta = dict(pool.map(_generate, [(c, str(out), args.fresh) for c in cases], chunksize=1))
    print(f"{len(cases)} bundles ready in {time.perf_counter() - t0:.0f} s "
          f"({sum(m['detectable'] for m in meta.values() if m['family'] == 'effect')} detectable "
          f"single-effect cases)", flush=True)
    if args.generate_only:
        return 0
    results = run_diagnoses({c.name: _folder(out, c) for c in cases}, args.workers,
                            args.timeout)
    scored_report({c.name: meta[c.name] for c in cases}, results, out)
    return 0


def scored_report(meta: dict[str, dict], results: dict[str, dict], out: Path) -> None:
    """Score, print the report and keep it, each diagnosis's outcome beside it, in
    ``OUT/summary.json``."""
    summary = score(meta, results)
    report(summary)
    summary["results"] = results
    summary["load_average"] = os.getloadavg()
    (out / "summary.json").write_text(json.dumps(summary, indent=1, default=str))
    print(f"summary: {out / 'summary.json'}")


if __name__ == "__main__":
    raise SystemExit(main())
