"""The package's shape: no import cycles, no private names across modules, one template
environment, modules of a readable size (docs/architecture.md)."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import spicethermal

PACKAGE = Path(spicethermal.__file__).resolve().parent
MAX_LINES = 500

#: Modules still over MAX_LINES (being split on other branches): shrink, never grow.
TOO_LONG: set[str] = set()

#: Private names still imported across modules (importer, name), in files being reworked on
#: other branches: shrink, never grow.
PRIVATE_IMPORTS: set[tuple[str, str]] = set()


def module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES = {module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


def resolve(importer: str, node: ast.ImportFrom) -> str:
    """The absolute module a ``from ... import`` statement of module ``importer`` reads."""
    if not node.level:
        return node.module or ""
    package = importer if MODULES[importer].name == "__init__.py" else importer.rpartition(".")[0]
    base = package.split(".")[:len(package.split(".")) - node.level + 1]
    return ".".join(base + ([node.module] if node.module else []))


def is_type_checking(node: ast.stmt) -> bool:
    return isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test)


def module_level(tree: ast.Module):
    """Statements run on import: the body and its if/try blocks, but not ``TYPE_CHECKING``
    blocks nor function or class bodies."""
    todo = list(tree.body)
    while todo:
        node = todo.pop()
        if is_type_checking(node):
            continue
        if isinstance(node, ast.If | ast.Try):
            todo.extend(node.body + node.orelse + getattr(node, "finalbody", []))
            for handler in getattr(node, "handlers", []):
                todo.extend(handler.body)
        yield node


def imports_on_load(name: str) -> set[str]:
    """Modules of the package that importing ``name`` imports first (module level only)."""
    out: set[str] = set()
    for node in module_level(ast.parse(MODULES[name].read_text())):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names if a.name in MODULES)
        elif isinstance(node, ast.ImportFrom):
            target = resolve(name, node)
            subs = {f"{target}.{a.name}" for a in node.names} & MODULES.keys()
            out.update(subs)
            if target in MODULES and len(subs) < len(node.names):
                out.add(target)  # names defined by the module itself (not submodules)
    out.discard(name)
    return out


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    found: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def test_the_cycle_finder_finds_cycles() -> None:
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert cycles({"a": {"b"}, "b": set()}) == []


def test_no_import_cycle() -> None:
    graph = {name: imports_on_load(name) for name in MODULES}
    assert not cycles(graph), f"import cycles (module level): {cycles(graph)}"


def private_imports() -> set[tuple[str, str]]:
    found = set()
    for name, path in MODULES.items():
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom):
                target = resolve(name, node)
                if target.split(".")[0] != "spicethermal" or target == name:
                    continue
                found.update((name, a.name) for a in node.names
                             if a.name.startswith("_") and not a.name.startswith("__"))
    return found


def test_no_private_name_is_imported_across_modules() -> None:
    found = private_imports()
    assert not found - PRIVATE_IMPORTS, ("make these public (or keep them in one module): "
                                         f"{sorted(found - PRIVATE_IMPORTS)}")
    assert not PRIVATE_IMPORTS - found, f"fixed, remove from the list: " \
                                        f"{sorted(PRIVATE_IMPORTS - found)}"


def test_exactly_one_jinja2_environment() -> None:
    places = [f"{name}:{n}" for name, path in MODULES.items()
              for n, line in enumerate(path.read_text().splitlines(), start=1)
              if "jinja2.Environment(" in line]
    assert len(places) == 1, places


def test_html_is_escaped_and_spice_text_is_not() -> None:
    from spicethermal.spice.templates import environment, template_dir

    env = environment()
    names = [p.relative_to(template_dir()).as_posix()
             for p in sorted(template_dir().rglob("*.j2"))]
    assert {n for n in names if env.autoescape(n)} == {n for n in names if n.endswith(".html.j2")}
    assert env.from_string("{{ x }}").render(x="V(a)<1") == "V(a)<1"
    page = env.get_template("report/index.html.j2")
    assert page.environment is env
    with pytest.raises(Exception, match="undefined"):
        env.from_string("{{ missing }}").render()


@pytest.mark.parametrize("name", sorted(MODULES))
def test_modules_stay_readable(name: str) -> None:
    lines = len(MODULES[name].read_text().splitlines())
    if name in TOO_LONG:
        assert lines > MAX_LINES, f"{name} has {lines} lines now: remove it from TOO_LONG"
        return
    assert lines <= MAX_LINES, f"{name}: {lines} lines (split it by what it holds)"
