"""docs/cli.md: the command-line reference, generated from the argparse definitions.

Regenerate after changing an option (``tests/test_clidoc.py`` fails while it is out of date)::

    .venv/bin/python -m spicethermal.cli.clidoc > docs/cli.md
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Iterator
from unittest import mock

from .main import build_parser

__all__ = ["cli_markdown", "commands"]

#: Width of the generated help text (independent of the terminal).
WIDTH = 100


def commands(parser: argparse.ArgumentParser, name: str = "spicethermal"
             ) -> Iterator[tuple[str, argparse.ArgumentParser]]:
    """Every (sub-)command's full name and parser, depth first, as ``--help`` lists them.

    Parameters
    ----------
    parser : the top-level parser (:func:`spicethermal.cli.main.build_parser`).
    name : its program name.

    Returns
    -------
    Iterator of ``(name, parser)``, the top level first.

    Examples
    --------
    >>> from spicethermal.cli.main import build_parser
    >>> names = [n for n, _ in commands(build_parser())]
    >>> names[0], "spicethermal bench run" in names
    ('spicethermal', True)
    """
    yield name, parser
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for sub, subparser in action.choices.items():
                yield from commands(subparser, f"{name} {sub}")


def cli_markdown() -> str:
    """The Markdown reference of every command and sub-command, in the order of ``--help``.

    Returns
    -------
    str : the text of docs/cli.md.

    Examples
    --------
    >>> text = cli_markdown()
    >>> text.startswith("# Command-line reference") and "## spicethermal fit" in text
    True
    """
    with mock.patch.dict(os.environ, {"COLUMNS": str(WIDTH)}):
        pages = [(name, p.format_help()) for name, p in commands(build_parser())]
    out = ["# Command-line reference", "",
           "Generated from the argparse definitions by `python -m spicethermal.cli.clidoc > "
           "docs/cli.md`; `tests/test_clidoc.py` fails when it is out of date.", "",
           "Numbers take SPICE and SI prefixes in any case and optional units in any case "
           "(`1k`, `25kHz`, `25KHz`, `100u`, `100us`, `2.5m`, `94mw`, `25meg`, `1e-4`, `20%`): "
           "prefixes `f p n u/µ m k meg g`, units `Hz s W J V A`. A capital `M` is refused "
           "(milli in SPICE, mega in SI: write `m` or `meg`). `K` is kilo, as in SPICE, except "
           "on an option measured in kelvin (metavar `K`), where it is the unit (`--tol 0.5K`). "
           "An option with a unit refuses the others (`--freq 1s`). Negative values read as "
           "values (`--ambient -40`, `--ambient -4e1`) and are refused in one line where they "
           "make no sense.", "",
           "One spelling per concept: `-o/--output` is the data a command writes (a model, a "
           "table, a `.lib`, a directory), `--plot FIG.png` a figure, `--report DIR` an HTML "
           "report, `--power W` a power in watts, `--profile PROFILE.csv` a power profile, "
           "`--freq HZ,...` and `--duty D,...` frequencies and duty cycles (a list where a "
           "command takes several), `--ambient DEGC` the reference temperature. Old spellings "
           "(`--tref`, `--p-max`, `--freqs`, `--duties`, `-o FIG.png`, ...) still work in this "
           "release, hidden from the help, with a one-line deprecation note on stderr.", ""]
    out += [f"- [`{name}`](#{name.replace(' ', '-')})" for name, _ in pages[1:]]
    for name, text in pages:
        out += ["", f"## {name}", "", "```text", text.rstrip(), "```"]
    return "\n".join(out) + "\n"


if __name__ == "__main__":  # pragma: no cover
    sys.stdout.write(cli_markdown())
