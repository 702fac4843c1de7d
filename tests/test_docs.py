"""Docs that run: every shell command in docs/*.md, in order, in a scratch directory (README.md's
run in one fresh shell, in order, in ``tests/test_readme_fresh.py``), and README.md's stated
figures checked against what the commands print.

A fenced ``sh`` block is run by bash (``-e``: the first failing command fails the test, with its
output); a ``python`` block by the project's Python (a tutorial's own set-up steps); a ``spice``
block is run by ngspice, with the ``.lib`` files the commands before it
wrote. A block right after ``<!-- docs-test: skip (reason) -->`` is not run (hardware, the whole
test suite). The scratch directory sees the repository's ``spicethermal/`` (its sample data),
``bench/`` and ``.venv/``, and has an empty ``docs/figures/``: commands write there, never into
the checkout.
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from spicethermal.spice.lib import NgspiceBatch

ROOT = Path(__file__).resolve().parent.parent
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
#: The documents whose commands :func:`test_every_command_in_the_docs_runs` runs block by block;
#: README.md's run in order in one fresh shell (``tests/test_readme_fresh.py``), once.
RUN = DOCS[1:]
SKIP = re.compile(r"<!--\s*docs-test:\s*skip\b")
LINKED = ("spicethermal", "bench", ".venv", "netlists", "templates")


def blocks(text: str) -> list[tuple[int, str, str]]:
    """``(line, language, body)`` of every ``sh``, ``python`` and ``spice`` block not marked
    skip."""
    out, lines, i = [], text.splitlines(), 0
    while i < len(lines):
        fence = re.match(r"^```(sh|python|spice)\s*$", lines[i])
        if fence:
            j = next(k for k in range(i + 1, len(lines)) if lines[k].startswith("```"))
            marked = i > 0 and SKIP.search(lines[i - 1])
            if not marked:
                out.append((i + 1, fence[1], "\n".join(lines[i + 1:j]) + "\n"))
            i = j
        i += 1
    return out


def test_blocks_are_found_and_skips_are_explicit():
    text = ("```sh\necho a\n```\n<!-- docs-test: skip (x) -->\n```sh\nexit 1\n```\n"
            "```json\n{}\n```\n")
    assert blocks(text) == [(1, "sh", "echo a\n")]


def _scratch(tmp: Path) -> dict[str, str]:
    for name in LINKED:
        if (ROOT / name).exists():
            (tmp / name).symlink_to(ROOT / name)
    (tmp / "docs" / "figures").mkdir(parents=True)
    bin_dir = str(Path(sys.executable).parent)
    return dict(os.environ, PATH=bin_dir + os.pathsep + os.environ.get("PATH", ""),
                MPLBACKEND="Agg")


def _run_spice(body: str, tmp: Path) -> None:
    deck, dialect = [], "ngspice"
    for line in body.splitlines():
        inc = re.match(r"^\.include\s+(\S+)", line, re.I)
        if inc:
            lib = tmp / inc[1]
            assert lib.is_file(), f"{inc[1]}: no command before this deck wrote it"
            dialect = re.search(r"(ngspice|pspice|ltspice) dialect", lib.read_text())[1]
            line = f".include {lib}"
        deck.append(line.split(";")[0].rstrip())
    wave = NgspiceBatch(timeout_s=60).run("\n".join(deck), ["V(TJ)"], dialect)
    assert wave.t_s.size > 2
    # as the reader runs it, `ngspice -b deck.cir`: every .meas prints its value
    as_written = re.sub(r"(?im)^\.include\s+(\S+)", lambda m: f".include {tmp / m[1]}", body)
    (tmp / "deck.cir").write_text(as_written)
    proc = subprocess.run(["ngspice", "-b", "deck.cir"], cwd=tmp, capture_output=True, text=True,
                          timeout=60)
    for name in re.findall(r"(?im)^\.meas\w*\s+\w+\s+(\w+)", body):
        assert re.search(rf"(?im)^{name}\s*=\s*\S", proc.stdout), (
            f"ngspice -b prints no {name}:\n{proc.stdout[-2000:]}\n{proc.stderr[-2000:]}")


def _duration(text: str) -> float:
    """``20m`` -> 0.02 (a SPICE number)."""
    scale = {"f": 1e-15, "p": 1e-12, "n": 1e-9, "u": 1e-6, "m": 1e-3, "k": 1e3, "meg": 1e6}
    number, unit = re.fullmatch(r"([\d.]+(?:e[-+]?\d+)?)([a-z]*)", text.lower()).groups()
    return float(number) * scale.get(unit.removesuffix("s") if unit != "s" else "", 1.0)


def test_the_tutorial_deck_says_what_it_simulates_and_prints_in_batch_mode():
    """The README's deck: its .tran comment states the simulated time (20 ms, not "a
    second"), and a .meas makes `ngspice -b` print a result."""
    decks = [b for _, lang, b in blocks((ROOT / "README.md").read_text(encoding="utf-8"))
             if lang == "spice" and "PULSE" in b]
    assert decks, "README.md: the tutorial's deck is gone"
    deck = decks[0]
    tran = re.search(r"(?im)^\.tran\s+(\S+)\s+(\S+).*?;(.*)$", deck)
    stop = _duration(tran[2])
    stated = re.search(r"\((\d+(?:\.\d+)?)\s*(ms|s|µs|us)\)", tran[3])
    assert stated, f"the .tran comment states no duration: {tran[3]!r}"
    value = float(stated[1]) * {"s": 1.0, "ms": 1e-3, "µs": 1e-6, "us": 1e-6}[stated[2]]
    assert value == pytest.approx(stop), (tran[0], stop)
    assert re.search(r"(?im)^\.(meas|print)", deck), "ngspice -b prints nothing without it"


@pytest.mark.slow
@pytest.mark.ngspice
@pytest.mark.parametrize("doc", RUN, ids=[str(d.relative_to(ROOT)) for d in RUN])
def test_every_command_in_the_docs_runs(doc, tmp_path):
    env = _scratch(tmp_path)
    for line, language, body in blocks(doc.read_text(encoding="utf-8")):
        where = f"{doc.relative_to(ROOT)}:{line}"
        if language == "spice":
            _run_spice(body, tmp_path)
            continue
        command = ([sys.executable, "-c", body] if language == "python"
                   else ["bash", "-e", "-o", "pipefail", "-c", body])
        proc = subprocess.run(command, cwd=tmp_path,
                              env=env, capture_output=True, text=True, timeout=600)
        assert proc.returncode == 0, (
            f"{where}: a command failed (exit {proc.returncode})\n{body}\n"
            f"--- stdout (tail)\n{proc.stdout[-2000:]}\n--- stderr (tail)\n{proc.stderr[-2000:]}")


@pytest.mark.slow
def test_the_readmes_diagnosis_of_the_sample_bundle_is_what_the_commands_print(tmp_path):
    """The staircase, the verdict and the error falling, as the README's step 5 states them."""
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    quoted = re.search(r"```text\n(RMS staircase: .*?)\n(verdict: .*?)\n```", readme)
    assert quoted, "the README quotes no staircase"
    sample = ROOT / "spicethermal" / "data" / "sample_bundle"
    cli = [sys.executable, "-m", "spicethermal.cli.main"]

    def run(*args: str) -> str:
        proc = subprocess.run([*cli, *args], cwd=tmp_path, capture_output=True, text=True,
                              timeout=600)
        assert proc.returncode == 0, proc.stderr
        return proc.stdout

    out = run("diagnose", str(sample))
    assert quoted[1] in out.splitlines()
    assert any(line.startswith(quoted[2]) for line in out.splitlines())
    run("fit", str(sample), "-o", "model.json", "-q")
    run("fit", str(sample), "--effect", "tsp-nonlinearity", "-o", "model2.json")
    before = json.loads(run("compare", "model.json", str(sample), "--json"))
    after = json.loads(run("compare", "model2.json", str(sample), "--json"))
    falls = re.search(r"falls from ([0-9.]+) K .*? to ([0-9.]+) K over every data set, the "
                      r"calibration's points from ([0-9.]+) K to\s+([0-9.]+) K", readme, re.S)
    assert falls, "the README states no fall of the error"
    assert f"{before['rms_k']:.3f}".rstrip("0") == falls[1].rstrip("0")
    assert f"{after['rms_k']:.3f}".rstrip("0") == falls[2].rstrip("0")

    def cal(doc: dict) -> float:
        r = [p["residual_k"] for p in doc["points"] if p["dataset"] == "calibration"]
        return float(np.sqrt(np.mean(np.square(r))))

    assert f"{cal(before):.2g}" == falls[3] and f"{cal(after):.2g}" == falls[4]
