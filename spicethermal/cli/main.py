"""The ``spicethermal`` command line.

Each sub-command lives in its own module under :mod:`spicethermal.cli.commands` and defines
``NAME``, ``HELP``, ``add_arguments(parser)`` and ``run(args) -> int``. They are discovered
here, so adding a command never touches this file. Errors raised on purpose
(:class:`~spicethermal.core.errors.SpiceThermalError`) become one line on stderr and exit code 2;
so do numerical failures on absurd input; anything else is a bug, reported in one line with
exit code 70.
"""

from __future__ import annotations

import argparse
import importlib
import os
import pkgutil
import sys
import warnings
from collections.abc import Sequence

from ..core.errors import SpiceThermalError
from . import commands


class _Parser(argparse.ArgumentParser):
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


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="spicethermal", description=__doc__.splitlines()[0])
    from .. import __version__

    parser.add_argument("--version", action="version", version=f"spicethermal {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    for info in sorted(pkgutil.iter_modules(commands.__path__), key=lambda m: m.name):
        if info.name.startswith("_"):
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
    parser = build_parser()
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
