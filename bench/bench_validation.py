"""Diagnosis on the independent validation sets: detectable single effects named right, wrong
names on clean, linear and uncatalogued bundles, pairs both named, failures, CPU per bundle.

Plain script (not a test)::

    .venv/bin/python bench/bench_validation.py                      # the fixed catalogue
    .venv/bin/python bench/bench_validation.py --seed S --n 90      # a held-out draw
        [--only KIND] [--set heldout|fixed|earlier|linear] [--cases TEXT] [--quick]
        [--workers 1] [--limit 60] [--kill 180] [--engine python|cli] [--entry MOD:FUNC]
        [--out DIR] [--fresh] [--generate-only] [--score-only] [--show-cases]

Sets: ``heldout`` (the default with ``--seed``) draws ``N`` cases of
:func:`spicethermal.validation.draws.draw` (every device class and kind of physics, ``--only``
one kind); ``fixed`` (the default without) is :func:`spicethermal.validation.cases.catalogue`;
``earlier`` the earlier random draws (``bench/bench_validation_random.py``, kept so that their
figures reproduce); ``linear`` the linear-data suite
(:func:`spicethermal.validation.linear.linear_cases`). Report results only on a seed never
used while developing, recorded in ``bench/README.md`` before it is scored.

Phase 1 simulates every case into ``OUT/bundles/`` with its truth and detectability
(:mod:`spicethermal.validation.detect`; cached by the case's content). Phase 2 diagnoses every
bundle in its own process, ``--workers`` at a time (one by default): ``--engine python``
forks and calls ``--entry`` (default :func:`spicethermal.analysis.diagnose.diagnose`) and
reads ``to_json()``; ``--engine cli`` runs ``spicethermal diagnose BUNDLE --json``. A bundle
over ``--limit`` s of CPU is a failure (its verdict is kept); one over ``--kill`` s of CPU (or
four times that in wall time) is killed. Per-case outcomes go to ``OUT/results.json`` and the
scores to ``OUT/summary.json``; only the aggregate is printed unless ``--show-cases`` (a held-out
draw is not read case by case).

The verdict is read from ``spicethermal-diagnosis/2`` (``verdict.effects``, names in order) or
``/3`` to ``/6`` (``verdict.class`` — ``named``, ``approximate``, ``ambiguous``, ``none`` — and
``verdict.effects``; for ``ambiguous`` the tied effects). Scoring (:func:`score`):

* a detectable single effect is *right* when it is the first name of a ``named`` or
  ``approximate`` verdict; an ``ambiguous`` verdict that includes it is counted apart (neither
  right nor wrong);
* a *wrong name* is any name of the verdict (any class) outside the case's acceptable set
  (:attr:`~spicethermal.validation.cases.Case.acceptable`);
* a pair counts when it and each of its effects alone are detectable: both named in a
  ``named`` or ``approximate`` verdict;
* clean and linear bundles: nothing named; uncatalogued physics: no name outside its
  acceptable set, and where ``none`` is not acceptable and the case is detectable, a first
  name from the set (*near-catalogue named*);
* crashes, killed diagnoses and those over the CPU limit are failures; a failure is never
  right;
* a case the independent simulator cannot simulate (its own shooting finds no periodic PWM
  state) has no bundle: it is counted apart as *not simulated* and not scored.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # one thread per worker

import argparse  # noqa: E402
import hashlib  # noqa: E402
import importlib  # noqa: E402
import importlib.util  # noqa: E402
import json  # noqa: E402
import multiprocessing as mp  # noqa: E402
import signal  # noqa: E402
import statistics  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
import traceback  # noqa: E402
from collections import defaultdict  # noqa: E402
from pathlib import Path  # noqa: E402

from spicethermal.validation.cases import Case, catalogue  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
HERE = Path(__file__).resolve().parent
NAMING = ("named", "approximate")
#: Bump when the bundles change in a way the cases' repr does not show.
BUNDLES = 3


# -- the sets --------------------------------------------------------------------------------
def earlier_draw(n: int, seed: int, only: str | None = None) -> list[Case]:
    """The earlier random draws (``bench/bench_validation_random.py``)."""
    spec = importlib.util.spec_from_file_location("_earlier_draws",
                                                  HERE / "bench_validation_random.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.draw(n, seed, only)


def cases_of(args: argparse.Namespace) -> list[Case]:
    """The cases of ``--set`` (module docstring), filtered by ``--cases`` and ``--quick``."""
    if args.set == "fixed":
        cases = catalogue()
    elif args.set == "linear":
        from spicethermal.validation.linear import linear_cases
        cases = linear_cases()
    elif args.set == "earlier":
        cases = earlier_draw(args.n, args.seed, args.only)
    else:
        from spicethermal.validation.draws import draw
        cases = draw(args.n, args.seed, args.only)
    if args.cases:
        cases = [c for c in cases if args.cases in c.name]
    if args.quick:  # the first case of every kind
        seen: set[str] = set()
        cases = [c for c in cases if not (c.kind in seen or seen.add(c.kind))]
    return cases


# -- phase 1: bundles and their truth ----------------------------------------------------------
def _key(case: Case) -> str:
    return hashlib.sha1(f"{BUNDLES} {case!r}".encode()).hexdigest()[:16]


def folder_of(out: Path, case: Case) -> Path:
    return out / "bundles" / case.name.replace("/", "__").replace(" ", "_")


def mark(case: Case, folder: Path) -> dict:
    """Simulate ``case`` into the bundle ``folder``: its description and detectability (a
    pair's also each effect's alone, ``parts_detectable``)."""
    from spicethermal.validation.detect import detectability

    record = case.record()
    det = detectability(record)
    record.bundle.write(folder)
    doc = {**case.describe(), **det.to_json()}
    if case.parts:
        doc["parts_detectable"] = [detectability(p.record()).detectable for p in case.parts]
    return doc


def generate(case: Case, out: Path, fresh: bool = False) -> dict:
    """The case's bundle and truth, from the cache when the case has not changed."""
    folder = folder_of(out, case)
    meta = folder.parent / (folder.name + ".json")
    if not fresh and meta.exists():
        doc = json.loads(meta.read_text())
        if doc.get("key") == _key(case) and folder.exists():
            return doc
    t0 = time.process_time()
    doc = {"key": _key(case), **mark(case, folder), "folder": str(folder),
           "generate_cpu_s": round(time.process_time() - t0, 2)}
    meta.write_text(json.dumps(doc, indent=1, default=str))
    return doc


def generate_all(cases: list[Case], out: Path, fresh: bool = False
                 ) -> tuple[dict[str, dict], dict[str, str]]:
    """Every case's bundle (:func:`generate`), and apart, by name, why the independent
    simulator could not simulate a case (its shooting found no periodic PWM state): such a
    case has no bundle and is not scored, and the others go on."""
    meta, unmade = {}, {}
    for k, c in enumerate(cases):
        try:
            meta[c.name] = generate(c, out, fresh)
        except ArithmeticError as err:
            unmade[c.name] = str(err)
        print(f"\r  bundles {k + 1}/{len(cases)}", end="", flush=True)
    return meta, unmade


# -- phase 2: the diagnoses ----------------------------------------------------------------------
def _python_child(entry: str, folder: str, conn) -> None:
    try:
        from spicethermal.io.bundle import Bundle

        module, _, func = entry.partition(":")
        diagnose = getattr(importlib.import_module(module), func)
        bundle = Bundle.read(folder)
        t0, c0 = time.perf_counter(), time.process_time()
        result = diagnose(bundle)
        cpu, wall = time.process_time() - c0, time.perf_counter() - t0
        # a JsonDocument (to_dict(); to_json() is its text), or an older result whose
        # to_json() is the document itself
        doc = result.to_dict() if hasattr(result, "to_dict") else result.to_json()
        if isinstance(doc, str):
            doc = json.loads(doc)
        conn.send({"doc": _kept(doc), "cpu_s": cpu, "elapsed_s": wall})
    except BaseException as exc:  # a crash is a result here
        conn.send({"crash": f"{type(exc).__name__}: {exc}"[:300],
                   "trace": traceback.format_exc()[-1500:]})
    finally:
        conn.close()


def _kept(doc: dict) -> dict:
    """What a result keeps of a diagnosis document."""
    return {k: doc[k] for k in ("format", "verdict", "steps", "baseline", "work") if k in doc}


def _cpu_s(pid: int) -> float:
    """CPU time (s) used so far by process ``pid`` (Linux ``/proc``; 0 elsewhere)."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    except (OSError, IndexError, ValueError):
        return 0.0


class _Job:
    """One diagnosis in its own process."""

    def __init__(self, folder: Path, engine: str, entry: str):
        self.start = time.perf_counter()
        self.cpu = 0.0
        if engine == "python":
            ctx = mp.get_context("fork")
            self.recv, send = ctx.Pipe(duplex=False)
            self.proc = ctx.Process(target=_python_child, args=(entry, str(folder), send),
                                    daemon=True)
            self.proc.start()
            send.close()
            self.pid = self.proc.pid
        else:  # stdout to a file: a pipe left unread would block a long document
            exe = Path(sys.executable).with_name("spicethermal")
            self.stdout = folder.parent / (folder.name + ".stdout")
            with open(self.stdout, "w") as fh:
                self.pid = subprocess.Popen([str(exe), "diagnose", str(folder), "--json",
                                             "-q"], stdout=fh, stderr=subprocess.STDOUT).pid

    def poll(self) -> dict | None:
        """The outcome when the process has ended, else None."""
        wall = time.perf_counter() - self.start
        if hasattr(self, "proc"):
            if self.recv.poll():
                try:
                    res = self.recv.recv()
                except EOFError:
                    res = {"crash": f"process died (exit code {self.proc.exitcode})"}
                self.proc.join(5)
                self.recv.close()
                return {**res, "wall_s": wall}
            if not self.proc.is_alive():
                return {"crash": f"process died (exit code {self.proc.exitcode})",
                        "wall_s": wall}
            self.cpu = _cpu_s(self.pid) or self.cpu
            return None
        pid, status, usage = os.wait4(self.pid, os.WNOHANG)
        if pid == 0:
            self.cpu = _cpu_s(self.pid) or self.cpu
            return None
        cpu = usage.ru_utime + usage.ru_stime
        text = self.stdout.read_text()
        if os.waitstatus_to_exitcode(status) != 0:
            return {"crash": f"exit status {os.waitstatus_to_exitcode(status)}: "
                             f"{text.strip()[-300:]}", "wall_s": wall, "cpu_s": cpu}
        try:
            doc = json.loads(text)
        except json.JSONDecodeError as exc:
            return {"crash": f"not JSON: {exc}", "wall_s": wall, "cpu_s": cpu}
        return {"doc": _kept(doc), "cpu_s": cpu, "elapsed_s": wall, "wall_s": wall}

    def kill(self) -> None:
        try:
            os.kill(self.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        if hasattr(self, "proc"):
            self.proc.join(5)
            self.recv.close()
        else:
            os.waitpid(self.pid, 0)


def run_diagnoses(folders: dict[str, Path], args: argparse.Namespace,
                  done: dict[str, dict] | None = None, save=None) -> dict[str, dict]:
    """Diagnose every bundle (module docstring); ``done`` results are kept, ``save`` is
    called after each new one."""
    if args.engine == "python":  # imported once, before the forks
        importlib.import_module(args.entry.partition(":")[0])
    results = dict(done or {})
    pending = [(n, f) for n, f in folders.items() if n not in results]
    running: dict[str, _Job] = {}
    total = len(folders)
    while pending or running:
        while pending and len(running) < args.workers:
            name, folder = pending.pop(0)
            running[name] = _Job(folder, args.engine, args.entry)
        for name, job in list(running.items()):
            res = job.poll()
            wall = time.perf_counter() - job.start
            if res is None and (job.cpu > args.kill or wall > 4 * args.kill):
                job.kill()
                res = {"killed": True, "cpu_s": job.cpu, "wall_s": wall}
            if res is None:
                continue
            results[name] = res
            del running[name]
            if save is not None:
                save(results)
            line = f"  [{len(results)}/{total}]"
            if args.show_cases:
                line += f" {name:56s} {outcome(res):40s} {res.get('cpu_s', 0.0):6.1f} s CPU"
            print(line, flush=True)
        time.sleep(0.05)
    return results


# -- scoring -------------------------------------------------------------------------------------
def verdict_of(doc: dict | None) -> dict:
    """``{"class", "effects", "first"}`` of a diagnosis document (format 2 to 6).

    >>> verdict_of({"format": "spicethermal-diagnosis/2",
    ...             "verdict": {"effect": "phase-change", "effects": ["phase-change"]}})
    {'class': 'named', 'effects': ['phase-change'], 'first': 'phase-change'}
    >>> verdict_of({"format": "spicethermal-diagnosis/3", "verdict": {"class": "ambiguous",
    ...             "effects": ["tsp-nonlinearity", "phase-change"], "effect": None}})
    {'class': 'ambiguous', 'effects': ['tsp-nonlinearity', 'phase-change'], 'first': None}
    """
    verdict = (doc or {}).get("verdict") or {}
    effects = [str(e) for e in (verdict.get("effects") or [])]
    if verdict.get("effect") and verdict["effect"] not in effects:
        effects.insert(0, str(verdict["effect"]))
    cls = verdict.get("class") or ("named" if effects else "none")
    first = (verdict.get("effect") or (effects[0] if effects else None)) if cls in NAMING \
        else None
    return {"class": cls, "effects": effects, "first": first}


def outcome(res: dict) -> str:
    if res.get("killed"):
        return "KILLED"
    if "crash" in res:
        return "CRASH " + res["crash"][:40]
    v = verdict_of(res.get("doc"))
    return f"{v['class']}: {'+'.join(v['effects']) or '-'}"


def _row(meta: dict, res: dict, limit_s: float) -> dict:
    """One case scored (module docstring)."""
    v = verdict_of(res.get("doc")) if "doc" in res else None
    fam, accept = meta["family"], set(meta.get("acceptable") or ["none"])
    failure = ("killed" if res.get("killed") else "crash" if "crash" in res
               else "over limit" if res.get("cpu_s", 0.0) > limit_s else "")
    names = v["effects"] if v else []
    row = {"case": meta["case"], "family": fam, "kind": meta.get("kind") or fam,
           "device": meta["device"], "detectable": meta["detectable"],
           "cpu_s": res.get("cpu_s"), "failure": failure,
           "class": v["class"] if v else None, "named": names,
           "wrong": [n for n in names if n not in accept]}
    ok = not failure
    if fam == "effect":
        want = meta["expected"][0]
        row["counted"] = meta["detectable"]
        row["right"] = ok and v["first"] == want
        row["ambiguous"] = ok and v["class"] == "ambiguous" and want in names
    elif fam == "pair":
        row["counted"] = meta["detectable"] and all(meta.get("parts_detectable", [True]))
        row["right"] = ok and v["class"] in NAMING and set(meta["expected"]) <= set(names)
        row["one"] = ok and bool(set(meta["expected"]) & set(names))
    elif fam in ("clean", "linear"):
        row["counted"] = True
        row["right"] = ok and not names
    else:
        row["counted"] = True
        row["right"] = ok and not row["wrong"]
        if "none" not in accept:
            row["near_counted"] = meta["detectable"]
            row["near"] = ok and v["first"] in accept
    return row


def _pct(a: int, b: int) -> str:
    return f"{a}/{b} ({100.0 * a / b:.0f} %)" if b else "0/0"


def score(meta: dict[str, dict], results: dict[str, dict], limit_s: float = 60.0) -> dict:
    """The aggregate scores (module docstring) and a breakdown per kind and per device."""
    rows = [_row(meta[n], results[n], limit_s) for n in meta if n in results]
    singles = [r for r in rows if r["family"] == "effect" and r["counted"]]
    pairs = [r for r in rows if r["family"] == "pair" and r["counted"]]
    nulls = [r for r in rows if r["family"] in ("clean", "linear", "uncatalogued")]
    near = [r for r in nulls if r.get("near_counted")]
    cpu = [r["cpu_s"] for r in rows if r["cpu_s"] is not None]
    breakdown: dict[str, dict[str, dict]] = {"kind": {}, "device": {}}
    for axis, table in breakdown.items():
        groups: dict[str, list] = defaultdict(list)
        for r in rows:
            groups[r[axis]].append(r)
        for key, group in sorted(groups.items()):
            counted = [r for r in group if r["counted"]]
            times = [r["cpu_s"] for r in group if r["cpu_s"] is not None]
            table[key] = {"n": len(group), "counted": len(counted),
                          "right": sum(r["right"] for r in counted),
                          "near": sum(r.get("near", False) for r in group
                                      if r.get("near_counted")),
                          "near_counted": sum(bool(r.get("near_counted")) for r in group),
                          "ambiguous": sum(r.get("ambiguous", False) for r in counted),
                          "wrong_name_bundles": sum(bool(r["wrong"]) for r in group),
                          "failures": sum(bool(r["failure"]) for r in group),
                          "cpu_median_s": statistics.median(times) if times else None}
    return {
        "n": len(rows),
        "singles_right": sum(r["right"] for r in singles), "singles_n": len(singles),
        "singles_ambiguous": sum(r["ambiguous"] for r in singles),
        "singles_undetectable": sum(r["family"] == "effect" and not r["counted"] for r in rows),
        "null_wrong_bundles": sum(bool(r["wrong"]) for r in nulls),
        "null_wrong_names": sum(len(r["wrong"]) for r in nulls), "null_n": len(nulls),
        "other_wrong_bundles": sum(bool(r["wrong"]) for r in rows
                                   if r["family"] in ("effect", "pair")),
        "pairs_both": sum(r["right"] for r in pairs), "pairs_one": sum(r["one"] for r in pairs),
        "pairs_n": len(pairs),
        "near_named": sum(r["near"] for r in near), "near_n": len(near),
        "crashes": sum(r["failure"] == "crash" for r in rows),
        "killed": sum(r["failure"] == "killed" for r in rows),
        "over_limit": sum(r["failure"] == "over limit" for r in rows),
        "cpu_median_s": statistics.median(cpu) if cpu else None,
        "cpu_max_s": max(cpu) if cpu else None,
        "breakdown": breakdown, "rows": rows,
    }


def report(s: dict, limit_s: float) -> str:
    """The aggregate as text (no case names)."""
    lines = [
        f"bundles: {s['n']}",
        f"detectable single effects right: {_pct(s['singles_right'], s['singles_n'])}; "
        f"ambiguous including it: {s['singles_ambiguous']}; undetectable (not counted): "
        f"{s['singles_undetectable']}",
        f"wrong names on clean, linear and uncatalogued bundles: {s['null_wrong_bundles']} of "
        f"{s['null_n']} bundles ({s['null_wrong_names']} names)",
        f"pairs both named: {_pct(s['pairs_both'], s['pairs_n'])} (one at least: "
        f"{s['pairs_one']})",
        f"near-catalogue physics named (null not acceptable, detectable): "
        f"{_pct(s['near_named'], s['near_n'])}",
        f"wrong names on single effects and pairs: {s['other_wrong_bundles']} bundles",
        f"failures: {s['crashes']} crashes, {s['killed']} killed, {s['over_limit']} over "
        f"{limit_s:g} s CPU",
    ]
    if s["cpu_median_s"] is not None:
        lines.append(f"CPU per bundle: median {s['cpu_median_s']:.2f} s, max "
                     f"{s['cpu_max_s']:.2f} s")
    for axis in ("kind", "device"):
        lines.append(f"\nper {axis}: bundles, counted, right (singles: named first; pairs: "
                     "both; others: no wrong name), near-catalogue named/counted, ambiguous, "
                     "bundles with a wrong name, failures, CPU median")
        for key, b in s["breakdown"][axis].items():
            med = "-" if b["cpu_median_s"] is None else f"{b['cpu_median_s']:.1f} s"
            near = f"{b['near']}/{b['near_counted']}" if b["near_counted"] else "-"
            lines.append(f"  {key:34s} {b['n']:4d} {b['counted']:4d} {b['right']:4d} "
                         f"{near:>6s} {b['ambiguous']:4d} {b['wrong_name_bundles']:4d} "
                         f"{b['failures']:4d} {med:>8s}")
    return "\n".join(lines)


# -- the command -----------------------------------------------------------------------------
def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--set", choices=("heldout", "fixed", "earlier", "linear"))
    ap.add_argument("--seed", type=int)
    ap.add_argument("--n", type=int, default=90, help="cases drawn (default 90)")
    ap.add_argument("--only", help="draw only cases of this kind")
    ap.add_argument("--cases", metavar="TEXT", help="only cases whose name contains TEXT")
    ap.add_argument("--quick", action="store_true", help="the first case of every kind")
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--limit", type=float, default=60.0, metavar="S",
                    help="CPU seconds beyond which a diagnosis is a failure (default 60)")
    ap.add_argument("--kill", type=float, default=180.0, metavar="S",
                    help="CPU seconds at which a diagnosis is killed (default 180)")
    ap.add_argument("--engine", choices=("python", "cli"), default="python")
    ap.add_argument("--entry", default="spicethermal.analysis.diagnose:diagnose",
                    metavar="MODULE:FUNC", help="the diagnosis the python engine calls")
    ap.add_argument("--out", metavar="DIR")
    ap.add_argument("--fresh", action="store_true", help="regenerate every bundle")
    ap.add_argument("--generate-only", action="store_true")
    ap.add_argument("--score-only", action="store_true",
                    help="score the results already in OUT")
    ap.add_argument("--show-cases", action="store_true",
                    help="print each case's outcome (not for a held-out draw)")
    args = ap.parse_args(argv)
    args.set = args.set or ("heldout" if args.seed is not None else "fixed")
    if args.set in ("heldout", "earlier") and args.seed is None:
        ap.error(f"--set {args.set} needs --seed")
    tag = args.set + (f"-{args.seed}" if args.seed is not None else "") + \
        (f"-{args.only}" if args.only else "")
    out = Path(args.out or ROOT / "out" / "validation" / tag)
    (out / "bundles").mkdir(parents=True, exist_ok=True)
    cases = cases_of(args)
    t0 = time.perf_counter()
    meta, unmade = generate_all(cases, out, args.fresh)
    cases = [c for c in cases if c.name in meta]
    print(f"\n{len(cases)} bundles ({args.set}) ready in {time.perf_counter() - t0:.0f} s"
          + (f"; {len(unmade)} not simulated (the independent simulator found no periodic "
             f"state), not scored" if unmade else ""), flush=True)
    if args.generate_only:
        return 0
    store = out / "results.json"  # kept per bundle and engine: a run resumes where it stopped
    done = json.loads(store.read_text()) if store.exists() else {}

    def key(name: str) -> str:
        return f"{meta[name]['key']} {args.engine} {args.entry} {args.limit:g} {args.kill:g}"

    done = {n: r for n, r in done.items() if n in meta and r.get("key") == key(n)}
    if not args.score_only:
        def save(results: dict) -> None:
            for n in results:
                results[n]["key"] = key(n)
            store.write_text(json.dumps(results, indent=1, default=str))

        done = run_diagnoses({c.name: folder_of(out, c) for c in cases}, args, done, save)
    summary = score(meta, done, args.limit)
    summary["not_simulated"] = unmade
    print("\n" + report(summary, args.limit)
          + (f"\nnot simulated, not scored: {len(unmade)}" if unmade else ""))
    summary.update({"set": args.set, "seed": args.seed, "only": args.only,
                    "engine": args.engine, "entry": args.entry, "limit_s": args.limit,
                    "kill_s": args.kill, "load_average": os.getloadavg()})
    (out / "summary.json").write_text(json.dumps(summary, indent=1, default=str))
    print(f"summary: {out / 'summary.json'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
