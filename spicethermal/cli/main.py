"""The ``spicethermal`` command line.

Each sub-command lives in its own module under :mod:`spicethermal.cli.commands`, named for
the command (``import_.py`` for ``import``), and defines ``NAME``, ``HELP``,
``add_arguments(parser)`` and ``run(args) -> int``. They are discovered here, so adding a
command never touches this file. Only the module of the command run is imported (with the
library it needs); the others are listed by the ``HELP`` read from their source, so
``spicethermal --help`` stays light. Errors raised on purpose
(:class:`~spicethermal.core.errors.SpiceThermalError`) become one line on stderr and exit code 2;
so do numerical failures on absurd input; anything else is a bug, reported in one line with
exit code 70.
"""

from __future__ import annotations

import argparse
import ast
import importlib
import os
import pkgutil
import sys
import warnings
from collections.abc import Sequence
from pathlib import Path

from .. import __version__
from ..core.errors import SpiceThermalError
from . import commands
from .commands._types import NEGATIVE


class _Parser(argparse.ArgumentParser):
    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        # -94m, -40, -2.5e3 are values, not options (argparse knows only -40 and -2.5)
        self._negative_number_matcher = NEGATIVE

    def error(self, message: str) -> None:  # one line, exit 2 (argparse's own convention)
        self.exit(2, f"{self.prog}: error: {one_line(message)}\n")


def one_line(text: object, limit: int = 600) -> str:
    """``text`` as one printable line: control characters (newline, NUL, escape...) shown
    as escapes, at most ``limit`` characters.

    >>> one_line("bad\\nname\\x00.csv: " + "x" * 10, limit=24)
    'bad\\\\nname\\\\x00.csv: xx...'
    """
    out = "".join(c if c.isprintable() else repr(c)[1:-1] for c in str(text))
    return out if len(out) <= limit else out[:limit - 3] + "..."


def command_modules() -> dict[str, pkgutil.ModuleInfo]:
    """Every sub-command's module, by command name (the module's name without a trailing
    ``_``), in the order ``--help`` lists them.

    Returns
    -------
    dict of str to pkgutil.ModuleInfo

    Examples
    --------
    >>> names = list(command_modules())
    >>> names[:2], "import" in names
    (['batch', 'bench'], True)
    """
    infos = sorted(pkgutil.iter_modules(commands.__path__), key=lambda m: m.name)
    return {info.name.rstrip("_"): info for info in infos if not info.name.startswith("_")}


def command_help(info: pkgutil.ModuleInfo) -> str:
    """A sub-command's one-line ``HELP``, read from its source without importing the module
    (nor the library it imports); imported when the source does not spell it literally.

    Parameters
    ----------
    info : pkgutil.ModuleInfo
        The command's module (:func:`command_modules`).

    Returns
    -------
    str

    Examples
    --------
    >>> command_help(command_modules()["compare"])
    "measured vs model over every data set of a bundle (the paper's Table 2)"
    """
    source = Path(getattr(info.module_finder, "path", "")) / f"{info.name}.py"
    blocks = source.read_text(encoding="utf-8").split("\n\n") if source.is_file() else []
    for block in blocks:  # parse only the paragraph that assigns HELP: a few ms in all
        if block.startswith("HELP = ") or "\nHELP = " in block:
            try:
                node = next(n for n in ast.parse(block).body if isinstance(n, ast.Assign)
                            and getattr(n.targets[0], "id", None) == "HELP")
                return str(ast.literal_eval(node.value))
            except (SyntaxError, ValueError, StopIteration):
                break
    return importlib.import_module(f"{commands.__name__}.{info.name}").HELP


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The ``spicethermal`` parser.

    Parameters
    ----------
    command : str, optional
        Build only this sub-command's arguments (importing only its module); the others are
        listed by name and help. None (the default): every sub-command in full, as the
        reference (``docs/cli.md``) and the tests read them.

    Returns
    -------
    argparse.ArgumentParser

    Examples
    --------
    >>> build_parser("pwm").parse_args(["pwm", "m.json", "--freq", "1k", "--duty", "0.5",
    ...                                 "--power", "1"]).freq
    (1000.0,)
    """
    parser = _Parser(prog="spicethermal", description=__doc__.splitlines()[0])
    parser.add_argument("--version", action="version", version=f"spicethermal {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    for name, info in command_modules().items():
        if command is not None and name != command:
            sub.add_parser(name, help=command_help(info))
            continue
        module = importlib.import_module(f"{commands.__name__}.{info.name}")
        p = sub.add_parser(module.NAME, help=module.HELP, description=module.HELP)
        module.add_arguments(p)
        p.set_defaults(_run=module.run)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit code: 0 done, 2 bad input or a failure the
    message explains (one line on stderr, never a traceback), 70 an internal error (a bug:
    one line too; ``SPICETHERMAL_DEBUG=1`` shows the traceback)."""
    argv = sys.argv[1:] if argv is None else list(argv)
    # the first word not an option is the command (the top level has no option with a value)
    parser = build_parser(next((a for a in argv if not a.startswith("-")), ""))
    args = parser.parse_args(argv)
    if not getattr(args, "_run", None):
        parser.print_help()
        return 2

    def fail(text: str, code: int = 2) -> int:
        print(one_line(f"spicethermal {args.command}: error: {text}"), file=sys.stderr)
        return code

    def warn(message, category, filename, lineno, file=None, line=None) -> None:
        print(one_line(f"spicethermal {args.command}: warning: {message}"), file=sys.stderr)

    try:
        with warnings.catch_warnings():
            # numerical warnings would break the one-line contract; results are checked
            warnings.simplefilter("ignore", RuntimeWarning)
            warnings.showwarning = warn
            return int(args._run(args) or 0)
    except SpiceThermalError as exc:
        return fail(str(exc))
    except KeyboardInterrupt:
        return fail("interrupted")
    except OSError as exc:
        name = getattr(exc, "filename", None)
        text = exc.strerror or type(exc).__name__
        return fail(f"{name}: {text}" if name is not None else text)
    except RecursionError:
        return fail("the input is nested too deeply to process")
    except MemoryError:
        return fail("out of memory: the input is too large")
    except (ArithmeticError, ValueError) as exc:
        if os.environ.get("SPICETHERMAL_DEBUG"):
            raise
        if "null byte" in str(exc) or "null character" in str(exc):
            return fail("a file name contains a NUL character")
        return fail(f"cannot compute a result from this input ({type(exc).__name__}: {exc}); "
                    f"check it for absurd or degenerate values")
    except Exception as exc:
        if os.environ.get("SPICETHERMAL_DEBUG"):
            raise
        return fail(f"internal error ({type(exc).__name__}: {exc}); please report it with "
                    f"the command line (SPICETHERMAL_DEBUG=1 shows the traceback)", 70)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
