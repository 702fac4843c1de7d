"""predict: Tj under a measured power profile; closed forms, ngspice, the command."""

from __future__ import annotations

import numpy as np
import pytest

from spicethermal.cli.main import main
from spicethermal.core.errors import DataFormatError
from spicethermal.core.ladder import Foster
from spicethermal.effects import Effect
from spicethermal.io.bundle import format_columns, read_columns
from spicethermal.model import Schedule, ThermalModel
from spicethermal.predict import PowerProfile, predict, pwl_response

LADDER = Foster.from_tau([0.5, 2.0, 4.0], [1e-4, 1e-2, 1.0])


def test_ramp_matches_the_closed_form_for_foster_and_cauer() -> None:
    """p(t) = a t into stages (R, τ): rise = Σ R a (t − τ (1 − e^(−t/τ))), also from 1e-9 τ."""
    a = 3.0
    profile = PowerProfile([0.0, 10.0], [0.0, 10.0 * a])
    t = np.concatenate([[0.0, 1e-13, 1e-9], np.geomspace(1e-6, 10.0, 40)])
    exact = sum(r * a * (t - tau * -np.expm1(-t / tau))
                for r, tau in zip(LADDER.r, LADDER.tau, strict=True))
    for ladder in (LADDER, LADDER.to_cauer()):
        rise = pwl_response(ThermalModel(ladder), profile, t)
        assert np.allclose(rise, exact, rtol=1e-9, atol=1e-15)


def test_rectangular_pulse_matches_the_step_model() -> None:
    """A pulse made of PWL corners 1 ns wide agrees with the piecewise-constant simulation of
    ThermalModel (independent code), to the energy of the edges."""
    p, on, off = 2.0, 1e-3, 5e-3
    profile = PowerProfile([0.0, 1e-9, on, on + 1e-9], [0.0, p, p, 0.0])
    t = np.linspace(0.0, off, 101)
    model = ThermalModel(LADDER)
    ours = predict(model, profile, t, tref_c=25.0)
    theirs = model.simulate(t, Schedule((0.0, on), (p, 0.0)), tref_c=25.0).tj_k + 25.0
    assert np.max(np.abs(ours.tj_c - theirs)) < 1e-6 * p * LADDER.rth
    assert ours.engine == "analytic" and ours.peak[0] == pytest.approx(on, rel=1e-6)


def test_ngspice_agrees_with_the_analytic_engine() -> None:
    t = np.linspace(0.0, 0.05, 51)
    profile = PowerProfile([0.0, 0.01, 0.02, 0.03], [0.0, 1.5, 0.5, 0.5])
    model = ThermalModel(LADDER)
    exact = predict(model, profile, t, engine="analytic")
    spice = predict(model, profile, t, engine="ngspice")
    assert spice.engine == "ngspice"
    assert np.max(np.abs(spice.tj_c - exact.tj_c)) < 2e-3 * 1.5 * LADDER.rth


def test_device_effects_go_to_ngspice_not_the_analytic_engine() -> None:
    """Rth falling with temperature: the hot end of the profile runs cooler than linear."""
    tc = ThermalModel(LADDER, (Effect.create("temperature-coefficient", alpha_per_k=-3e-3),))
    profile = PowerProfile([0.0, 1e-6, 2.0], [0.0, 5.0, 5.0])
    with pytest.raises(DataFormatError, match="--engine ngspice"):
        predict(tc, profile, engine="analytic")
    t = np.linspace(0.0, 2.0, 21)
    hot = predict(tc, profile, t, tref_c=25.0)
    linear = predict(ThermalModel(LADDER), profile, t, tref_c=25.0)
    assert hot.engine == "ngspice"
    assert hot.tj_c[-1] < linear.tj_c[-1] - 1.0


@pytest.mark.parametrize(("text", "words"), [
    ("t_s,power_w\n0.1,1\n1,1\n", "row 2, column t_s: the profile must start at t = 0"),
    ("t_s,power_w\n0,1\n1,-1\n", "row 3, column power_w: power must not be negative"),
    ("t_s,power_w\n0,1\n0,1\n", "row 3, column t_s: times must increase"),
    ("t_s,watts\n0,1\n", "missing column power_w"),
])
def test_bad_profile_names_the_row(tmp_path, capsys, text, words) -> None:
    model = tmp_path / "m.json"
    ThermalModel(LADDER).save(model)
    prof = tmp_path / "p.csv"
    prof.write_text(text)
    out = tmp_path / "tj.csv"
    assert main(["predict", str(model), "--profile", str(prof), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert words in err and err.count("\n") == 1 and not out.exists()


def test_command_writes_tj_csv_and_figure(tmp_path, capsys) -> None:
    model = tmp_path / "m.json"
    ThermalModel(LADDER).save(model)
    prof = tmp_path / "p.csv"
    prof.write_text(format_columns({"t_s": [0.0, 1e-6, 0.1, 0.100001],
                                    "power_w": [0.0, 1.0, 1.0, 0.0]}))
    out, fig = tmp_path / "tj.csv", tmp_path / "tj.png"
    assert main(["predict", str(model), "--profile", str(prof), "-o", str(out), "--plot",
                 str(fig), "--ambient", "40", "--until", "1", "--points", "101"]) == 0
    assert "peak" in capsys.readouterr().out
    cols = read_columns(out, ["t_s", "power_w", "tj_c"])
    assert cols["t_s"][-1] == 1.0 and cols["tj_c"][0] == 40.0
    k = int(np.argmax(cols["tj_c"]))
    assert cols["t_s"][k] == pytest.approx(0.1, rel=1e-4)
    assert cols["tj_c"][k] == pytest.approx(40.0 + LADDER.zth(0.1 - 1e-6 / 2), rel=1e-4)
    assert fig.stat().st_size > 10000
