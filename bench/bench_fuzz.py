"""Reliability study: the long CLI fuzz and the issue's data-loss scenarios, rerun many times.

Targets (issue #17): the fuzz run clean (no traceback, no internal error, no hang, no NaN in
JSON); two concurrent writers lose nothing in 10 of 10 trials; kill -9 at random moments
leaves a complete bundle with every earlier data set in 10 of 10 kills.

Run: .venv/bin/python bench/bench_fuzz.py [--examples N] [--seed S] [--trials T]
(or with pytest -m benchmark bench/). The fuzz is tests/test_fuzz_cli.py with
SPICETHERMAL_FUZZ_EXAMPLES=N, a random seed and the simulated bench added.
"""

from __future__ import annotations

import argparse
import collections
import os
import random
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pytest

from spicethermal.io.bundle import Bundle

ROOT = Path(__file__).resolve().parent.parent
CLI = [sys.executable, "-m", "spicethermal.cli.main"]
QUICK = ["--cooling-power", "0.094", "--t-last", "5", "--settle", "20", "-q"]


def fuzz(examples: int, seed: int) -> dict:
    """Run the CLI fuzz; returns examples run, outcome counts, failure text and wall time."""
    env = {**os.environ, "SPICETHERMAL_FUZZ_EXAMPLES": str(examples),
           "SPICETHERMAL_FUZZ_SEED": str(seed), "SPICETHERMAL_FUZZ_SLOW": "1",
           "SPICETHERMAL_FUZZ_VERBOSE": "1"}
    t0 = time.perf_counter()
    p = subprocess.run([sys.executable, "-m", "pytest", "-q", "-s", "-x", "-p",
                        "no:cacheprovider", str(ROOT / "tests" / "test_fuzz_cli.py"), "-k",
                        "traceback"], cwd=ROOT, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    runs = [line.split(maxsplit=3) for line in p.stdout.splitlines() if line.startswith("FUZZ ")]
    outcomes = collections.Counter(f"exit {r[1]}" for r in runs)
    commands = collections.Counter(r[2] for r in runs)
    failure = "" if p.returncode == 0 else (p.stdout + p.stderr)[-3000:]
    return {"examples": len(runs), "outcomes": dict(outcomes), "commands": dict(commands),
            "ok": p.returncode == 0, "failure": failure, "wall_s": wall}


def _bench(out: Path, seed: int, *extra: str) -> subprocess.Popen:
    return subprocess.Popen(CLI + ["bench", "cooling", "--port", f"sim://actuator?seed={seed}",
                                   "-o", str(out), *QUICK, *extra],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def _files(root: Path) -> dict[str, bytes]:
    return {str(p.relative_to(root)): p.read_bytes() for p in root.rglob("*") if p.is_file()}


def _lost(before: dict[str, bytes], out: Path) -> list[str]:
    """Files of ``before`` missing or changed (raw logs may only have grown)."""
    try:
        Bundle.read(out)
    except Exception as exc:  # noqa: BLE001 - any failure to read counts as loss
        return [f"bundle unreadable: {exc}"]
    lost = []
    for name, data in before.items():
        path = out / name
        now = path.read_bytes() if path.is_file() else None
        if now is None or (name.startswith("raw/") and not now.startswith(data)) or (
                not name.startswith("raw/") and name != "bundle.json" and now != data):
            lost.append(name)
    return lost


def _base(root: Path) -> Path:
    out = root / "b"
    subprocess.run(CLI + ["bench", "cooling", "--port", "sim://actuator?seed=1", "-o", str(out),
                          *QUICK], check=True, capture_output=True)
    (out / "notes.txt").write_text("operator's notes\n")
    return out


def concurrent_writers(trials: int) -> dict:
    """Two ``bench cooling --wait`` sessions into one bundle at once, ``trials`` times."""
    bad = 0
    for k in range(trials):
        with tempfile.TemporaryDirectory() as tmp:
            out = _base(Path(tmp))
            before = _files(out)
            procs = [_bench(out, 10 * k + i, "--wait") for i in (2, 3)]
            codes = [p.wait() for p in procs]
            for p in procs:
                p.communicate()
            ok = codes == [0, 0] and not _lost(before, out) and len(Bundle.read(out).cooling) == 3
            bad += not ok
    return {"trials": trials, "lost": bad}


def kills(trials: int, seed: int) -> dict:
    """kill -9 a ``bench cooling`` into an existing bundle at a random moment, ``trials``
    times in a row; then one clean run must succeed and leave no leftovers."""
    rng = random.Random(seed)
    bad = 0
    with tempfile.TemporaryDirectory() as tmp:
        out = _base(Path(tmp))
        t0 = time.perf_counter()
        _bench(out, 2).communicate()
        duration = time.perf_counter() - t0
        for k in range(trials):
            before = _files(out)
            p = _bench(out, 100 + k)
            time.sleep(rng.uniform(0, 1.2 * duration))
            p.send_signal(signal.SIGKILL)
            p.communicate()
            bad += bool(_lost(before, out))
        p = _bench(out, 999)
        p.communicate()
        clean = p.returncode == 0 and sorted(os.listdir(tmp)) == ["b"]
    return {"kills": trials, "lost": bad, "clean_after": clean}


@pytest.mark.benchmark
def test_fuzz_and_scenarios_are_clean():
    f = fuzz(300, random.randrange(1 << 30))
    assert f["ok"], f["failure"]
    assert concurrent_writers(3)["lost"] == 0
    assert kills(5, 1)["lost"] == 0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--examples", type=int, default=1500)
    ap.add_argument("--seed", type=int, default=None)
    ap.add_argument("--trials", type=int, default=10)
    args = ap.parse_args()
    seed = random.randrange(1 << 30) if args.seed is None else args.seed
    f = fuzz(args.examples, seed)
    print(f"CLI fuzz, seed {seed}: {f['examples']} inputs in {f['wall_s']:.0f} s, "
          f"{'clean' if f['ok'] else 'FAILED'}; outcomes {f['outcomes']}")
    print(f"  per command: {f['commands']}")
    if not f["ok"]:
        print(f["failure"])
    c = concurrent_writers(args.trials)
    print(f"two concurrent writers (--wait): data lost in {c['lost']} of {c['trials']} trials")
    k = kills(args.trials, seed)
    print(f"kill -9 at random moments: data lost in {k['lost']} of {k['kills']} kills; next run "
          f"{'clean, no leftovers' if k['clean_after'] else 'NOT clean'}")
    return 0 if f["ok"] and not c["lost"] and not k["lost"] and k["clean_after"] else 1


if __name__ == "__main__":
    sys.exit(main())
