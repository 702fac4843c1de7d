"""The main job end to end: every report section, real figures, and a real browser."""

from __future__ import annotations

import hashlib
import json
import os
import re
import shutil
import subprocess
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest
from matplotlib.figure import Figure

from spicethermal.demo import run_demo
from spicethermal.identify.readings import calibration_fit
from spicethermal.model import ThermalModel
from spicethermal.report.html import SECTION_IDS, figure_is_nontrivial

#: A unit at the end of an axis label or a table header: ``(K)``, ``(K/W)``, ``(°C)``, ``(%)``,
#: ``(1)`` for a ratio, with an SI prefix where it applies.
UNIT = re.compile(r"\((?:[mµunk]?(?:K/W|J/K|K|s|V|W|Hz|B|A|Ω)|°C|%|1)\)\s*$")


@pytest.fixture(scope="module")
def demo_run(tmp_path_factory):
    """The demo, with what every saved figure drew (:func:`_drawn`), by file path."""
    drawn: dict[str, dict] = {}
    save = Figure.savefig

    def spy(fig, fname, *args, **kwargs):
        out = save(fig, fname, *args, **kwargs)  # drawn: the tick labels are laid out
        name = getattr(fname, "name", fname)
        if isinstance(name, int):  # an atomic write's temporary file: .NAME.XXXX.tmp
            name = os.readlink(f"/proc/self/fd/{name}")
        path = Path(name)
        final = re.fullmatch(r"\.(.+)\.[^.]+\.tmp", path.name)
        drawn[str(path.with_name(final[1]) if final else path)] = _drawn(fig)
        return out

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(Figure, "savefig", spy)
        result = run_demo(tmp_path_factory.mktemp("demo") / "out", seed=3, quiet=True)
    return result, drawn


@pytest.fixture(scope="module")
def demo(demo_run):
    return demo_run[0]


def _numeric(text: str) -> bool:
    try:
        float(text.replace("−", "-").rstrip("*").strip())
    except ValueError:
        return False
    return True


def _drawn(fig) -> dict:
    """Axes of ``fig`` whose axis has no unit, and a fingerprint of each panel's data."""
    no_unit, panels = [], []
    for ax in fig.get_axes():
        if not ax.axison:
            continue
        title = ax.get_title(loc="left") or ax.get_title()
        for name in "xy":
            axis = getattr(ax, f"{name}axis")
            label = axis.get_label_text()
            ticks = [t.get_text() for t in axis.get_ticklabels() if t.get_text()]
            siblings = getattr(ax, f"get_shared_{name}_axes")().get_siblings(ax)
            if not label and (not ticks or not any(_numeric(t) for t in ticks) or any(
                    UNIT.search(getattr(o, f"get_{name}label")()) for o in siblings)):
                continue  # no scale shown, categories, or labelled once on a shared axis
            if not UNIT.search(label):
                no_unit.append(f"{name} axis {label!r} of the panel {title!r}")
        digest = hashlib.sha1()
        data = [np.column_stack([line.get_xdata(), line.get_ydata()]).astype(float)
                for line in ax.get_lines()]
        data += [np.asarray(c.get_offsets(), dtype=float) for c in ax.collections]
        data = [d for d in data if d.size > 2]
        for d in data:
            digest.update(d.tobytes())
        panels.append((title, digest.hexdigest() if data else ""))
    return {"no_unit": no_unit, "panels": panels}


class _Page(HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.ids: list[str] = []
        self.images: list[str] = []
        self.text: list[str] = []
        self.captions: list[str] = []
        self.tables: list[list[list[tuple[str, str]]]] = []  # rows of (tag, text) cells
        self._in: str | None = None

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if "id" in a:
            self.ids.append(a["id"])
        if tag == "img":
            self.images.append(a["src"])
        if tag == "table":
            self.tables.append([])
        elif tag == "tr":
            self.tables[-1].append([])
        elif tag in ("th", "td"):
            self.tables[-1][-1].append((tag, ""))
            self._in = tag
        elif tag == "figcaption":
            self.captions.append("")
            self._in = tag

    def handle_endtag(self, tag):
        if tag in ("th", "td", "figcaption"):
            self._in = None

    def handle_data(self, data):
        self.text.append(data)
        if self._in == "figcaption":
            self.captions[-1] += data
        elif self._in in ("th", "td"):
            tag, text = self.tables[-1][-1][-1]
            self.tables[-1][-1][-1] = (tag, text + data)


@pytest.mark.slow
def test_report_has_every_section_and_real_figures(demo):
    page = _Page()
    page.feed(demo.report.read_text())
    assert set(SECTION_IDS) <= set(page.ids)
    for needed in ("fig2_calibration", "fig7_fit", "fig8_impedance", "table1_mur880e",
                   "table2_delta", "diagnosis_before_after", "diagnosis_candidates",
                   "diode_law", "circuit_pwm"):
        assert any(needed in src for src in page.images), needed
    for src in page.images:
        path = demo.report.parent / src
        assert path.exists() and not src.startswith(("/", "http")), src  # offline, relative
        assert figure_is_nontrivial(path), src
    text = " ".join(page.text)
    assert re.search(r"Verdict: (named|approximate) — temperature-coefficient", text)
    assert ".SUBCKT ACTUATOR TJ TREF" in text  # the usage snippet and a netlist
    assert ".SUBCKT ACTUATOR_HEATER A K TJ TREF" in text  # the electrothermal part
    # Table 2 from the circuit deck beside the thermal-only deck (issue #46)
    circuit = re.search(r"agrees with the thermal-only deck within ([\d.]+) K", text)
    assert circuit and float(circuit[1]) < 0.02


@pytest.mark.slow
def test_report_figures_exist_say_what_they_show_and_have_units(demo_run):
    demo, drawn = demo_run
    page = _Page()
    page.feed(demo.report.read_text())
    assert len(page.captions) == len(page.images) > 0
    for src, caption in zip(page.images, page.captions, strict=True):
        path = (demo.report.parent / src).resolve()
        assert path.is_file(), src
        words = Path(src).stem.replace("_", " ").lower()
        assert len(caption.split()) >= 6 and words not in caption.lower(), caption
        assert ".png" not in caption, caption
        assert str(path) in drawn, f"{src} was not drawn by this run"
        assert drawn[str(path)]["no_unit"] == [], src
    panels = [(src, t, fp) for src in page.images
              for t, fp in drawn[str((demo.report.parent / src).resolve())]["panels"] if fp]
    seen: dict[str, tuple[str, str]] = {}
    for src, title, fp in panels:  # no panel drawn twice in the report
        assert fp not in seen, f"{src} {title!r} repeats {seen.get(fp)}"
        seen[fp] = (src, title)
    fig8 = drawn[str((demo.report.parent / "figures/fig8_impedance.png").resolve())]
    assert fig8["panels"] and "(K/W)" in demo.report.read_text()  # the family in K/W per duty


@pytest.mark.slow
def test_report_tables_have_units_in_their_headers(demo):
    page = _Page()
    page.feed(demo.report.read_text())
    assert len(page.tables) >= 8
    for table in page.tables:
        header, *rows = table
        assert all(tag == "th" for tag, _ in header) and rows
        for k, (_, head) in enumerate(header):
            cells = [row[k][1] for row in rows if row[k][1]]
            measured = cells and all(_numeric(c) for c in cells) and \
                not all(float(c.rstrip("*")).is_integer() for c in cells)
            assert not measured or UNIT.search(head), f"column {head!r} has no unit: {cells[:3]}"


@pytest.mark.slow
def test_demo_outputs_are_usable(demo):
    assert len(demo.libs) == 12 and all(p.read_text().count(".SUBCKT") == 1 for p in demo.libs)
    heater = ThermalModel.load(demo.out / "actuator_model.json").electrical
    assert heater is not None and heater.n == pytest.approx(1.75, abs=0.05)  # the bench's diode
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
    from spicethermal.cli.commands import demo as command

    assert "report" in command.HELP and Path(command.__file__).exists()


def _netlist(path: Path) -> list[str]:
    """A .lib's element lines (no comments: the header names the bundle's path)."""
    return [line for line in path.read_text().splitlines() if line and not line.startswith("*")]


@pytest.mark.slow
def test_report_numbers_agree_with_the_files_and_the_command_line(demo, tmp_path, capsys):
    """One number per thing: what the report says about the .lib files, the Cauer ladder, the
    calibration and Rth is what the folder holds and what the commands give for the same
    bundle and model."""
    from spicethermal.cli.main import main
    from spicethermal.io.bundle import Bundle

    html = demo.report.read_text()
    page = _Page()
    page.feed(html)
    text = " ".join(page.text)
    tables = {t[0][0][1]: t[1:] for t in page.tables}
    # every .lib written is counted and listed once (the summary said 6 of 9)
    libs = sorted((demo.out / "lib").glob("*.lib"))
    assert len(libs) == len(demo.libs) == 12
    assert f"{len(libs)} .lib files in" in demo.summary[4]
    assert sorted(row[0][1] for row in tables["file"]) == sorted(f"lib/{p.name}" for p in libs)
    # absolute temperatures, as the copy-paste deck reads V(TJ) and as `export` writes them
    for p in libs:
        assert "node voltages are temperatures in degC" in p.read_text(), p.name
    model = demo.out / "actuator_model.json"
    assert main(["export", str(model), "--topology", "cauer", "--name", "ACTUATOR", "-o",
                 str(tmp_path / "cli.lib")]) == 0
    assert _netlist(tmp_path / "cli.lib") == _netlist(demo.out / "lib" /
                                                      "actuator_ngspice_cauer.lib")
    # the Cauer table in the .lib's words and values: node TJ, N1...; C to node 0
    assert "each capacity to node 0, the thermal ground" in text and "node 0 is" not in text
    lines = _netlist(demo.out / "lib" / "actuator_ngspice_cauer.lib")
    r = {ln.split()[1]: float(ln.split()[3]) for ln in lines if ln.startswith("R")}
    c = {ln.split()[1]: float(ln.split()[3]) for ln in lines if ln.startswith("C")}
    assert [row[0][1] for row in tables["node"]] == list(r)
    for (_, node), (_, rv), (_, cv) in tables["node"]:
        assert float(rv) == pytest.approx(r[node], rel=1e-3)
        assert float(cv) == pytest.approx(c[node], rel=1e-3)
    # the fitted parameters are where the text says
    assert html.index("fitted parameters in the candidates table below") < \
        html.index("Candidates, best first")
    # the calibration: the law the text names is the bundle's, and the figure draws it
    cal = calibration_fit(Bundle.read(demo.out / "actuator"))
    assert ("with a quadratic" if cal.degree == 2 else "fitted linearly") in text
    assert f"K-factor {cal.k_factor_mv_per_k:.3f} mV/K" in text
    # Rth of section 2 is what `fit` gives for the same bundle
    assert main(["fit", str(demo.out / "actuator"), "-o", str(tmp_path / "m.json"), "-q"]) == 0
    rth = json.loads((tmp_path / "m.json").read_text())["rth_k_per_w"]
    stated = float(re.search(r"gives Rth = ([\d.]+) K/W \(eq\. 1\)", text)[1])
    assert stated == pytest.approx(rth, abs=0.005)
    capsys.readouterr()
