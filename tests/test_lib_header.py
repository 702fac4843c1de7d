"""The usage deck in every exported .lib header says what it does, and does it."""

from __future__ import annotations

import re
import shutil

import numpy as np
import pytest
from conftest import NETLISTS

from spicethermal.spice.lib import NgspiceBatch
from spicethermal.spice.netlists import GOLDEN

SI = {"": 1.0, "m": 1e-3, "u": 1e-6, "n": 1e-9, "k": 1e3}
#: The thermal .lib goldens (the electrothermal parts, whose usage drives a current, have
#: their own checks in tests/test_electrothermal.py).
LIBS = sorted(name for name in GOLDEN if name.endswith(".lib") and "heater" not in name)


def _si(text: str) -> float:
    number, prefix = re.fullmatch(r"([0-9.eE+-]+?)([munk]?)", text).groups()
    return float(number) * SI[prefix]


def _usage(text: str) -> tuple[dict[str, float], list[str]]:
    """The header's claims and its deck (the ``*   `` lines after ``* Usage:``)."""
    head = re.search(r"\* Usage: a test pulse train of ([0-9.]+) W at ([0-9.]+) kHz and "
                     r"([0-9.]+) % duty, its first (\d+) periods from ambient:", text)
    assert head, "the header must state power, frequency, duty and span of its test pulse"
    claims = {"power_w": float(head[1]), "freq_hz": float(head[2]) * 1e3,
              "duty": float(head[3]) / 100, "periods": int(head[4])}
    deck = [line[4:].split(";")[0].strip() for line in text[head.end():].splitlines()
            if line.startswith("*   ") and not line.startswith("*   ;")]
    return claims, deck


@pytest.mark.parametrize("filename", LIBS)
def test_header_pulse_matches_its_claims(filename):
    claims, deck = _usage((NETLISTS / filename).read_text())
    pulse = next(line for line in deck if "PULSE(" in line)
    v1, v2, td, tr, tf, pw, per = map(_si, re.search(r"PULSE\(([^)]*)\)", pulse)[1].split())
    assert (v1, td) == (0.0, 0.0)
    assert v2 == pytest.approx(claims["power_w"])
    assert 1 / per == pytest.approx(claims["freq_hz"])
    assert (pw + (tr + tf) / 2) / per == pytest.approx(claims["duty"], abs=0.01)
    tran = next(line for line in deck if line.startswith(".tran"))
    assert _si(tran.split()[2]) == pytest.approx(claims["periods"] * per)
    comment = re.search(r"PULSE\([^)]*\)\s*;(.*)", (NETLISTS / filename).read_text())[1]
    assert f"period {pulse.split()[-1].rstrip(')')}" in comment  # the comment reads the deck


@pytest.mark.ngspice
@pytest.mark.skipif(shutil.which("ngspice") is None, reason="no ngspice binary")
@pytest.mark.parametrize("filename", [n for n in LIBS if "ngspice" in n])
def test_header_deck_runs_and_gives_the_pulse_train_response(filename, tmp_path, actuator):
    """Run the header's deck as written; V(TJ) at its end is the ladder's response to the train."""
    text = (NETLISTS / filename).read_text()
    claims, deck = _usage(text)
    (tmp_path / filename).write_text(text)
    deck = [f".include {tmp_path / filename}" if d.startswith(".include") else d for d in deck]
    wave = NgspiceBatch().run("* header deck\n" + "\n".join(deck) + "\n.end\n", ["V(TJ)"])
    t_end = claims["periods"] / claims["freq_hz"]
    assert wave.t_s[-1] == pytest.approx(t_end)
    period, on = 1 / claims["freq_hz"], claims["duty"] / claims["freq_hz"]
    starts = np.arange(claims["periods"]) * period
    zth = actuator.zth  # the goldens' ladder (tests/conftest.py)
    rise = claims["power_w"] * np.sum(zth(t_end - starts) - zth(t_end - starts - on))
    # the reference the deck drives: V(TJ) reads its level plus the rise
    base = next(float(d.split()[-1]) for d in deck if d.upper().startswith("VREF "))
    tj = float(wave["V(TJ)"][-1])
    if "effects" not in filename:  # linear ladder: the closed form to a few mK
        assert tj - base == pytest.approx(rise, abs=5e-3)
    else:  # device effects change it, but not beyond 10 %
        assert tj - base == pytest.approx(rise, rel=0.1)
