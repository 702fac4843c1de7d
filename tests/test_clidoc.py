"""docs/cli.md is the argparse definitions, rendered: it must not fall out of date."""

from __future__ import annotations

import re
from pathlib import Path

from spicethermal.cli.clidoc import cli_markdown, commands
from spicethermal.cli.main import build_parser

CLI_MD = Path(__file__).resolve().parent.parent / "docs" / "cli.md"


def test_cli_md_is_up_to_date():
    assert CLI_MD.read_text(encoding="utf-8") == cli_markdown(), (
        "docs/cli.md is out of date: run .venv/bin/python -m spicethermal.cli.clidoc > docs/cli.md")


def test_every_command_and_option_is_documented():
    sections = {part.split("\n", 1)[0]: part for part in cli_markdown().split("\n## ")[1:]}
    for name, parser in commands(build_parser()):
        text = sections[name]
        for action in parser._actions:
            hidden = getattr(action, "hidden_aliases", ())
            for opt in action.option_strings:
                shown = re.search(rf"(?<![\w-]){opt}(?![\w-])", text) is not None
                assert shown == (opt not in hidden), (name, opt)
