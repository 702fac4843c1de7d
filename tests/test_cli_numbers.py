"""One number parser for every numeric option: SI prefixes, optional units, clear errors."""

from __future__ import annotations

import argparse

import pytest

from spicethermal.cli.commands._types import count, frequency, listed, number, parse_si
from spicethermal.cli.main import main


@pytest.mark.parametrize("text, value", [
    ("1k", 1e3), ("25kHz", 25e3), ("25 kHz", 25e3), ("100u", 1e-4), ("100us", 1e-4),
    ("100µs", 1e-4), ("2.5m", 2.5e-3), ("2.5ms", 2.5e-3), ("1e-4", 1e-4), ("94mW", 0.094),
    ("20%", 0.2), ("-40", -40.0), ("3M", 3e6), ("1.5G", 1.5e9), ("10n", 1e-8), ("5K", 5.0),
    (".5", 0.5), ("7", 7.0), ("2p", 2e-12), ("3f", 3e-15),
])
def test_si_forms(text, value):
    assert parse_si(text) == value  # exact: decimal scaling, no 9.999...e-05


@pytest.mark.parametrize("text", ["", "k", "1kk", "1 kHzz", "1x", "1e", "--1", "1%%", "1 m s"])
def test_bad_forms_show_the_accepted_ones(text):
    with pytest.raises(argparse.ArgumentTypeError, match=r"e\.g\. 1k, 25kHz, 100u, 100us, 2\.5m"):
        parse_si(text)


def test_units_of_a_quantity_are_checked():
    assert frequency("25k") == frequency("25kHz") == 25e3
    for bad in ("1K", "1s", "20%"):
        with pytest.raises(argparse.ArgumentTypeError, match="the unit is Hz"):
            frequency(bad)
    with pytest.raises(argparse.ArgumentTypeError, match="must be > 0"):
        frequency("0")
    with pytest.raises(argparse.ArgumentTypeError, match="not a finite number"):
        number("nan")


def test_counts_and_lists():
    assert count("10k") == 10_000 and count("3") == 3
    with pytest.raises(argparse.ArgumentTypeError, match="whole number"):
        count("2.5")
    assert listed(frequency)("500, 1k,25kHz") == (500.0, 1e3, 25e3)


def test_every_command_reads_si_numbers(tmp_path, actuator, capsys):
    from spicethermal.model import ThermalModel

    model = str(ThermalModel(actuator).save(tmp_path / "m.json"))
    assert main(["pwm", model, "--freq", "25kHz", "--duty", "20%", "--power", "94m",
                 "--window", "100us", "--json"]) == 0
    a = capsys.readouterr().out
    assert main(["pwm", model, "--freq", "25e3", "--duty", "0.2", "--power", "0.094",
                 "--window", "1e-4", "--json"]) == 0
    assert capsys.readouterr().out == a
    with pytest.raises(SystemExit) as err:
        main(["pwm", model, "--freq", "1K", "--duty", "0.2", "--power", "1"])
    assert err.value.code == 2
    line = capsys.readouterr().err.strip()
    assert "\n" not in line and "--freq" in line and "the unit is Hz" in line
