"""The drive's result objects: the one serialisation convention, the ``drive --json``
document unchanged, summaries and figures."""

from __future__ import annotations

import json

import pytest

from spicethermal.core.ladder import Foster
from spicethermal.drive.optimize import optimize_drive
from spicethermal.drive.release import Release
from spicethermal.drive.result import DriveResult
from spicethermal.drive.twophase import TwoPhase
from spicethermal.model import ThermalModel

#: The keys of the ``spicethermal drive --json`` document, in order (a contract).
DRIVE_KEYS = ["time_to_target_s", "constant_duty_time_to_target_s", "speedup",
              "peak_junction_c", "peak_method", "method", "node", "target_c", "t_max_c",
              "ambient_c", "p_max_w", "f_pwm_hz", "tol_k", "hold_duty", "hold_peak_junction_c",
              "schedule", "ripple_margin_k", "two_phase", "release"]


@pytest.fixture(scope="module")
def result() -> DriveResult:
    model = ThermalModel(Foster.from_tau([30.0, 70.0], [0.01, 1.0]))
    return optimize_drive(model, 70.0, 55.0, p_max_w=1.0, release_c=40.0)


@pytest.mark.parametrize("part", [TwoPhase(0.463, 0.7889, 0.4896, 69.95),
                                  Release(40.0, 0.05, 1.375)])
def test_parts_round_trip(part) -> None:
    cls = type(part)
    assert cls.from_dict(part.to_dict()) == part
    assert cls.from_json(part.to_json()) == part
    assert part.as_json() == part.to_dict()  # the deprecated spelling still answers


def test_parts_of_a_real_drive_round_trip(result) -> None:
    assert result.two_phase is not None and result.release is not None
    assert TwoPhase.from_dict(result.two_phase.to_dict()) == result.two_phase
    assert Release.from_json(result.release.to_json()) == result.release


def test_the_json_document_keeps_its_keys_and_values(result) -> None:
    doc = result.to_dict()
    assert list(doc) == DRIVE_KEYS
    assert doc["schedule"] == [{"t_s": t, "duty": d} for t, d in result.schedule]
    assert doc["two_phase"] == {"boost_s": result.two_phase.boost_s,
                                "boost_duty": result.two_phase.boost_duty,
                                "time_to_target_s": result.two_phase.time_to_target_s,
                                "peak_junction_c": result.two_phase.peak_junction_c}
    assert doc["release"] == {"release_c": 40.0, "keep_warm_duty": 0.0,
                              "time_s": result.release.time_s}
    assert doc["speedup"] == result.constant_duty_time_to_target_s / result.time_to_target_s
    assert json.loads(result.to_json()) == doc
    assert result.as_json() == doc


def test_summary_names_both_drives_and_the_release(result) -> None:
    text = str(result)
    assert f"  {result.two_phase}" in text.splitlines()
    assert f"  {result.release}" in text.splitlines()
    assert text.startswith("drive of the junction to 55 °C")


def test_the_result_plots_itself(result) -> None:
    ax = result.plot()
    assert ax.get_xscale() == "log"
    assert result.t_max_c in [line.get_ydata()[0] for line in ax.get_lines()]
