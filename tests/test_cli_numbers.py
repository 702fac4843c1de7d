"""One number parser for every numeric option: SPICE and SI prefixes, optional units, clear
errors (the rule: the docstring of :mod:`spicethermal.cli.commands._types`)."""

from __future__ import annotations

import argparse

import pytest

from spicethermal.cli.commands._types import (
    count,
    frequency,
    listed,
    number,
    parse_si,
    power,
    quantity,
)
from spicethermal.cli.main import main


@pytest.mark.parametrize("text, value", [
    ("1k", 1e3), ("25kHz", 25e3), ("25 kHz", 25e3), ("100u", 1e-4), ("100us", 1e-4),
    ("100µs", 1e-4), ("2.5m", 2.5e-3), ("2.5ms", 2.5e-3), ("1e-4", 1e-4), ("94mW", 0.094),
    ("20%", 0.2), ("-40", -40.0), ("1.5G", 1.5e9), ("10n", 1e-8), ("5K", 5e3), ("5k", 5e3),
    (".5", 0.5), ("7", 7.0), ("2p", 2e-12), ("3f", 3e-15),
    # SPICE spellings, any case: kilo K, mega meg, units in any case
    ("25KHz", 25e3), ("25khz", 25e3), ("25KHZ", 25e3), ("94mw", 0.094), ("94mW", 0.094),
    ("25meg", 25e6), ("25MEG", 25e6), ("25Meg", 25e6), ("1megHz", 1e6), ("100US", 1e-4),
    ("2.5mS", 2.5e-3), ("1g", 1e9), ("10N", 1e-8), ("100U", 1e-4), ("-94m", -0.094),
    ("-2.5e3", -2500.0), ("3 s", 3.0), ("3S", 3.0), ("1w", 1.0),
])
def test_si_forms(text, value):
    assert parse_si(text) == value  # exact: decimal scaling, no 9.999...e-05


@pytest.mark.parametrize("text", ["", "k", "1kk", "1 kHzz", "1x", "1e", "--1", "1%%", "1 m s"])
def test_bad_forms_show_the_accepted_ones(text):
    with pytest.raises(argparse.ArgumentTypeError, match=r"e\.g\. 1k, 25kHz, 100u, 100us, 2\.5m"):
        parse_si(text)


@pytest.mark.parametrize("text, m, meg", [
    ("94M", "94m", "94meg"), ("25MHz", "25mHz", "25megHz"), ("94MW", "94mW", "94megW"),
    ("1.5 M", "1.5m", "1.5meg"),
])
def test_a_capital_m_is_refused_naming_both_readings(text, m, meg):
    with pytest.raises(argparse.ArgumentTypeError) as err:
        parse_si(text)
    message = str(err.value)
    assert "milli in SPICE" in message and "mega in SI" in message
    assert f"write {m} (milli) or {meg} (mega)" in message


def test_k_is_kilo_except_on_an_option_in_kelvin():
    assert parse_si("5K") == parse_si("5k") == frequency("5K") == 5e3
    kelvin = quantity("K")
    assert kelvin("0.5K") == kelvin("0.5") == 0.5
    assert kelvin("2kK") == 2e3  # kilokelvin: the prefix before the unit
    with pytest.raises(argparse.ArgumentTypeError, match="the unit is K"):
        kelvin("1s")


def test_units_of_a_quantity_are_checked():
    assert frequency("25k") == frequency("25kHz") == frequency("25KHz") == 25e3
    assert power("94mw") == power("94 mW") == 0.094
    with pytest.raises(argparse.ArgumentTypeError, match="the unit is W"):
        power("94ms")
    for bad in ("1s", "20%", "1W"):
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
        main(["pwm", model, "--freq", "1s", "--duty", "0.2", "--power", "1"])
    assert err.value.code == 2
    line = capsys.readouterr().err.strip()
    assert "\n" not in line and "--freq" in line and "the unit is Hz" in line


def _model(tmp_path, actuator) -> str:
    from spicethermal.model import ThermalModel

    return str(ThermalModel(actuator).save(tmp_path / "m.json"))


def test_spice_spellings_on_the_command_line(tmp_path, actuator, capsys):
    model = _model(tmp_path, actuator)
    assert main(["pwm", model, "--freq", "25KHz", "--duty", "20%", "--power", "94mw",
                 "--window", "100US", "--json"]) == 0
    a = capsys.readouterr().out
    assert main(["pwm", model, "--freq", "25e3", "--duty", "0.2", "--power", "0.094",
                 "--window", "1e-4", "--json"]) == 0
    assert capsys.readouterr().out == a


def test_negative_values_read_as_values(tmp_path, actuator, capsys):
    model = _model(tmp_path, actuator)
    # a negative power is refused by its range, not mistaken for an option
    with pytest.raises(SystemExit) as err:
        main(["pwm", model, "--freq", "1k", "--duty", "0.5", "--power", "-94m"])
    assert err.value.code == 2
    line = capsys.readouterr().err
    assert "expected one argument" not in line and "'-94m' must be >= 0" in line
    # a negative ambient is a value (with a prefix too)
    assert main(["pwm", model, "--freq", "1k", "--duty", "0.5", "--power", "94m",
                 "--ambient", "-40", "--json"]) == 0
    assert main(["pwm", model, "--freq", "1k", "--duty", "0.5", "--power", "94m",
                 "--ambient", "-0.04k", "--json"]) == 0
    capsys.readouterr()


def test_a_capital_m_on_the_command_line_is_one_clear_line(tmp_path, actuator, capsys):
    model = _model(tmp_path, actuator)
    with pytest.raises(SystemExit) as err:
        main(["pwm", model, "--freq", "1k", "--duty", "0.5", "--power", "94M"])
    assert err.value.code == 2
    line = capsys.readouterr().err.strip()
    assert "\n" not in line and "--power" in line and "write 94m (milli) or 94meg (mega)" in line


def test_an_absurd_rise_is_warned_about(tmp_path, actuator, capsys):
    model = _model(tmp_path, actuator)
    assert main(["pwm", model, "--freq", "1k", "--duty", "0.5", "--power", "94meg"]) == 0
    err = capsys.readouterr().err
    assert "warning: a peak rise of" in err and "--power 9.4e+07 W" in err
    assert main(["pwm", model, "--freq", "1k", "--duty", "0.5", "--power", "94m"]) == 0
    assert "warning" not in capsys.readouterr().err


def test_predict_warns_about_an_absurd_rise(tmp_path, actuator, capsys):
    model = _model(tmp_path, actuator)
    profile = tmp_path / "p.csv"
    profile.write_text("t_s,power_w\n0,1e6\n1,1e6\n")
    assert main(["predict", model, "--profile", str(profile), "-o", str(tmp_path / "tj.csv"),
                 "--engine", "analytic"]) == 0
    assert "warning: a peak rise of" in capsys.readouterr().err
