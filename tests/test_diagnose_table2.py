"""Diagnosis of a measured-vs-simulated PWM table: the paper's Table 2, and a synthetic table
where the sample window really is the cause (the tool must then say so)."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest
from conftest import DATA
from scenarios import DUTIES, FREQS_HZ, actuator

from spicethermal.analysis.diagnosis import DIAGNOSIS_FORMAT
from spicethermal.analysis.table2 import diagnose_table
from spicethermal.cli.main import main
from spicethermal.engines.pwm import steady_state
from spicethermal.io.bundle import format_columns

TABLE2 = DATA / "actuator_table2.csv"


@pytest.fixture(scope="module")
def paper():
    return diagnose_table(TABLE2)


def _rows():
    with open(TABLE2) as fh:
        rows = list(csv.DictReader(line for line in fh if not line.startswith("#")))
    f = np.array([float(r["freq_hz"]) for r in rows])
    d = np.array([float(r["duty"]) for r in rows])
    e = np.array([float(r["tj_exp_c"]) for r in rows]) - 25
    m = np.array([float(r["tj_model_c"]) for r in rows]) - 25
    return f, d, e, m


def test_paper_table_baseline_is_the_published_delta(paper):
    f, d, e, m = _rows()
    doc = paper.to_dict()
    assert doc["format"] == DIAGNOSIS_FORMAT
    assert doc["baseline"]["rms_k"] == pytest.approx(float(np.sqrt(np.mean((e - m) ** 2))))
    worst = doc["baseline"]["worst"][0]
    k = int(np.argmax(np.abs(e - m)))
    assert worst["at"] == {"freq_hz": f[k], "duty": d[k]}
    assert worst["residual_k"] == pytest.approx(e[k] - m[k])


def test_paper_explanations_do_not_fit(paper):
    """The window and early-time hypotheses at their best case leave most of Δ: no verdict."""
    a = paper.analysis
    assert paper.verdict.cls == "none" and paper.verdict_effect is None
    assert paper.verdict.reason.startswith("neither explanation the paper gives fits")
    assert {c.effect for c in paper.candidates} == {"sample-window", None}
    assert all(c.improvement < 2 for c in paper.candidates)
    # the window's prediction is never positive, while Δ is positive at two points
    assert np.all(a.paper_window_pred_k <= 1e-12)
    assert set(zip(a.freq_hz[a.delta_k > 0], a.duty[a.delta_k > 0], strict=True)) == {
        (1e3, 0.2), (25e3, 0.8)}
    # and its size never grows with frequency at fixed duty
    for duty in DUTIES:
        sel = np.argsort(np.where(a.duty == duty, a.freq_hz, np.inf))[:6]
        assert np.all(np.diff(np.abs(a.paper_window_pred_k[sel])) <= 1e-9)


def test_paper_simulated_column_is_not_a_periodic_steady_state(paper):
    f, d, e, m = _rows()
    a = paper.analysis
    for duty in (0.2, 0.5):  # rises with frequency by more than two standard errors
        slope, se = a.slopes_k_per_decade[("simulated", duty)]
        sel = d == duty
        assert slope == pytest.approx(np.polyfit(np.log10(f[sel]), m[sel], 1)[0])
        assert slope > 2 * se
    assert a.ladder_rms_k > 2 * a.reading_noise_k
    k = float(d @ e / (d @ d))  # the measured column is D·P·Rth plus per-frequency offsets
    assert a.mean_model["measured"][0] == pytest.approx(k)
    assert a.offsets_rms_k < 0.5 * a.mean_model["measured"][1]
    assert "per-frequency offsets" in paper.verdict.reason
    assert a.departure_corr < -0.5


def _synthetic_table(tmp_path, window_s: float):
    lad, p = actuator(), 0.1
    f, d = (np.array(x) for x in zip(*[(f, d) for d in DUTIES for f in FREQS_HZ], strict=True))
    sim = np.array([25 + steady_state(lad, p, fi, di).peak_k for fi, di in zip(f, d, strict=True)])
    exp = np.array([25 + steady_state(lad, p, fi, di, window_s).reading_k
                    for fi, di in zip(f, d, strict=True)])
    exp = exp + np.random.default_rng(0).normal(0.0, 0.03, f.size)
    path = tmp_path / "table.csv"
    path.write_text(format_columns({"freq_hz": f, "duty": d, "tj_exp_c": exp,
                                    "tj_model_c": sim}))
    return path


@pytest.mark.slow
def test_a_real_sample_window_is_recognised(tmp_path):
    d = diagnose_table(_synthetic_table(tmp_path, 1e-4))
    assert d.verdict_effect == "sample-window", d.verdict.reason
    assert d.candidates[0].improvement > 3
    a = d.analysis
    assert a.ladder_rms_k < 0.01  # a linear ladder reproduces this simulated column
    assert a.power_w == pytest.approx(0.1, rel=1e-3)


def test_table_command(tmp_path, capsys):
    assert main(["diagnose", str(TABLE2), "--json", "--report", str(tmp_path / "r")]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["verdict"]["effect"] is None
    assert (tmp_path / "r" / "diagnosis_table2.png").stat().st_size > 10000
    assert main(["diagnose", str(TABLE2), "--rth", "146", "--power", "0.1"]) == 0
    out = capsys.readouterr().out
    assert "findings (measured vs simulated table):" in out and "verdict: none" in out
    bad = tmp_path / "bad.csv"
    bad.write_text("freq_hz,duty,tj_exp_c\n500,0.2,27.2\n")
    assert main(["diagnose", str(bad)]) == 2
    assert "tj_model_c" in capsys.readouterr().err
    assert main(["diagnose", str(TABLE2), "--model", str(bad)]) == 2
    assert "--model" in capsys.readouterr().err
