"""Measured vs model over a bundle: exact zeros on self-generated data, signs, effects, command."""

from __future__ import annotations

import csv
import json
import math
import re

import numpy as np
import pytest
from conftest import DATA

from spicethermal.analysis.compare import (
    COMPARISON_FORMAT,
    Comparison,
    ComparisonPoint,
    compare,
    cooling_rise_k,
)
from spicethermal.cli.main import main
from spicethermal.core.errors import DataFormatError
from spicethermal.effects import Effect
from spicethermal.io.bundle import Bundle, CalibrationTable, CoolingTable, PwmTable
from spicethermal.model import ThermalModel

FREQS = (500.0, 1e3, 3e3, 5e3, 10e3, 25e3)
DUTIES = (0.2, 0.5, 0.8)
POWER_W = 0.094
WINDOW_S = 1e-4
T_COOL = np.logspace(-4, 2, 13)


def synthetic_bundle(model: ThermalModel, *, window_s: float = WINDOW_S,
                     manifest_window_s: float | None = None, ambient_c: float = 25.0) -> Bundle:
    """What a perfect bench would record from ``model``: the PWM grid and two cooling curves
    (one with a drifting ``tref_c`` column), plus a calibration (not compared)."""
    f, d = (np.array(x) for x in zip(*[(f, d) for f in FREQS for d in DUTIES], strict=True))
    tj = [ambient_c + model.pwm(POWER_W, fi, di, window_s, ambient_c).reading_k
          for fi, di in zip(f, d, strict=True)]
    pwm = PwmTable(f, d, tj, power_w=POWER_W,
                   sample_window_s=window_s if manifest_window_s is None else manifest_window_s)
    tref = 24.0 + 0.01 * np.arange(T_COOL.size)
    cool1 = CoolingTable(T_COOL, POWER_W, tj_c=ambient_c + cooling_rise_k(model, POWER_W, T_COOL),
                         tref_steady_c=ambient_c)
    cool2 = CoolingTable(T_COOL, 2 * POWER_W, tj_c=tref + cooling_rise_k(model, 2 * POWER_W,
                                                                         T_COOL, 24.0),
                         tref_c=tref)
    return Bundle(device="synthetic actuator", ambient_c=ambient_c,
                  calibration=CalibrationTable([25.0, 75.0], [0.6, 0.5]), pwm=pwm,
                  cooling=(cool1, cool2))


@pytest.fixture
def model(actuator) -> ThermalModel:
    return ThermalModel(actuator)


@pytest.fixture
def bundle_dir(tmp_path, model):
    return synthetic_bundle(model).write(tmp_path / "bundle")


# ------------------------------------------------------------------------------ library
def test_self_generated_bundle_gives_exact_zeros(model, bundle_dir):
    c = compare(model, Bundle.read(bundle_dir))
    # two calibration points: no calibration data set (a line needs three to show a bow)
    assert c.datasets == ("cooling_1", "cooling_2", "pwm")
    assert len(c.dataset("pwm").points) == 18
    assert len(c.dataset("cooling_2").points) == T_COOL.size
    assert c.max_abs_k < 1e-9 and c.engine == "analytic"  # the closed forms, to rounding
    p = c.dataset("pwm").points[-1]
    assert dict(p.at) == {"freq_hz": 25e3, "duty": 0.8}
    assert p.info["window_s"] == WINDOW_S and p.info["power_w"] == POWER_W


def test_perturbations_show_with_the_right_sign(model, tmp_path):
    b = synthetic_bundle(model)
    tj = b.pwm.tj_c.copy()
    tj[4] += 0.5  # bench reads hotter than the model at row 4
    cool = b.cooling[0]
    tjc = cool.tj_c.copy()
    tjc[2] -= 0.3  # and colder on the first cooling curve
    b = b.with_(pwm=PwmTable(b.pwm.freq_hz, b.pwm.duty, tj, power_w=POWER_W,
                             sample_window_s=WINDOW_S),
                cooling=(CoolingTable(cool.t_s, POWER_W, tj_c=tjc, tref_steady_c=25.0),
                         b.cooling[1]))
    c = compare(model, Bundle.read(b.write(tmp_path / "b")))
    r = {(p.dataset, i): p.residual_k for name, sub in c.by_dataset().items()
         for i, p in enumerate(sub.points)}
    assert r.pop(("pwm", 4)) == pytest.approx(0.5, abs=1e-12)
    assert r.pop(("cooling_1", 2)) == pytest.approx(-0.3, abs=1e-12)
    assert max(abs(v) for v in r.values()) < 1e-12
    assert c.max_abs_k == pytest.approx(0.5, abs=1e-12)
    assert c.worst(1)[0].dataset == "pwm"
    assert c.rms_k == pytest.approx(math.sqrt((0.25 + 0.09) / len(c.points)), rel=1e-9)


def test_model_with_more_heat_reads_hotter(model, bundle_dir):
    """A model with a 10 % higher Rth predicts hotter junctions: every residual negative."""
    lad = model.ladder
    hot = ThermalModel(type(lad)(np.array(lad.r) * 1.1, np.array(lad.c) / 1.1))
    c = compare(hot, Bundle.read(bundle_dir))
    assert np.all(c.residuals_k[c.residuals_k != 0] < 0)
    assert np.sum(c.residuals_k < 0) > 0.9 * len(c.points)


def test_sample_window_effect_overrides_the_bundle(model, tmp_path):
    """Bundle recorded with a 100 µs window but not saying so (sample_window_s = 0)."""
    b = Bundle.read(synthetic_bundle(model, manifest_window_s=0.0).write(tmp_path / "b"))
    plain = compare(model, b, datasets=["pwm"])
    assert np.all(plain.residuals_k < 0)  # model reads the peak, hotter than the bench
    assert plain.residuals_k[-1] < -0.1  # 25 kHz: the window is 2.5 periods long
    with_window = model.with_effects([Effect.create("sample-window", window_s=WINDOW_S)])
    assert compare(with_window, b).max_abs_k < 1e-9
    assert compare(model, b, window_s=WINDOW_S).max_abs_k < 1e-9


def test_a_tsp_effect_bends_every_reading(model, bundle_dir):
    b = Bundle.read(bundle_dir)
    q = 1e-3
    tsp = model.with_effects([Effect.create("tsp-nonlinearity", quad_k_per_k2=q, t_cal_c=25.0)])
    c2 = compare(tsp, b, datasets=["pwm"])
    for p in c2.points:
        true_c = p.measured_c  # the bundle holds the true temperature
        assert p.residual_k == pytest.approx(-q * (true_c - 25.0) ** 2, abs=1e-9)


def test_nonlinear_cooling_starts_at_the_self_consistent_steady_state(actuator):
    alpha, p, tref = -3e-3, 0.3, 30.0
    m = ThermalModel(actuator, (Effect.create("temperature-coefficient", alpha_per_k=alpha),))
    rise = cooling_rise_k(m, p, [0.0, 1e-3, 1e3], tref)
    rth = actuator.rth
    # θ = P Rth (1 + α (tref + θ − t0))  →  θ = P Rth (1 + α (tref − t0)) / (1 − α P Rth)
    expect = p * rth * (1 + alpha * (tref - 25.0)) / (1 - alpha * p * rth)
    assert rise[0] == pytest.approx(expect, rel=1e-9)
    assert 0 < rise[1] < rise[0] and abs(rise[2]) < 1e-6


def test_errors(model, bundle_dir):
    b = Bundle.read(bundle_dir)
    with pytest.raises(DataFormatError, match="cooling_9"):
        compare(model, b, datasets=["cooling_9"])
    with pytest.raises(DataFormatError, match="nothing to compare"):
        compare(model, Bundle(calibration=CalibrationTable([25.0, 75.0], [0.6, 0.5])))
    case = ThermalModel(model.ladder, reference="case")
    with pytest.raises(DataFormatError, match="reference"):
        compare(case, b)
    with pytest.raises(DataFormatError, match="engine"):
        compare(model, b, "spectre")
    with pytest.raises(DataFormatError, match="window_s"):
        compare(model, b, window_s=-1.0)


def test_comparison_document_and_table():
    pts = (ComparisonPoint("pwm", {"freq_hz": 500.0, "duty": 0.2}, 27.20, 27.56,
                           {"power_w": 0.094, "window_s": 1e-4}),
           ComparisonPoint("pwm", {"freq_hz": 25e3, "duty": 0.8}, 37.70, 37.10,
                           {"power_w": 0.094, "window_s": 1e-4}),
           ComparisonPoint("cooling_1", {"t_s": 1e-3}, 38.0, 38.5))
    c = Comparison(pts)
    doc = json.loads(json.dumps(c.to_json()))
    assert set(doc) == {"format", "rms_k", "max_abs_k", "points"}
    assert doc["format"] == COMPARISON_FORMAT
    assert doc["points"][0] == {"dataset": "pwm", "at": {"freq_hz": 500.0, "duty": 0.2},
                                "measured_c": 27.20, "model_c": 27.56,
                                "residual_k": pytest.approx(-0.36)}
    assert doc["max_abs_k"] == pytest.approx(0.6)
    text = c.table()
    assert "Freq (kHz)" in text and "D=20%" in text and "D=80%" in text
    row = next(line for line in text.splitlines() if line.strip().startswith("0.5 |"))
    assert "27.20" in row and "27.56" in row and "-0.36" in row
    assert any(line.startswith("cooling_1") for line in text.splitlines())
    assert Comparison(()).to_json()["rms_k"] is None


def test_paper_table2_layout(actuator):
    """The paper's measured column through our table: 6 frequencies × 3 duties."""
    with open(DATA / "actuator_table2.csv") as fh:
        rows = list(csv.DictReader(line for line in fh if not line.startswith("#")))
    table = PwmTable([float(r["freq_hz"]) for r in rows], [float(r["duty"]) for r in rows],
                     [float(r["tj_exp_c"]) for r in rows], power_w=POWER_W,
                     sample_window_s=WINDOW_S)
    m = ThermalModel(actuator)
    c = compare(m, Bundle(ambient_c=25.0, pwm=table))
    lines = c.table().splitlines()
    body = [line for line in lines if line.split("|")[0].strip() in
            ("0.5", "1", "3", "5", "10", "25")]
    assert len(body) == 6 and all(line.count("|") == 4 for line in body)
    for p, r in zip(c.points, rows, strict=True):
        assert p.residual_k == pytest.approx(float(r["tj_exp_c"]) - p.model_c, abs=1e-12)


# ------------------------------------------------------------------------------ ngspice
@pytest.mark.ngspice
def test_ngspice_engine_agrees_with_analytic(model, bundle_dir):
    b = Bundle.read(bundle_dir)
    c = compare(model, b, "pyspice", datasets=["pwm"])
    assert c.engine == "pyspice"
    assert c.max_abs_k < 0.02


def test_the_analytic_engine_is_exact_with_device_effects(actuator):
    """With device effects the closed form freezes the network at the mean temperatures
    (first order in the ripple); the comparison adds the exact periodic state's correction."""
    m = ThermalModel(actuator, (Effect.create("temperature-coefficient", alpha_per_k=-1e-2),))
    rows = ((2.0, 0.5), (1e3, 0.5), (25e3, 0.2))
    pwm = PwmTable([f for f, _ in rows], [d for _, d in rows], [30.0, 30.0, 28.0],
                   power_w=POWER_W, sample_window_s=WINDOW_S)
    got = compare(m, Bundle(ambient_c=25.0, pwm=pwm))
    exact = [25.0 + m.pwm_reading(POWER_W, f, d, WINDOW_S) for f, d in rows]
    assert [p.model_c for p in got.points] == pytest.approx(exact, abs=3e-5)


@pytest.mark.ngspice
def test_ngspice_agrees_with_the_analytic_engine_with_device_effects(actuator):
    """ngspice integrates the exported subcircuit; the analytic engine is the network's
    exact periodic state: they agree to ngspice's own accuracy."""
    m = ThermalModel(actuator, (Effect.create("temperature-coefficient", alpha_per_k=-3e-3),))
    pwm = PwmTable([1e3, 25e3], [0.5, 0.2], [0.0 + 30, 28.0], power_w=POWER_W,
                   sample_window_s=WINDOW_S)
    b = Bundle(ambient_c=25.0, pwm=pwm)
    spice = compare(m, b, "ngspice")
    analytic = compare(m, b)
    assert spice.engine == "ngspice" and analytic.engine == "analytic"
    assert np.max(np.abs(spice.residuals_k - analytic.residuals_k)) < 2e-3


# ------------------------------------------------------------------------------ command
def test_compare_command_json_and_table(model, bundle_dir, tmp_path, capsys):
    path = str(model.save(tmp_path / "m.json"))
    assert main(["compare", path, str(bundle_dir), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["format"] == COMPARISON_FORMAT and doc["rms_k"] < 1e-9
    assert len(doc["points"]) == 18 + 2 * T_COOL.size
    assert {p["dataset"] for p in doc["points"]} == {"pwm", "cooling_1", "cooling_2"}
    assert main(["compare", path, str(bundle_dir), "--engine", "analytic"]) == 0
    out = capsys.readouterr().out
    assert "Freq (kHz)" in out and "cooling_2" in out


@pytest.mark.parametrize("extra, word", [(["--engine", "xyce"], "engine"),
                                         (["--window", "-1"], "window")])
def test_compare_command_bad_options(model, bundle_dir, tmp_path, capsys, extra, word):
    path = str(model.save(tmp_path / "m.json"))
    with pytest.raises(SystemExit) as exc:
        main(["compare", path, str(bundle_dir), *extra])
    assert exc.value.code == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and word in err


def test_compare_command_bad_files(model, bundle_dir, tmp_path, capsys):
    path = str(model.save(tmp_path / "m.json"))
    assert main(["compare", path, str(tmp_path / "missing")]) == 2
    assert main(["compare", str(tmp_path / "none.json"), str(bundle_dir)]) == 2
    case = str(ThermalModel(model.ladder, reference="case").save(tmp_path / "case.json"))
    assert main(["compare", case, str(bundle_dir)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 3 and "missing" in err[0] and "none.json" in err[1]
    assert "reference" in err[2]


# ------------------------------------------------------------------------------ figures
def test_table2_figures(model, bundle_dir, tmp_path):
    from spicethermal.viz.plots import fig_table2, plot_table2, plot_table2_heatmap

    b = Bundle.read(bundle_dir)
    lad = model.ladder
    c = compare(ThermalModel(type(lad)(np.array(lad.r) * 1.05, lad.c)), b)
    pwm = c.dataset("pwm")
    bars = plot_table2(c)
    heights = sorted(round(p.get_height(), 9) for p in bars.patches)
    assert heights == sorted(round(p.residual_k, 9) for p in pwm.points)
    cells = plot_table2_heatmap(c).texts
    assert sorted(float(t.get_text()) for t in cells) == \
        sorted(round(p.residual_k, 2) for p in pwm.points)
    out = fig_table2(c, tmp_path / "t2.png")
    assert out.stat().st_size > 10000
    with pytest.raises(DataFormatError, match="pwm"):
        plot_table2(c.dataset("cooling_1"))


# ------------------------------------------------------------------------------ output (#45)
def test_a_pwm_grid_with_a_power_per_row_is_one_table(model):
    """Each row's measured power (as the bench records it) goes in a column of one Table 2,
    not into 18 one-row tables."""
    f, d = (np.array(x) for x in zip(*[(f, d) for f in FREQS for d in DUTIES], strict=True))
    powers = POWER_W * (1 + 1e-3 * np.arange(f.size))
    table = PwmTable(f, d, np.full(f.size, 30.0), power_w=POWER_W, row_power_w=powers,
                     sample_window_s=WINDOW_S)
    text = compare(model, Bundle(ambient_c=25.0, pwm=table)).table()
    lines = text.splitlines()
    assert sum("Freq (kHz)" in line for line in lines) == 1
    assert "P per point" in lines[0] and "sample window 100 µs" in lines[0]
    assert lines[2].count("P (W)") == len(DUTIES)
    body = [line for line in lines if line.split("|")[0].strip() in ("0.5", "1", "3", "5", "10",
                                                                      "25")]
    assert len(body) == len(FREQS) and all(line.count("|") == 4 for line in body)
    assert "0.0940" in body[0] and f"{powers[-1]:.4f}" in body[-1]
    assert any(line.startswith("pwm: 18 points, rms") for line in lines)


def test_cooling_curves_are_one_table(model):
    c = compare(model, synthetic_bundle(model))
    lines = c.table().splitlines()
    start = lines.index(next(x for x in lines if x.startswith("Cooling curves")))
    assert lines[start + 1].split()[:4] == ["curve", "power", "(W)", "points"]
    assert [x.split()[0] for x in lines[start + 2:start + 4]] == ["cooling_1", "cooling_2"]
    assert lines[-1].startswith("all data sets: 44 points")


def test_compare_on_the_record_a_model_was_fitted_to_leaves_out_what_fit_masked(tmp_path,
                                                                                 capsys):
    """The real MOSFET transient: fit, then compare with the same calibration. The samples of
    the electrical transient that fit masked are left out and counted; what is left is what the
    model was asked to describe (RMS 1.71 K and a 28 K worst point when they were compared)."""
    raw = DATA / "pyrth_mosfet"
    cal = ["--calibration", str(raw / "calibration.csv"), "--ambient", "25"]
    model = str(tmp_path / "m.json")
    assert main(["fit", str(raw / "MOSFET_dry.txt"), *cal, "-o", model, "-q"]) == 0
    fitted = json.loads((tmp_path / "m.json").read_text())["provenance"]["early_time"]
    capsys.readouterr()
    assert main(["compare", model, str(raw / "MOSFET_dry.txt"), *cal, "--json"]) == 0
    out, err = capsys.readouterr()
    doc = json.loads(out)
    left = doc["left_out"]["cooling_1"]
    assert left["before_s"] == fitted["masked_s"][1] and left["samples"] == 88
    assert min(p["at"]["t_s"] for p in doc["points"]) >= left["before_s"]
    assert doc["rms_k"] < 0.05 and doc["max_abs_k"] < 0.1
    assert "88 samples before 9.6e-05 s left out" in err
    assert main(["compare", model, str(raw / "MOSFET_dry.txt"), *cal]) == 0
    text = capsys.readouterr().out
    assert re.search(r"^cooling_1\s+1\s+242\s+88 before 96 µs", text, re.M), text


def test_a_model_fitted_to_every_reading_is_compared_on_every_sample(tmp_path, model, capsys):
    """A ladder fitted to a Zth (its provenance records the early-time treatment) is judged
    without the samples fit masked; a model fitted to every reading (fit --effect, diagnose:
    here with the transient it found) on every sample."""
    t = np.geomspace(1e-6, 10.0, 200)
    rise = POWER_W * model.ladder.cooling(t) - 2.0 * np.exp(-t / 2e-5)  # a 2 K transient
    b = Bundle(ambient_c=25.0, cooling=(CoolingTable(t, POWER_W, tj_c=25.0 + rise,
                                                     tref_steady_c=25.0),))
    path = b.write(tmp_path / "b")
    zth_fit = ThermalModel(model.ladder, provenance={"early_time": {"masked_s": 1e-4}})
    with_effect = ThermalModel(model.ladder, (Effect.create(
        "electrical-transient", amplitude_k=2.0, masked_s=1e-4),))
    for m, masked in ((zth_fit, True), (with_effect, False)):
        m.save(tmp_path / "m.json")
        assert main(["compare", str(tmp_path / "m.json"), str(path), "--json"]) == 0
        doc = json.loads(capsys.readouterr().out)
        assert ("left_out" in doc and doc["left_out"]["cooling_1"]["samples"] > 0) == masked
