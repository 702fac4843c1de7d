"""Fuzzing the command line: hostile file contents, file names and option values for every
command must end in exit 0, or exit 2 with one printable line, within a time limit; never a
traceback, never an internal error, never NaN or Infinity in JSON output.

The commands and their options are found by walking the argument parser, so a new command
is fuzzed without touching this file. ``make test`` runs a short, derandomized run;
``bench/bench_fuzz.py`` runs a long random one (``SPICETHERMAL_FUZZ_EXAMPLES``,
``SPICETHERMAL_FUZZ_SEED``, ``SPICETHERMAL_FUZZ_SLOW=1`` adds ``bench`` on the simulated
bench).
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import os
import shutil
import signal
import tempfile
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, seed, settings
from hypothesis import strategies as st

from spicethermal.cli.main import build_parser, main
from spicethermal.core.ladder import Foster
from spicethermal.io.bundle import Bundle, CalibrationTable, CoolingTable, PwmTable
from spicethermal.model import ThermalModel

EXAMPLES = int(os.environ.get("SPICETHERMAL_FUZZ_EXAMPLES", "60"))
SLOW = os.environ.get("SPICETHERMAL_FUZZ_SLOW") == "1"
LIMIT_S = int(os.environ.get("SPICETHERMAL_FUZZ_LIMIT_S", "180"))
SKIP = {"demo"} if SLOW else {"bench", "demo"}  # demo takes no input file: test_demo.py
VERBOSE = os.environ.get("SPICETHERMAL_FUZZ_VERBOSE") == "1"

#: Numbers a hostile or unlucky user writes, as text.
HOSTILE = ["0", "-1", "-0", "1e306", "1e308", "1e400", "-1e400", "nan", "inf", "-inf",
           "1e-320", "5e-324", "", "x", "0x10", "1,2", "1e", "--", "\x00", "١"]
TYPICAL = ["1", "0.5", "0.1", "1000", "25", "60", "80", "2", "1e-4", "auto", "3"]
#: Characters that break naive code when they appear in a file name.
NAME_CHARS = "ab$^{}%_\\ \t\n\x01\x7f'\"é[*?"


class Hang(BaseException):
    """Raised by the alarm: the command ran past the time limit."""


def _alarm(signum, frame):
    raise Hang("no result within the time limit")


# ------------------------------------------------------------------------ base inputs
@pytest.fixture(scope="module")
def base(tmp_path_factory) -> Path:
    """A valid model, a small valid bundle and a Table-2 CSV to start mutating from."""
    root = tmp_path_factory.mktemp("fuzzbase")
    ladder = Foster.from_tau((6.0, 20.0, 50.0, 70.0), (1e-4, 5e-3, 0.4, 30.0))
    ThermalModel(ladder).save(root / "model.json")
    t = np.geomspace(1e-4, 30.0, 24)
    p_w = 0.1
    tj = 25.0 + p_w * (ladder.rth - ladder.zth(t))
    freqs, duties = np.array([1e3, 1e3, 1e4, 1e4]), np.array([0.2, 0.8, 0.2, 0.8])
    Bundle(device="fuzz", ambient_c=25.0,
           calibration=CalibrationTable([25.0, 50.0, 75.0], [0.60, 0.55, 0.50]),
           cooling=(CoolingTable(np.round(t, 9), p_w, np.round(tj, 5),
                                 tj_steady_c=round(25 + p_w * ladder.rth, 5),
                                 tref_steady_c=25.0),),
           pwm=PwmTable(freqs, duties, 25.0 + p_w * ladder.rth * duties, power_w=p_w,
                        sample_window_s=1e-4)).write(root / "bundle")
    (root / "table2.csv").write_text(
        "freq_hz,duty,tj_exp_c,tj_model_c\n1000,0.2,29.1,29.4\n1000,0.8,41.0,40.2\n"
        "25000,0.2,28.9,29.4\n25000,0.8,40.1,40.2\n")
    return root


def _mutate_csv(text: str, data) -> str:
    lines = text.splitlines()
    kind = data.draw(st.sampled_from(["cell", "cell", "constant", "single", "equal",
                                      "garbage", "none"]), label="csv mutation")
    header = [i for i, line in enumerate(lines) if line and not line.startswith("#")][0]
    rows = list(range(header + 1, len(lines)))
    ncol = len(lines[header].split(","))
    if kind == "cell" and rows:
        r = data.draw(st.sampled_from(rows), label="row")
        c = data.draw(st.integers(0, ncol - 1), label="column")
        cells = lines[r].split(",")
        cells[c] = data.draw(st.sampled_from(HOSTILE + ["1e308", "-273.16", "1e300"]),
                             label="cell")
        lines[r] = ",".join(cells)
    elif kind == "constant" and rows:
        c = data.draw(st.integers(0, ncol - 1), label="column")
        value = lines[rows[0]].split(",")[c]
        for r in rows:
            cells = lines[r].split(",")
            cells[c] = value
            lines[r] = ",".join(cells)
    elif kind == "single" and rows:
        lines = lines[:rows[0] + 1]
    elif kind == "equal" and ncol >= 4:  # measured column equal to the simulated one
        for r in rows:
            cells = lines[r].split(",")
            cells[2] = cells[3]
            lines[r] = ",".join(cells)
    elif kind == "garbage":
        return data.draw(st.text(max_size=200), label="garbage csv")
    return "\n".join(lines) + "\n"


def _mutate_json(doc, data):
    kind = data.draw(st.sampled_from(["key", "key", "provenance", "deep", "text", "none"]),
                     label="json mutation")
    if kind == "text":
        return data.draw(st.sampled_from(["", "[]", "null", "{", "[" * 5000, '{"a": 1e400}',
                                          "\ufeff{}"]), label="json text")
    if kind == "deep":
        return "[" * 100000 + "]" * 100000
    doc = json.loads(json.dumps(doc))
    value = data.draw(st.recursive(
        st.none() | st.booleans() | st.integers() | st.floats(allow_nan=False,
                                                               allow_infinity=False)
        | st.text(max_size=8) | st.sampled_from([1e306, -1e306, 1e-320, 0.0, -1.0]),
        lambda kids: st.lists(kids, max_size=3) | st.dictionaries(st.text(max_size=4), kids,
                                                                  max_size=3),
        max_leaves=6), label="json value")
    if kind == "provenance":
        doc["provenance"] = value
    elif kind == "key":
        paths = []

        def walk(node, path):
            if isinstance(node, dict):
                for k, v in node.items():
                    paths.append(path + (k,))
                    walk(v, path + (k,))
            elif isinstance(node, list):
                for i, v in enumerate(node):
                    paths.append(path + (i,))
                    walk(v, path + (i,))

        walk(doc, ())
        if paths:
            path = data.draw(st.sampled_from(paths), label="json key")
            node = doc
            for k in path[:-1]:
                node = node[k]
            node[path[-1]] = value
    return json.dumps(doc)


def _hostile_name(data, suffix: str) -> str:
    stem = data.draw(st.text(alphabet=NAME_CHARS, min_size=1, max_size=6), label="name")
    return stem.replace("/", "_") + suffix


def make_inputs(base: Path, work: Path, data) -> dict[str, str]:
    """Copies of the base inputs in ``work``, each perhaps mutated; returns role -> path."""
    shutil.copytree(base / "bundle", work / "bundle")
    files = {"model": work / "model.json", "table": work / "table2.csv",
             "bundle": work / "bundle"}
    model = json.loads((base / "model.json").read_text())
    if data.draw(st.booleans(), label="mutate model"):
        (files["model"]).write_text(_mutate_json(model, data))
    else:
        (files["model"]).write_text(json.dumps(model))
    table = (base / "table2.csv").read_text()
    files["table"].write_text(_mutate_csv(table, data) if data.draw(st.booleans()) else table)
    target = data.draw(st.sampled_from(["none", "bundle.json", "cooling_1.csv", "pwm.csv",
                                        "calibration.csv", "link", "fifo"]),
                       label="bundle mutation")
    victim = work / "bundle" / "cooling_1.csv"
    if target == "bundle.json":
        doc = json.loads((work / "bundle" / "bundle.json").read_text())
        (work / "bundle" / "bundle.json").write_text(_mutate_json(doc, data))
    elif target.endswith(".csv"):
        p = work / "bundle" / target
        p.write_text(_mutate_csv(p.read_text(), data))
    elif target == "link":
        victim.unlink()
        victim.symlink_to(data.draw(st.sampled_from(["/etc/passwd", "/dev/zero", "../x"])))
    elif target == "fifo":
        victim.unlink()
        os.mkfifo(victim)
    if data.draw(st.booleans(), label="hostile names"):
        for role in ("model", "table"):
            new = work / _hostile_name(data, files[role].suffix)
            if not new.exists():
                files[role].rename(new)
                files[role] = new
    return {k: str(v) for k, v in files.items()}


# ------------------------------------------------------------------------ arguments
def commands() -> dict[str, argparse.ArgumentParser]:
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return {name: p for name, p in sub.choices.items() if name not in SKIP}


def _value(action: argparse.Action, inputs: dict[str, str], work: Path, data) -> list[str]:
    name = (action.metavar or action.dest or "").lower() + " " + action.dest.lower()
    if action.choices is not None and not isinstance(action, argparse._SubParsersAction):
        pick = data.draw(st.sampled_from([*map(str, action.choices), "bogus"]), label=name)
        return [pick]
    if any(k in name for k in ("model", "source", "bundle", "table", "datasheet",
                               "calibration")):
        usual = ["model"] * 6 if "model" in name else ["bundle"] * 4 + ["table"] * 2
        role = data.draw(st.sampled_from(usual + ["model", "bundle", "table", "missing"]),
                         label=name)
        return [inputs.get(role, str(work / "missing"))]
    if any(k in name for k in ("fig", ".png", ".lib", ".cir", ".json", "dir", "out", "file",
                               "plot", "report", "spice")):
        suffix = "" if "dir" in name else Path(name.split()[0]).suffix or ".out"
        return [str(work / _hostile_name(data, suffix))]
    if name.startswith("url"):
        return ["sim://actuator?seed=1"]
    if data.draw(st.integers(0, 3), label="hostile value") == 0:
        pool = HOSTILE + [f"{a},{b}" for a in ("1", "0.5") for b in ("2", "x", "1e400")]
    else:
        pool = TYPICAL
    return [data.draw(st.sampled_from(pool), label=name)]


def make_argv(cmd: str, parser: argparse.ArgumentParser, inputs: dict[str, str], work: Path,
              data) -> list[str]:
    argv = [cmd]
    subs = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    if subs:  # e.g. bench ACTION
        action = data.draw(st.sampled_from(sorted(subs[0].choices)), label="action")
        argv.append(action)
        parser = subs[0].choices[action]
    positionals, optionals = [], []
    for action in parser._actions:
        if isinstance(action, argparse._HelpAction | argparse._SubParsersAction):
            continue
        if not action.option_strings:
            positionals += _value(action, inputs, work, data)
        elif action.required or data.draw(st.integers(0, 3), label="use option") == 0:
            flag = action.option_strings[-1]
            if action.nargs == 0:
                optionals.append(flag)
            else:
                optionals += [flag, *_value(action, inputs, work, data)]
    return argv + optionals + positionals


# ------------------------------------------------------------------------ the test
def run_cli(argv: list[str]) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    old = signal.signal(signal.SIGALRM, _alarm)
    # the simulated bench runs hours of bench time: slow, not hung
    limit = 5 * LIMIT_S if argv[0] == "bench" else LIMIT_S
    signal.alarm(limit)
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err), \
                warnings.catch_warnings():
            warnings.simplefilter("default")
            try:
                code = main(argv)
            except SystemExit as exc:  # argparse
                code = exc.code if isinstance(exc.code, int) else 2
    except Hang:
        raise AssertionError(f"hang: no result within {limit} s\nargv: {argv!r}") from None
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)
    return code, out.getvalue(), err.getvalue()


def check(argv: list[str], code: int, out: str, err: str) -> None:
    where = f"\nargv: {argv!r}\nstderr: {err[-2000:]}"
    assert "Traceback" not in err, where
    assert code in (0, 2), f"exit {code}{where}"
    if code == 2:
        lines = [line for line in err.splitlines() if line.strip()]
        assert len(lines) >= 1 and "error:" in lines[-1], where
        errors = [line for line in lines if "error:" in line]
        assert len(errors) == 1 and errors[0] == lines[-1], f"not one line{where}"
        assert lines[-1].isprintable(), where
    elif "--json" in argv and out.strip():
        json.loads(out, parse_constant=lambda c: pytest.fail(f"{c} in JSON output{where}"))


@settings(max_examples=EXAMPLES, deadline=None, derandomize="SPICETHERMAL_FUZZ_SEED" not in
          os.environ, database=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                                 HealthCheck.function_scoped_fixture])
@seed(int(os.environ.get("SPICETHERMAL_FUZZ_SEED", "0")))
@given(data=st.data())
def test_no_input_ends_in_a_traceback(base: Path, data) -> None:
    cmds = commands()
    cmd = data.draw(st.sampled_from(sorted(cmds)), label="command")
    work = Path(tempfile.mkdtemp(prefix="fuzz"))
    try:
        inputs = make_inputs(base, work, data)
        argv = make_argv(cmd, cmds[cmd], inputs, work, data)
        code, out, err = run_cli(argv)
        if VERBOSE:
            print(f"FUZZ {code} {cmd} {err.strip().splitlines()[-1:]!r} {argv!r}")
        check(argv, code, out, err)
    finally:
        shutil.rmtree(work, ignore_errors=True)


def test_the_fuzzer_reaches_every_command() -> None:
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    assert set(commands()) == set(sub.choices) - SKIP
    assert {"fit", "export", "pwm", "compare", "diagnose"} <= set(commands())
