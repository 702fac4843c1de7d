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
7. A figure is ``--plot`` (or ``--<what>-plot``); ``-o/--output`` is the data the command writes
   (a model, a table, a .lib, a directory), never a figure.
8. ``--power`` is a power in W; a power profile (a CSV) is ``--profile``.
9. A list (metavar ``X,...``) has a singular name: ``--freq HZ,...``, ``--duty D,...``; a
   frequency is ``--freq``, a list of duty cycles ``--duty``.
10. Every option and argument has help text, and every option with a default states it.
11. Every old spelling prints a one-line deprecation note on stderr and still parses.

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
           "--report-dir": "--report", "--freqs": "--freq", "--duties": "--duty",
           "--p-max": "--power", "--powers": "--cooling-power", "--setpoints": "--setpoint"}
FIGURE = re.compile(r"\.(png|svg|pdf)$", re.I)
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
        if FIGURE.search(meta) and not any(o == "--plot" or o.endswith("-plot") for o in shown):
            problems.append(f"{name}: {'/'.join(shown)} writes a figure: spell it --plot")
        if "-o" in shown and FIGURE.search(meta):
            problems.append(f"{name}: -o/--output is the data output, not a figure ({meta})")
        if "--power" in shown and meta not in ("W", "W,..."):
            problems.append(f"{name}: --power is a power in W (metavar W), not {meta}; a power "
                            f"profile is --profile")
        if meta.endswith(",..") and not meta.endswith(",..."):
            problems.append(f"{name}: a list's metavar ends with ',...', not {meta}")
        if meta.endswith(",...") and any(o.startswith("--") and o.endswith("s") for o in shown):
            problems.append(f"{name}: {'/'.join(shown)} takes a list: a singular name")
        if meta.startswith("HZ") and "--freq" not in shown:
            problems.append(f"{name}: {'/'.join(shown)} takes frequencies: spell it --freq")
        if meta == "D,..." and "--duty" not in shown:
            problems.append(f"{name}: {'/'.join(shown)} takes duty cycles: spell it --duty")
    assert not problems, "\n".join(problems)


def test_every_option_has_help_and_states_its_default():
    problems = []
    for name, command in commands(build_parser()):
        for action in command._actions:
            if isinstance(action, argparse._HelpAction | argparse._VersionAction
                          | argparse._SubParsersAction) \
                    or action.help == argparse.SUPPRESS:
                continue
            what = "/".join(action.option_strings) or action.metavar or action.dest
            if not (action.help or "").strip():
                problems.append(f"{name}: {what} has no help text")
            elif action.option_strings and not action.required \
                    and action.default not in (None, False) and "default" not in action.help:
                problems.append(f"{name}: {what}'s help does not state its default "
                                f"({action.default!r})")
    assert not problems, "\n".join(problems)


def test_every_old_spelling_notes_its_deprecation():
    problems = []
    for name, action, _ in OPTIONS:
        for old in getattr(action, "hidden_aliases", ()):
            if not type(action).__name__.startswith("Deprecating"):
                problems.append(f"{name}: {old} parses silently: add it with add_option(..., "
                                f"old=({old!r},))")
    assert not problems, "\n".join(problems)


@pytest.mark.parametrize("argv, dest, value", [
    (["drive", "m.json", "--t-max", "90", "--target", "60", "--f-pwm", "2k"], "f_pwm", 2e3),
    (["drive", "m.json", "--t-max", "90", "--target", "60", "--p-max", "2"], "p_max", 2.0),
    (["predict", "m.json", "--power", "p.csv", "-o", "tj.csv"], "profile", "p.csv"),
    (["structure", "a.csv", "-o", "sf.png"], "plot", "sf.png"),
    (["bench", "pwm", "--port", "sim://actuator", "-o", "b", "--freqs", "1k,25k"],
     "pwm_freqs_hz", (1e3, 25e3)),
    (["bench", "pwm", "--port", "sim://actuator", "-o", "b", "--duties", "0.2,0.5"],
     "pwm_duties", (0.2, 0.5)),
    (["bench", "cooling", "--port", "sim://actuator", "-o", "b", "--powers", "0.094"],
     "cooling_powers_w", (0.094,)),
    (["bench", "calibrate", "--port", "sim://actuator", "-o", "b", "--setpoints", "25,45"],
     "calibration_c", (25.0, 45.0)),
    (["pwm", "m.json", "--freq", "1k", "--duty", "0.5", "--power", "1", "--tref", "30"],
     "tref", 30.0),
    (["demo", "--out", "x"], "out", "x"),
    (["bench", "rth", "--port", "sim://actuator", "--out", "b", "--window-s", "1e-4",
      "--settle-s", "5"], "window_s", 1e-4),
])
def test_old_spellings_still_parse(argv, dest, value, capsys):
    assert getattr(build_parser().parse_args(argv), dest) == value
    notes = capsys.readouterr().err.strip().splitlines()  # one line per old spelling
    assert notes and all(" is deprecated, use " in n and "next release" in n for n in notes)


def test_a_figure_given_to_o_is_the_old_spelling_of_plot(tmp_path, actuator, capsys):
    from spicethermal.cli.main import main
    from spicethermal.model import ThermalModel

    model = str(ThermalModel(actuator).save(tmp_path / "m.json"))
    assert main(["curves", model, "-o", str(tmp_path / "f.png")]) == 0
    out, err = capsys.readouterr()
    assert "-o " in err and "is deprecated, use --plot" in err
    assert (tmp_path / "f.png").is_file() and (tmp_path / "f.csv").is_file()
    assert main(["curves", model, "--plot", str(tmp_path / "g.png"), "-o",
                 str(tmp_path / "g.csv"), "--duty", "0.1,0.5", "--duty", "0.9"]) == 0
    out, err = capsys.readouterr()
    assert not err and "wrote figure" in out and "wrote table" in out and "0.1, 0.5, 0.9" in out


def test_old_spellings_are_hidden_from_help():
    helps = build_parser()._subparsers._group_actions[0].choices
    for command, old in (("drive", "--f-pwm"), ("pwm", "--tref"), ("demo", "--out")):
        assert not re.search(rf"{old}(?![\w-])", helps[command].format_help())
