"""One Engine interface: the closed form, ngspice -b and ngspice in process agree on the same
model and schedule; the analytic engine refuses a nonlinear model in one line."""

from __future__ import annotations

import numpy as np
import pytest

from spicethermal.core.errors import DataFormatError
from spicethermal.core.ladder import Foster
from spicethermal.effects import Effect
from spicethermal.engines.interface import NAMES, Analytic, Spice, engine, pwl_corners
from spicethermal.model import Schedule, ThermalModel

LADDER = Foster.from_tau((6.0, 20.0, 50.0, 70.0), (1e-4, 5e-3, 0.4, 3.0))
POWER = 0.2
#: a pulse of 1 s, then cooling: step and (finite) impulse response in one run
SCHEDULE = Schedule((0.0, 1.0), (POWER, 0.0))
T = np.concatenate([np.geomspace(1e-4, 1.0, 30), np.geomspace(1.001, 4.0, 20)])


def test_names_and_the_auto_choice():
    linear = ThermalModel(LADDER)
    tc = linear.with_effects([Effect.create("temperature-coefficient", alpha_per_k=-3e-3)])
    assert NAMES == ("auto", "analytic", "ngspice", "pyspice")
    assert engine("auto", linear).name == "analytic" and engine("auto", tc).name == "ngspice"
    assert [engine(n).name for n in NAMES[2:]] == ["ngspice", "pyspice"]
    assert isinstance(engine("analytic", linear), Analytic)
    assert isinstance(engine("ngspice", tc), Spice)
    with pytest.raises(DataFormatError, match="^--engine analytic: the model has device "
                                              "effects \\(temperature-coefficient\\)[^\n]*$"):
        engine("analytic", tc)
    with pytest.raises(DataFormatError, match="temperature-coefficient"):
        Analytic().simulate(tc, SCHEDULE, T)
    with pytest.raises(DataFormatError, match="expected one of auto, analytic"):
        engine("spectre")


def test_pwl_corners_keep_the_energy_of_every_piece():
    s = Schedule((0.0, 0.3, 0.5, 2.0), (1.0, 3.0, 0.0, 2.0))
    pts = np.array(pwl_corners(s, 4.0))
    assert np.all(np.diff(pts[:, 0]) > 0) and pts[0].tolist() == [0.0, 0.0]
    energy = np.trapezoid(pts[:, 1], pts[:, 0]) + pts[-1, 1] * (4.0 - pts[-1, 0])
    exact = 1.0 * 0.3 + 3.0 * 0.2 + 2.0 * 2.0
    assert energy == pytest.approx(exact - 0.5 * 1e-7 * 4.0 * 1.0, rel=1e-12)  # the first ramp


def test_analytic_step_and_cooling_are_the_closed_forms():
    rise = Analytic().simulate(ThermalModel(LADDER), SCHEDULE, T)
    on = T <= 1.0
    np.testing.assert_allclose(rise[on], POWER * LADDER.zth(T[on]), rtol=1e-12, atol=1e-12)
    off = ~on  # superposition: the step minus a step delayed by 1 s
    np.testing.assert_allclose(rise[off], POWER * (LADDER.zth(T[off]) - LADDER.zth(T[off] - 1.0)),
                               rtol=1e-10, atol=1e-12)


@pytest.mark.ngspice
@pytest.mark.parametrize("name", ["ngspice", "pyspice"])
def test_every_engine_agrees_on_the_same_model_and_schedule(name):
    model = ThermalModel(LADDER)
    exact = engine("analytic", model)
    spice = engine(name, model)
    assert spice.name == name
    tol = 1e-3 * POWER * LADDER.rth  # ngspice's ladder responses: within 3e-4 of Rth
    np.testing.assert_allclose(spice.simulate(model, SCHEDULE, T),
                               exact.simulate(model, SCHEDULE, T), rtol=0, atol=tol)
    a = exact.pwm_steady(model, POWER, 1e3, 0.3, 1e-4)
    b = spice.pwm_steady(model, POWER, 1e3, 0.3, 1e-4)
    for key in ("peak_k", "mean_k", "valley_k", "reading_k"):
        assert getattr(b, key) == pytest.approx(getattr(a, key), abs=2e-3), key


@pytest.mark.ngspice
def test_spice_engines_agree_with_the_nonlinear_integration():
    tc = ThermalModel(LADDER, (Effect.create("temperature-coefficient", alpha_per_k=-3e-3,
                                             t0_c=25.0),))
    python = tc.simulate(T, SCHEDULE, 25.0).tj_k  # Radau on the nodal network
    linear = Analytic().simulate(ThermalModel(LADDER), SCHEDULE, T)
    assert np.max(np.abs(python - linear)) > 0.1  # the effect matters here
    for name in ("ngspice", "pyspice"):
        rise = engine(name, tc).simulate(tc, SCHEDULE, T, 25.0)
        np.testing.assert_allclose(rise, python, rtol=0, atol=1e-3 * POWER * LADDER.rth)


# ------------------------------------------------------------------------------ commands
def _tc_model(tmp_path) -> str:
    tc = ThermalModel(LADDER, (Effect.create("temperature-coefficient", alpha_per_k=-3e-3),))
    return str(tc.save(tmp_path / "tc.json"))


def test_commands_refuse_analytic_for_a_nonlinear_model(tmp_path, capsys):
    from conftest import DATA

    from spicethermal.cli.main import main

    (tmp_path / "p.csv").write_text("t_s,power_w\n0,0\n1e-3,0.5\n")
    model = _tc_model(tmp_path)
    for argv in (["compare", model, str(DATA / "sample_bundle")],
                 ["predict", model, "--profile", str(tmp_path / "p.csv"), "-o",
                  str(tmp_path / "tj.csv")]):
        assert main([*argv, "--engine", "analytic"]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "--engine analytic: the model has device effects" in err
    assert not (tmp_path / "tj.csv").exists()


@pytest.mark.slow
@pytest.mark.ngspice
def test_commands_run_every_engine(tmp_path, capsys):
    import json

    from spicethermal.cli.main import main

    (tmp_path / "p.csv").write_text("t_s,power_w\n0,0\n1e-3,0.5\n0.5,0.5\n")
    model = str(ThermalModel(LADDER).save(tmp_path / "m.json"))
    peaks = {}
    for name in NAMES:
        out = tmp_path / f"tj_{name}.csv"
        assert main(["predict", model, "--profile", str(tmp_path / "p.csv"), "-o", str(out),
                     "--engine", name]) == 0
        peaks[name] = np.loadtxt(out, delimiter=",", skiprows=2)[:, 2].max()  # tj_c
    assert max(peaks.values()) - min(peaks.values()) < 1e-3 * 0.5 * LADDER.rth
    capsys.readouterr()
    checks = []
    for name in ("ngspice", "pyspice"):
        assert main(["drive", model, "--t-max", "70", "--target", "50", "--p-max", "1",
                     "--verify", "--json", "--engine", name]) == 0
        checks.append(json.loads(capsys.readouterr().out)["ngspice"])
    assert [c["engine"] for c in checks] == ["ngspice", "pyspice"]
    assert checks[0]["ngspice_peak_junction_c"] == pytest.approx(
        checks[1]["ngspice_peak_junction_c"], abs=1e-3)


def test_drive_refuses_the_analytic_engine_before_writing(tmp_path, capsys):
    from spicethermal.cli.main import main

    model = str(ThermalModel(LADDER).save(tmp_path / "m.json"))
    deck = tmp_path / "d.cir"
    assert main(["drive", model, "--t-max", "70", "--target", "50", "--spice", str(deck),
                 "--engine", "analytic"]) == 2
    assert "--engine analytic" in capsys.readouterr().err and not deck.exists()


# ------------------------------------------------------------------------- plugin effects
def test_a_plugin_device_effect_is_simulated_by_every_engine_and_exported(register_plugin,
                                                                           tmp_path):
    """A toy device effect registered from outside the package (issue #13): the first layer's
    resistance falls with the junction temperature, ``R0 (1 − g (Tj − 25))``. The package
    knows it only through its hooks: the Python integration, ngspice -b and ngspice in
    process agree, and its exported .lib holds its own expression."""
    from spicethermal.effects import COOLING, DeviceEffect, Param, Traits
    from spicethermal.effects.spice import number
    from spicethermal.spice.lib import render_lib

    class Toy(DeviceEffect):
        name = "toy-sink"
        summary = "a toy: the first layer conducts better when hot"
        params = {"g_per_k": Param("1/K", 0.0, 0.0, 0.01)}
        traits = Traits(frozenset({COOLING}))

        def resistance_scale(self, form, p, t_layer_c, t_junction_c):
            out = np.ones_like(t_layer_c)
            out[:, 0] = (1.0 - p["g_per_k"] * (t_junction_c - 25.0))[:, 0]
            return out

        def spice_resistance_scale(self, effect, layer, t_layer, t_junction):
            if layer != 0:
                return None
            return f"(1-({number(effect.params['g_per_k'])})*({t_junction}-25))"

        def guess(self, form, fixed, evidence):
            return ({"g_per_k": 1e-3},)

    register_plugin(Toy)
    model = ThermalModel(LADDER, (Effect.create("toy-sink", g_per_k=0.008),))
    assert not model.is_linear
    with pytest.raises(DataFormatError):
        engine("analytic", model)
    lib = render_lib(model, "ngspice", "cauer")
    assert "BR1 TJ N1 I=V(TJ,N1)/(" in lib and "*(1-(0.008)*(V(TJ)+TOFFSET-25)))" in lib
    python = model.simulate(T, SCHEDULE, 25.0).tj_k
    linear = Analytic().simulate(ThermalModel(LADDER), SCHEDULE, T)
    assert np.max(np.abs(python - linear)) > 0.1  # the toy effect matters here
    for name in ("ngspice", "pyspice"):
        rise = engine(name, model).simulate(model, SCHEDULE, T, 25.0)
        np.testing.assert_allclose(rise, python, rtol=0, atol=1e-3 * POWER * LADDER.rth)
