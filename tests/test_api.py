"""The public API: lazily loaded, complete, documented, and the README's example runs."""

from __future__ import annotations

import inspect
import re
import subprocess
import sys
from pathlib import Path

import pytest

import spicethermal

README = Path(__file__).resolve().parents[1] / "README.md"
HEAVY = ("matplotlib", "PySpice", "serial", "jinja2")


def test_import_is_light() -> None:
    code = f"import sys, spicethermal; print([m for m in {HEAVY!r} if m in sys.modules])"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


@pytest.mark.parametrize("name", spicethermal.__all__)
def test_every_public_name_resolves_and_is_documented(name: str) -> None:
    obj = getattr(spicethermal, name)
    if name == "__version__":
        assert re.fullmatch(r"\d+\.\d+\.\d+", obj)
        return
    doc = inspect.getdoc(obj) or ""
    assert doc.strip(), f"{name} has no docstring"
    if inspect.isfunction(obj):  # numpydoc sections of every public function
        if inspect.signature(obj).parameters:
            assert "\nParameters\n----------" in doc, f"{name}: numpydoc 'Parameters' missing"
        assert "\nReturns\n-------" in doc, f"{name}: numpydoc 'Returns' missing"


def test_unknown_name_is_an_attribute_error() -> None:
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        _ = spicethermal.nope  # noqa: B018


def test_readme_python_example_runs(tmp_path: Path) -> None:
    blocks = re.findall(r"```python\n(.*?)```", README.read_text(), flags=re.S)
    assert blocks, "README has no Python example"
    for i, code in enumerate(blocks):
        script = tmp_path / f"example_{i}.py"
        script.write_text(code)
        out = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                             cwd=tmp_path, timeout=120)
        assert out.returncode == 0, out.stderr
        # the printed values are the ones the comments promise
        for line in code.splitlines():
            m = re.match(r"print\(.*\)\s+# (\d[\d. ]*)$", line.strip())
            if m:
                assert m.group(1).strip() in out.stdout, (line, out.stdout)
