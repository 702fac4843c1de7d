"""The diagnosis: nothing named on linear data of any shape, each hidden effect named with the
error falling, the sample bundle's bow, the verdict's classes, the document, the command."""

from __future__ import annotations

import json

import numpy as np
import pytest
from conftest import DATA
from scenarios import hidden, scenario_bundle

from spicethermal.analysis.compare import compare
from spicethermal.analysis.diagnose import diagnose, fit_with_effects
from spicethermal.analysis.diagnosis import DIAGNOSIS_FORMAT
from spicethermal.cli.main import main
from spicethermal.io.bundle import Bundle
from spicethermal.validation.cases import DEVICES, Case, bench_for, laws_on
from spicethermal.validation.laws import ResistanceLaw
from spicethermal.validation.linear import linear_fast

CATALOGUED = [n for n, e in hidden().items() if e is not None]


# ------------------------------------------------------------------------------ the fast tier
@pytest.mark.parametrize("case", linear_fast(), ids=lambda c: c.name)
def test_on_linear_data_the_baseline_is_at_the_noise_and_nothing_is_named(case):
    """Data a linear network produced, of any shape, with or without the steady readings:
    the baseline is no misfit to explain (an independent simulator made them)."""
    d = diagnose(case.record().bundle)
    assert d.verdict.cls == "none" and not d.effects and not d.steps, d.verdict.reason
    assert d.verdict.reason.startswith("the linear ladder fits every data set within its noise")


@pytest.mark.slow
def test_the_work_is_the_same_on_every_run():
    b = linear_fast()[0].record().bundle
    one, two = diagnose(b), diagnose(b)
    assert one.work == two.work and one.to_dict() == two.to_dict()


# ------------------------------------------------------------------------------ the slow tier
@pytest.mark.slow
@pytest.mark.parametrize("name", CATALOGUED)
def test_a_hidden_effect_is_named_and_the_error_falls(name):
    d = diagnose(scenario_bundle(name, seed=1))
    assert d.effects[:1] == [name], d.verdict.reason
    assert d.verdict.cls == "named"
    assert d.final.rms_k < d.baseline.rms_k / 2
    doc = d.to_dict()
    assert doc["format"] == DIAGNOSIS_FORMAT and doc["verdict"]["effect"] == name
    assert doc["steps"][0]["status"] == "named" and doc["work"]["rows"] == d.work


@pytest.mark.slow
def test_clean_data_and_physics_outside_the_catalogue_are_not_named():
    assert not diagnose(scenario_bundle("clean", seed=2)).effects
    drift = diagnose(scenario_bundle("ambient-drift", seed=2))
    assert drift.verdict.cls == "none" and not drift.effects, drift.verdict.reason
    assert "not in the catalogue" in drift.verdict.reason


@pytest.mark.slow
def test_the_sample_bundle_names_its_calibrations_bow_and_adding_it_lowers_the_error():
    bundle = Bundle.read(DATA / "sample_bundle")
    d = diagnose(bundle)
    assert d.effects == ["tsp-nonlinearity"] and d.verdict.cls == "named"
    assert d.final.dataset("calibration").rms_k < d.baseline.dataset("calibration").rms_k / 5
    model = fit_with_effects(bundle, ["tsp-nonlinearity"])
    assert model.effects[0].name == "tsp-nonlinearity"
    assert compare(model, bundle).rms_k < compare(d.baseline_model, bundle).rms_k


@pytest.mark.slow
def test_an_effect_the_data_cannot_show_alone_is_never_named_alone():
    """A TSP's curvature without calibration points reads as a device effect would."""
    b = scenario_bundle("tsp-nonlinearity", seed=1)
    b = Bundle(device=b.device, ambient_c=b.ambient_c, cooling=b.cooling, pwm=b.pwm)
    # alone, the curvature explains the step, and is refused for want of a calibration
    d = diagnose(b, effects=("tsp-nonlinearity",))
    assert (d.steps[0].chosen.name, d.steps[0].status) == ("tsp-nonlinearity", "unshown")
    assert not d.effects and d.verdict.cls == "none", d.verdict.reason
    # beside a device effect that bends the same way (a quadratic law), never named alone
    d = diagnose(b, effects=("tsp-nonlinearity", "temperature-coefficient"))
    assert "tsp-nonlinearity" not in d.effects or d.verdict.cls == "ambiguous", \
        d.verdict.reason


@pytest.mark.slow
def test_the_command_prints_the_report_the_document_and_the_figures(tmp_path, capsys):
    bundle = scenario_bundle("sample-window", seed=1).write(tmp_path / "b")
    assert main(["diagnose", str(bundle), "--json", "--report", str(tmp_path / "r")]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["format"] == DIAGNOSIS_FORMAT and doc["verdict"]["effects"] == ["sample-window"]
    assert set(doc["verdict"]) >= {"class", "effect", "effects", "alternatives", "reason",
                                   "separate_by", "where"}
    page = (tmp_path / "r" / "index.html").read_text()
    assert "sample-window" in page and f"{doc['baseline']['rms_k']:.3g}" in page
    assert main(["diagnose", str(bundle)]) == 0
    text = capsys.readouterr().out
    assert "RMS staircase: baseline" in text and "verdict: named — sample-window" in text
    assert np.isfinite(doc["final"]["rms_k"])


def test_the_command_takes_a_work_budget_and_says_when_it_stopped_the_search(capsys):
    sample = str(DATA / "sample_bundle")
    assert main(["diagnose", sample, "--budget", "1k", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["work"]["budget"] == 1000 and "work budget" in doc["work"]["stopped"]
    assert doc["verdict"]["class"] == "none" and "work budget" in doc["verdict"]["reason"]
    assert main(["diagnose", sample, "--budget", "1k"]) == 0
    assert "e.g. --budget 4000," in capsys.readouterr().out
    assert main(["diagnose", str(DATA / "actuator_table2.csv"), "--budget", "1k"]) == 2
    assert capsys.readouterr().err.strip().endswith(
        "--budget applies to a bundle, not to a table of readings")
    with pytest.raises(SystemExit) as err:
        main(["diagnose", sample, "--budget", "0"])
    assert err.value.code == 2 and "must be >= 1" in capsys.readouterr().err


@pytest.mark.slow
def test_a_strong_power_law_on_every_layer_is_named_on_every_layer():
    """An independent simulator's device whose every layer follows R ∝ T^2.5 (T in kelvin)
    with heat capacities rising 0.25 %/K: the coefficient is named on every layer of the
    fitted ladder, every data set at its noise (a subset of layers, which the screens on a
    ladder that took the law into its values may rank first, is not)."""
    dev = DEVICES["diode"]
    law = ResistanceLaw("power", exponent=2.5)
    variant = {"noise_k": 0.01, "per_decade": 5, "dense_pwm": True, "steady": False,
               "volts": False, "n_curves": 3}
    network = dev.network(laws=laws_on(dev, law), c_slope_per_k=(2.5e-3,) * 4)
    case = Case("every", "effect", ("temperature-coefficient",), dev.name, network,
                bench_for(dev, variant), 13)
    d = diagnose(case.record().bundle)
    assert d.verdict.cls == "named" and d.effects == ["temperature-coefficient"], \
        d.verdict.reason
    e = d.model().effect("temperature-coefficient")
    assert e.form != "junction" and e.params["first_layer"] == 0, e.params
    assert e.params["last_layer"] >= 3, e.params
