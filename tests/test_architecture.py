"""The package's shape: no import cycles, no private names across modules, one template
environment, modules of a readable size, function-local imports only where they defer a heavy
dependency (docs/architecture.md)."""

from __future__ import annotations

import ast
import importlib
import re
import subprocess
import sys
from collections.abc import Iterable
from pathlib import Path

import pytest

import spicethermal
from spicethermal.cli.main import command_help, command_modules

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


def package_imports(name: str, nodes: Iterable[ast.AST]) -> set[str]:
    """Modules of the package that the import statements among ``nodes`` of module ``name``
    load (:func:`imported`), itself excluded."""
    return {dep for node in nodes if isinstance(node, ast.Import | ast.ImportFrom)
            for dep in imported(name, node) if dep in MODULES} - {name}


def imports_on_load(name: str) -> set[str]:
    """Modules of the package that importing ``name`` imports first (module level only)."""
    return package_imports(name, module_level(ast.parse(MODULES[name].read_text())))


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


# --- function-local imports: only for heavy optional dependencies ---------------------------

#: Third-party packages a function may import locally, and why each is worth deferring. numpy
#: is not among them: every module needs it, ``import spicethermal`` loads it.
HEAVY = {
    "matplotlib": "figures only; ~0.3 s to load",
    "PySpice": "libngspice, only for --engine pyspice",
    "serial": "pyserial: the bench only",
    "jinja2": ".lib files, test benches and reports",
    "scipy": "fits, ODEs and linear algebra; ~0.2 s, not needed by --help or light commands",
    "mpmath": "exact conversions of small ladders only",
    "tqdm": "progress bars of long runs",
    "dask": "optional extra 'batch'",
    "distributed": "optional extra 'batch'",
    "pyarrow": "optional extra 'batch-parquet'",
    "rich": "not a dependency: optional terminal output",
    "hypothesis": "tests only",
}

#: Function-local imports of something light, (importer, imported module): the reason they
#: must stay local. Keep it empty unless the import is truly dynamic.
LOCAL_IMPORT_EXCEPTIONS: dict[tuple[str, str], str] = {
    ("spicethermal.effects.registry", "importlib"):
        "every effect is a plugin found through entry points when the registry is first "
        "read; importlib.metadata (~40 ms: email, zipfile) would load with every command",
    ("spicethermal.analysis.diagnosis", "spicethermal.viz.plots"):
        "a result's .plot() draws it: computation never imports presentation at module level",
    ("spicethermal.analysis.table2", "spicethermal.viz.diagnosis"):
        "a result's .plot() draws it: computation never imports presentation at module level",
    ("spicethermal.drive.result", "spicethermal.viz.pwm"):
        "a result's .plot() draws it: computation never imports presentation at module level",
}


def parents(name: str) -> list[str]:
    """The packages Python imports before module ``name`` (``a.b.c``: ``a``, ``a.b``)."""
    parts = name.split(".")
    return [".".join(parts[:i]) for i in range(1, len(parts))]


def imported(importer: str, node: ast.Import | ast.ImportFrom) -> set[str]:
    """The modules an import statement of ``importer`` loads: the package's own modules by
    name, third-party and standard ones by their top-level package."""
    if isinstance(node, ast.Import):
        names = {a.name for a in node.names}
    else:
        target = resolve(importer, node)
        subs = {f"{target}.{a.name}" for a in node.names} & MODULES.keys()
        names = subs | ({target} if len(subs) < len(node.names) else set())
    return {n if n in MODULES else n.split(".")[0] for n in names}


def heavy_on_load() -> dict[str, set[str]]:
    """For each module of the package, the heavy packages that importing it loads: by its own
    module-level imports, its parent packages' and those of every module they import."""
    direct: dict[str, set[str]] = {}
    for name, path in MODULES.items():
        deps = set(parents(name))
        for node in module_level(ast.parse(path.read_text())):
            if isinstance(node, ast.Import | ast.ImportFrom):
                for dep in imported(name, node):
                    deps.update([dep, *parents(dep)] if dep in MODULES else [dep])
        direct[name] = deps - {name}
    heavy = {name: {d for d in deps if d in HEAVY} for name, deps in direct.items()}
    changed = True
    while changed:  # the closure over module-level imports: a fixed point
        changed = False
        for name, deps in direct.items():
            more = set().union(*(heavy[d] for d in deps if d in MODULES)) - heavy[name]
            if more:
                heavy[name] |= more
                changed = True
    return heavy


def local_imports(tree: ast.Module):
    """Import statements inside function and method bodies (module-level ``if``/``try`` and
    ``TYPE_CHECKING`` blocks are not function bodies)."""
    def visit(node: ast.AST, in_function: bool):
        for child in ast.iter_child_nodes(node):
            if in_function and isinstance(child, ast.Import | ast.ImportFrom):
                yield child
            yield from visit(child, in_function or isinstance(
                child, ast.FunctionDef | ast.AsyncFunctionDef))
    yield from visit(tree, False)


def needless_local_imports() -> set[tuple[str, str]]:
    """(importer, imported) for every function-local import that defers no heavy package:
    the imported module loads nothing heavy, or nothing the importer does not load anyway."""
    heavy = heavy_on_load()
    found = set()
    for name, path in MODULES.items():
        for node in local_imports(ast.parse(path.read_text())):
            for dep in imported(name, node):
                deferred = (heavy[dep] if dep in MODULES else {dep} & HEAVY.keys()) - heavy[name]
                if not deferred:
                    found.add((name, dep))
    return found


def test_the_heavy_closure_follows_module_level_imports_only() -> None:
    heavy = heavy_on_load()
    assert heavy["spicethermal.bench.protocol_sim"] == {"serial"}  # imports pyserial itself
    assert "scipy" in heavy["spicethermal.validation.network"]
    assert heavy["spicethermal.core.errors"] == set()
    assert heavy["spicethermal"] == set()  # the public API is lazy (tests/test_api.py)


def test_function_local_imports_only_defer_heavy_dependencies() -> None:
    found = needless_local_imports()
    assert not found - LOCAL_IMPORT_EXCEPTIONS.keys(), (
        "import these at the top of the module (a cycle means a shared piece belongs in a "
        f"lower module): {sorted(found - LOCAL_IMPORT_EXCEPTIONS.keys())}")
    assert not LOCAL_IMPORT_EXCEPTIONS.keys() - found, (
        f"fixed, remove from the exceptions: {sorted(LOCAL_IMPORT_EXCEPTIONS.keys() - found)}")


def test_the_command_line_help_stays_light() -> None:
    code = ("import sys\nfrom spicethermal.cli.main import main\n"
            "try:\n    main(['--help'])\nexcept SystemExit:\n    pass\n"
            f"print(sorted(m for m in {sorted(HEAVY)!r} if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip().splitlines()[-1] == "[]", out.stdout


def test_the_light_command_list_says_what_the_command_modules_say() -> None:
    for name, info in command_modules().items():
        module = importlib.import_module(f"spicethermal.cli.commands.{info.name}")
        assert (module.NAME, module.HELP) == (name, command_help(info))


def all_imports(name: str) -> set[str]:
    """Modules of the package that module ``name`` imports anywhere: at module level, under
    ``TYPE_CHECKING`` and in function bodies (a lazy import is still an arrow)."""
    out = package_imports(name, ast.walk(ast.parse(MODULES[name].read_text())))
    return {m for m in out if not (name.startswith(m + ".") and MODULES[m].name == "__init__.py")}


def test_no_import_cycle_even_through_type_only_or_lazy_imports() -> None:
    graph = {name: all_imports(name) for name in MODULES}
    assert not cycles(graph), f"import cycles (any import): {cycles(graph)}"


#: Computation (the rooms below) never imports presentation; a result's ``.plot()`` is the
#: one way in, lazily (:data:`LOCAL_IMPORT_EXCEPTIONS`).
COMPUTATION = ("core", "effects", "engines", "fit", "identify", "analysis", "drive", "io")
PRESENTATION = ("spicethermal.viz", "spicethermal.report", "spicethermal.cli")


def test_computation_never_imports_presentation_at_module_level() -> None:
    bad = {(name, dep) for name in MODULES
           if name.split(".")[1:2] and name.split(".")[1] in COMPUTATION
           for dep in imports_on_load(name) if dep.startswith(PRESENTATION)}
    assert not bad, sorted(bad)


def test_io_reads_files_and_identify_interprets_them_not_both_ways() -> None:
    io_to_identify = {(n, d) for n in MODULES if n.startswith("spicethermal.io")
                      for d in all_imports(n) if d.startswith("spicethermal.identify")}
    assert not io_to_identify, sorted(io_to_identify)


def test_no_effect_is_named_outside_the_effects_package() -> None:
    """Effects are plugins: nothing outside ``spicethermal/effects/`` spells one's name (the
    independent validation generator, which holds each case's truth as a label, excepted)."""
    from spicethermal.effects import CATALOGUE

    names = set(CATALOGUE)
    found = []
    for name, path in MODULES.items():
        if name.startswith(("spicethermal.effects", "spicethermal.validation")):
            continue
        tree = ast.parse(path.read_text())
        docs = {id(n.body[0].value) for n in ast.walk(tree)  # docstrings document, not code
                if isinstance(n, ast.Module | ast.ClassDef | ast.FunctionDef)
                and n.body and isinstance(n.body[0], ast.Expr)
                and isinstance(n.body[0].value, ast.Constant)}
        for node in ast.walk(tree):
            if id(node) in docs:
                continue
            if isinstance(node, ast.Constant) and isinstance(node.value, str):
                text = node.value
                hits = [n for n in names if n == text or f'"{n}"' in text or f"'{n}'" in text]
                if hits:
                    found.append((name, node.lineno, hits))
    assert not found, found


FIRMWARE = Path(__file__).resolve().parent.parent / "firmware"
C_DEFINITION = re.compile(r"^(?!static\b)[A-Za-z_][\w \t\*]*?\b([A-Za-z_]\w*)\s*\([^;{}]*\)\s*\{",
                          re.M)
C_CALL = re.compile(r"\b([A-Za-z_]\w*)\s*\(")


def c_calls(sources: dict[str, str], interface: frozenset[str] = frozenset()
            ) -> dict[str, set[str]]:
    """File -> the files whose external functions it calls (comments and strings ignored);
    the ``interface``'s functions, which each hardware layer defines, belong to no file."""
    text = {name: re.sub(r'/\*.*?\*/|//[^\n]*|"(?:\\.|[^"\\])*"', " ", body, flags=re.S)
            for name, body in sources.items()}
    owner = {fn: name for name, body in text.items() for fn in C_DEFINITION.findall(body)
             if fn not in interface}
    return {name: {owner[fn] for fn in C_CALL.findall(body) if owner.get(fn, name) != name}
            for name, body in text.items()}


def test_the_c_call_graph_sees_definitions_and_calls() -> None:
    graph = c_calls({"a.c": "/* b_f() */\nvoid a_f(int x)\n{\n    b_f();\n}\n",
                     "b.c": "uint8_t b_f(void)\n{\n    return a_f(1);\n}\n"
                            "static void b_g(void)\n{\n}\n"})
    assert graph == {"a.c": {"b.c"}, "b.c": {"a.c"}} and cycles(graph) == [["a.c", "b.c"]]


def test_no_circle_between_the_firmwares_files() -> None:
    """The portable core's files call down, never round (a procedure split over two files
    shares what both use through a third below them, st_proc.c); the hardware layers call the
    core, which reaches them only through the interface of ``st_hal.h``."""
    sources = {str(p.relative_to(FIRMWARE)): p.read_text(encoding="utf-8")
               for p in sorted([*FIRMWARE.glob("src/*.c"), *FIRMWARE.glob("hal/*/*.c")])}
    hal = (FIRMWARE / "src" / "st_hal.h").read_text(encoding="utf-8")
    interface = frozenset(re.findall(r"\b(hal_\w+)\s*\(", hal))
    graph = c_calls(sources, interface)
    assert "src/st_proc.c" in graph["src/st_array.c"], "the call graph reads no call"
    assert not cycles(graph), f"circles between firmware files: {cycles(graph)}"
