"""One spelling per concept: a walk over every command's argparse (new commands included).

The rules (each failure message says what to rename):

1. Renamed concepts: ``--out`` -> ``-o/--output``; ``--window-s`` -> ``--window``; ``--f-pwm``
   -> ``--freq``; ``--tref`` -> ``--ambient``; ``--settle-s`` -> ``--settle``; ``--fig``,
   ``--figure`` -> ``--plot``; ``--outdir``, ``--output-dir``, ``--report-dir`` -> ``--report``.
2. No unit in an option's name (``--window-s``, ``--power-w``): the unit goes in the metavar.
3. ``-o`` and ``--output`` come together (what the command writes); ``-q`` and ``--quiet`` too.
4. ``--plot`` takes a figure file (metavar like ``FIG.png``); ``--report`` a directory (``DIR``).
5. ``--model`` is only an input: its help must not say it writes (an output model is
   ``-o/--output``).
6. ``--json`` takes no value: it prints the machine-readable document.

Old spellings stay accepted as hidden aliases (:func:`spicethermal.cli.commands._types.add_option`,
``old=(...)``); the rules apply to the spellings ``--help`` shows.
"""

from __future__ import annotations

import argparse
import re

import pytest

from spicethermal.cli.clidoc import commands
from spicethermal.cli.main import build_parser

RENAMED = {"--out": "-o/--output", "--window-s": "--window", "--f-pwm": "--freq",
           "--tref": "--ambient", "--settle-s": "--settle", "--fig": "--plot",
           "--figure": "--plot", "--outdir": "--report", "--output-dir": "--report",
           "--report-dir": "--report"}
UNIT_SUFFIX = re.compile(r"^--.+-(s|hz|w|k|c|v|degc|k-per-w)$")
HOW = "(keep the old spelling with add_option(parser, ..., old=('{old}',)))"


def _options(parser: argparse.ArgumentParser):
    for name, command in commands(parser):
        for action in command._actions:
            if action.option_strings and action.help != argparse.SUPPRESS:
                hidden = getattr(action, "hidden_aliases", ())
                yield name, action, [s for s in action.option_strings if s not in hidden]


OPTIONS = list(_options(build_parser()))


def test_the_walk_sees_every_command():
    commands = {name.split()[1] for name, _, _ in OPTIONS if " " in name}
    assert {"fit", "export", "pwm", "compare", "diagnose", "drive", "demo", "bench"} <= commands


def test_one_spelling_per_concept():
    problems = []
    for name, action, shown in OPTIONS:
        for opt in shown:
            if opt in RENAMED:
                problems.append(f"{name}: rename {opt} to {RENAMED[opt]} {HOW.format(old=opt)}")
            elif UNIT_SUFFIX.match(opt):
                new = opt.rsplit("-", 1)[0]
                problems.append(f"{name}: {opt} names its unit; rename it {new} and put the unit "
                                f"in the metavar {HOW.format(old=opt)}")
        pairs = (("-o", "--output"), ("-q", "--quiet"))
        for short, long in pairs:
            if (short in shown) != (long in shown):
                problems.append(f"{name}: {'/'.join(shown)} must be spelled {short}/{long}")
        meta = str(action.metavar or "")
        if "--plot" in shown and not re.search(r"\.(png|svg|pdf)$", meta, re.I):
            problems.append(f"{name}: --plot takes a figure file: metavar like FIG.png, not "
                            f"{meta or 'none'}")
        if "--report" in shown and meta != "DIR":
            problems.append(f"{name}: --report takes a directory: metavar DIR, not {meta}")
        if "--model" in shown and re.search(r"\bwrites?\b", action.help or "", re.I):
            problems.append(f"{name}: --model is only an input; an output model is -o/--output")
        if "--json" in shown and action.nargs != 0:
            problems.append(f"{name}: --json takes no value (it prints the JSON document)")
    assert not problems, "\n".join(problems)


@pytest.mark.parametrize("argv, dest, value", [
    (["drive", "m.json", "--t-max", "90", "--target", "60", "--f-pwm", "2k"], "f_pwm", 2e3),
    (["pwm", "m.json", "--freq", "1k", "--duty", "0.5", "--power", "1", "--tref", "30"],
     "tref", 30.0),
    (["demo", "--out", "x"], "out", "x"),
    (["bench", "rth", "--port", "sim://actuator", "--out", "b", "--window-s", "1e-4",
      "--settle-s", "5"], "window_s", 1e-4),
])
def test_old_spellings_still_parse(argv, dest, value):
    assert getattr(build_parser().parse_args(argv), dest) == value


def test_old_spellings_are_hidden_from_help():
    helps = build_parser()._subparsers._group_actions[0].choices
    for command, old in (("drive", "--f-pwm"), ("pwm", "--tref"), ("demo", "--out")):
        assert not re.search(rf"{old}(?![\w-])", helps[command].format_help())
