"""The main job end to end: every report section, real figures, and a real browser."""

from __future__ import annotations

import json
import re
import shutil
import subprocess
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest

from spicethermal.demo import run_demo
from spicethermal.model import ThermalModel
from spicethermal.report import SECTION_IDS, figure_is_nontrivial


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    return run_demo(tmp_path_factory.mktemp("demo") / "out", seed=3, quiet=True)


class _Page(HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.ids: list[str] = []
        self.images: list[str] = []
        self.text: list[str] = []

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if "id" in a:
            self.ids.append(a["id"])
        if tag == "img":
            self.images.append(a["src"])

    def handle_data(self, data):
        self.text.append(data)


@pytest.mark.slow
def test_report_has_every_section_and_real_figures(demo):
    page = _Page()
    page.feed(demo.report.read_text())
    assert set(SECTION_IDS) <= set(page.ids)
    for needed in ("fig2_calibration", "fig7_fit", "fig8_impedance", "table1_mur880e",
                   "table2_delta", "effect_before_after", "diagnosis_candidates"):
        assert any(needed in src for src in page.images), needed
    for src in page.images:
        path = demo.report.parent / src
        assert path.exists() and not src.startswith(("/", "http")), src  # offline, relative
        assert figure_is_nontrivial(path), src
    text = " ".join(page.text)
    assert "Verdict: temperature-coefficient" in text
    assert ".SUBCKT ACTUATOR TJ TREF" in text  # the usage snippet and a netlist


@pytest.mark.slow
def test_demo_outputs_are_usable(demo):
    assert len(demo.libs) == 6 and all(p.read_text().count(".SUBCKT") == 1 for p in demo.libs)
    model = ThermalModel.load(demo.out / "actuator_model.json")
    assert model.rth == pytest.approx(146.0 * (1 - 2e-3 * 13.7), rel=0.02)  # Rth at its rise
    better = ThermalModel.load(demo.out / "actuator_model_temperature-coefficient.json")
    alpha = better.effect("temperature-coefficient").params["alpha_per_k"]
    assert alpha == pytest.approx(-2e-3, rel=0.25)  # the bench's hidden coefficient
    summary = json.loads((demo.out / "summary.json").read_text())
    assert len(summary["summary"]) == 5 and len(demo.summary) == 5
    m = re.search(r"RMS ([\d.]+) K -> ([\d.]+) K", demo.summary[3])
    assert m, demo.summary[3]
    assert float(m.group(1)) / float(m.group(2)) >= 3  # the error falls when the effect is added


@pytest.mark.slow
def test_report_renders_in_headless_chromium(demo, tmp_path):
    browser = shutil.which("chromium") or shutil.which("chromium-browser")
    assert browser, "chromium is installed by `make setup`"
    shot = tmp_path / "page.png"
    subprocess.run([browser, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
                    "--no-first-run", "--disable-background-networking",
                    "--disable-component-update", "--disable-sync",
                    f"--user-data-dir={tmp_path / 'profile'}", "--window-size=1100,3000",
                    f"--screenshot={shot}", demo.report.as_uri()],
                   capture_output=True, timeout=120, check=True)
    assert figure_is_nontrivial(shot)
    from matplotlib.image import imread

    img = imread(str(shot))
    # the page is laid out: a white column on a grey background, with dark text on it
    assert np.mean(img[:, :30, :3]) < np.mean(img[:, 200:900, :3]) + 0.2
    assert np.min(img[:400, 100:900, :3]) < 0.3


def test_demo_command_help_names_the_report():
    from spicethermal.commands import demo as command

    assert "report" in command.HELP and Path(command.__file__).exists()
