"""Regenerate the benchmark table in bench/README.md (``make bench`` runs this with ``--all``).

Each ``bench_*.py`` with a ``summary()`` gives its rows (benchmark, before, today, target); the
others are studies that print their figures: with ``--all`` each is run (its output shown) and
its wall time recorded, without it their rows say so. The table goes between the markers of
bench/README.md; the rest of the file is kept.

Run: ``.venv/bin/python bench/table.py [--all]``
"""

from __future__ import annotations

import importlib.util
import re
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
README = HERE / "README.md"
BEGIN, END = "<!-- table: begin (bench/table.py) -->", "<!-- table: end -->"


def _module(path: Path):
    spec = importlib.util.spec_from_file_location(path.stem, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def rows(run_all: bool) -> list[tuple[str, ...]]:
    out = []
    for path in sorted(HERE.glob("bench_*.py")):
        command = f"`.venv/bin/python bench/{path.name}`"
        text = path.read_text(encoding="utf-8")
        if "def summary(" in text:
            print(f"== {path.name}: summary", flush=True)
            out += [(*row, command) for row in _module(path).summary()]
            continue
        title = re.search(r'"""(.*?)(?:\n\n|""")', text, re.S)[1].replace("\n", " ").strip()
        figure = "figures in its output (`make bench`)"
        if run_all:
            print(f"== {path.name}", flush=True)
            t0 = time.perf_counter()
            subprocess.run([sys.executable, str(path)], check=True)
            figure = f"runs in {time.perf_counter() - t0:.0f} s; figures in its output"
        out.append((title, "—", figure, "study (no single target)", command))
    return out


def table(all_rows: list[tuple[str, ...]]) -> str:
    head = ["benchmark", "before (main, issue #18)", "today", "target", "command"]
    lines = ["| " + " | ".join(head) + " |", "|" + " --- |" * len(head)]
    lines += ["| " + " | ".join(cell.replace("|", "\\|") for cell in row) + " |"
              for row in all_rows]
    return "\n".join(lines)


def main(argv: list[str]) -> None:
    text = README.read_text(encoding="utf-8")
    start, stop = text.index(BEGIN) + len(BEGIN), text.index(END)
    stamp = time.strftime("%Y-%m-%d", time.gmtime())
    body = f"\n\nMeasured {stamp}.\n\n{table(rows('--all' in argv))}\n\n"
    README.write_text(text[:start] + body + text[stop:], encoding="utf-8")
    print(f"wrote {README}")


if __name__ == "__main__":
    main(sys.argv[1:])
