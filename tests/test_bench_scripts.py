"""The benchmark scripts stay runnable: every name they import from the package exists.

The studies are not run by the tests (they take minutes); a renamed or removed module breaks
them silently, so their imports are checked here, reading the scripts without running them.
"""

from __future__ import annotations

import ast
import importlib
from pathlib import Path

import pytest

BENCH = Path(__file__).resolve().parent.parent / "bench"
SCRIPTS = sorted(BENCH.glob("*.py"))


def _imports(path: Path) -> list[tuple[str, str]]:
    """``(module, name)`` of every ``from spicethermal... import name`` in ``path``, nested
    ones included (``name`` empty for a plain ``import spicethermal...``)."""
    out = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("spicethermal"):
            out += [(node.module, a.name) for a in node.names]
        elif isinstance(node, ast.Import):
            out += [(a.name, "") for a in node.names if a.name.startswith("spicethermal")]
    return out


def test_there_are_scripts_to_check():
    assert len(SCRIPTS) >= 10 and any(_imports(p) for p in SCRIPTS)


@pytest.mark.parametrize("script", SCRIPTS, ids=lambda p: p.name)
def test_every_name_a_script_imports_exists(script):
    missing = []
    for module, name in _imports(script):
        try:
            mod = importlib.import_module(module)
        except ImportError:
            missing.append(module)
            continue
        if name and not hasattr(mod, name):
            try:
                importlib.import_module(f"{module}.{name}")
            except ImportError:
                missing.append(f"{module}.{name}")
    assert not missing, f"{script.name} imports what the package no longer has: {missing}"
