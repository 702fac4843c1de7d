"""The package as users meet it: a light import, every command's --help, one-line errors."""

from __future__ import annotations

import subprocess
import sys

import pytest

from spicethermal.cli.main import build_parser, main

HEAVY = ("matplotlib", "scipy", "PySpice", "serial", "jinja2", "mpmath")


def test_import_stays_light():
    code = ("import sys, spicethermal; "
            f"print(','.join(m for m in {HEAVY!r} if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.strip()
    assert out == "", f"import spicethermal loaded {out}"


def _commands() -> list[str]:
    sub = next(a for a in build_parser()._actions if a.dest == "command")
    return sorted(sub.choices)


def test_contract_commands_exist():
    for name in ("demo", "fit", "export", "pwm", "compare"):
        assert name in _commands()


@pytest.mark.parametrize("command", _commands())
def test_every_command_has_help(command, capsys):
    with pytest.raises(SystemExit) as exc:
        main([command, "--help"])
    assert exc.value.code == 0
    assert "usage: spicethermal " + command in capsys.readouterr().out


def test_unknown_arguments_are_one_line_exit_2():
    proc = subprocess.run([sys.executable, "-m", "spicethermal.cli.main", "export", "--bogus"],
                          capture_output=True, text=True)
    assert proc.returncode == 2
    assert len(proc.stderr.strip().splitlines()) == 1 and "Traceback" not in proc.stderr
