"""A newcomer's path: README.md top to bottom, in a fresh shell, in a fresh clone.

This is the one run of the README's commands (``tests/test_docs.py`` runs the other docs' and
checks the figures the README states). Nothing is on the PATH but the system's, as in a new
terminal after ``make``: the README itself must say how to reach ``spicethermal``. The clone is
the working tree as it is (HEAD, with the tracked files' uncommitted changes copied over);
``make`` is not run again: the clone's ``.venv`` is the checkout's (what ``make setup`` built),
so nothing is installed. The blocks run in order in one shell session, as typed: ``sh`` as is,
``python`` through ``python``, a ``spice`` deck saved to a file and run by ``ngspice -b`` (into a
raw file when the README runs it interactively).
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
from pathlib import Path

import pytest
from test_docs import blocks

ROOT = Path(__file__).resolve().parent.parent
#: The shell a new terminal has: the system's directories only.
SYSTEM_PATH = os.pathsep.join(p for p in ("/usr/local/bin", "/usr/bin", "/bin")
                              if Path(p).is_dir())


def script(readme: str) -> str:
    """The README's blocks as one bash session, in order."""
    lines = []
    for k, (line, language, body) in enumerate(blocks(readme)):
        lines.append(f"echo '--- README.md:{line} ({language})'")
        if language == "sh":
            lines.append(body)
        elif language == "python":
            lines.append(f"python - <<'PY_{k}'\n{body}PY_{k}")
        else:  # spice: saved as a deck and run in batch mode (a deck the README runs
            # interactively, with no .meas or .print, writes its waveforms to a raw file)
            raw = "" if re.search(r"(?im)^\.(meas|print)", body) else f"-r readme_deck_{k}.raw "
            lines += [f"cat > readme_deck_{k}.cir <<'CIR_{k}'\n{body}CIR_{k}",
                      f"ngspice -b {raw}readme_deck_{k}.cir"]
    return "\n".join(lines) + "\n"


def test_the_session_is_the_blocks_in_order():
    text = "```sh\necho a\n```\n```python\nprint(1)\n```\n```spice\n* t\n.end\n```\n"
    out = script(text)
    assert out.index("echo a") < out.index("python - <<'PY_1'") < out.index("ngspice -b")


def _clone(tmp: Path) -> Path:
    """A clone of the checkout with its tracked files as they are now."""
    if shutil.which("git") is None or not (ROOT / ".git").exists():
        pytest.skip("not a git checkout")
    clone = tmp / "spicethermal"
    subprocess.run(["git", "clone", "-q", "--no-hardlinks", str(ROOT), str(clone)], check=True,
                   capture_output=True, timeout=120)
    changed = subprocess.run(["git", "-C", str(ROOT), "diff", "--name-only", "HEAD"],
                             check=True, capture_output=True, text=True).stdout.split()
    for name in changed:
        src, dst = ROOT / name, clone / name
        if src.is_file():
            dst.parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(src, dst)
        elif dst.exists():
            dst.unlink()
    (clone / ".venv").symlink_to(ROOT / ".venv")  # what `make setup` built: not reinstalled
    return clone


@pytest.mark.slow
@pytest.mark.ngspice
def test_the_readme_runs_as_written_in_a_fresh_shell(tmp_path):
    if not (ROOT / ".venv" / "bin" / "activate").is_file():
        pytest.skip("no .venv: run `make setup`")
    clone = _clone(tmp_path)
    (clone / "readme.sh").write_text(script((clone / "README.md").read_text(encoding="utf-8")))
    home = tmp_path / "home"
    home.mkdir()
    env = {"HOME": str(home), "PATH": SYSTEM_PATH, "LANG": "C.UTF-8", "MPLBACKEND": "Agg",
           "TERM": "dumb"}
    proc = subprocess.run(["bash", "-e", "-o", "pipefail", "readme.sh"], cwd=clone, env=env,
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, (
        f"README.md, run as written in a fresh shell, fails (exit {proc.returncode})\n"
        f"--- stdout (tail)\n{proc.stdout[-3000:]}\n--- stderr (tail)\n{proc.stderr[-3000:]}")
    assert "tj_peak" in proc.stdout  # the tutorial's deck printed its measurement
