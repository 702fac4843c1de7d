"""Relative (log-domain) weighting: every decade of a datasheet or vendor curve counts."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from spicethermal.cli.main import main
from spicethermal.core.errors import DataFormatError
from spicethermal.core.ladder import Cauer, Foster
from spicethermal.fit.ladder import fit_foster
from spicethermal.io.bundle import read_columns

DATA = Path(__file__).resolve().parent / "data"
#: Infineon OptiMOS 5 80 V typical junction-to-case Cauer ladders (R in K/W, C in J/K), see
#: tests/data/README.md.
VENDOR = {
    "BSC021N08NS5": ([2.24e-3, 24.39e-3, 30.85e-3, 97.77e-3, 200.97e-3],
                     [203.543e-6, 467.306e-6, 1.124e-3, 2.576e-3, 56.903e-3]),
    "BSC037N08NS5": ([4.57e-3, 48.82e-3, 61.62e-3, 199.21e-3, 304.48e-3],
                     [99.892e-6, 233.503e-6, 565.178e-6, 1.264e-3, 31.897e-3]),
}


def _digitized(z: np.ndarray, digits: int) -> np.ndarray:
    """Values read off a log-log datasheet plot: ``digits`` significant digits."""
    e = np.floor(np.log10(z))
    return np.round(z / 10**e, digits - 1) * 10**e


def test_nds332p_datasheet_curve_within_5_percent_everywhere(tmp_path) -> None:
    """The onsemi NDS332P curve (100 us .. 216 s): the absolute fit misses the early decades
    (28 % at 0.1 ms, smallest τ 4.7 ms); the relative fit holds every point within 5 %."""
    cols = read_columns(DATA / "nds332p_zth.csv", ["t_s", "r"])
    t, z = cols["t_s"], cols["r"] * 250.0
    bad = fit_foster(t, z, weighting="absolute")
    assert np.max(np.abs(bad.foster.zth(t) / z - 1)) > 0.2
    model = tmp_path / "nds332p.json"
    assert main(["fit", str(DATA / "nds332p_zth.csv"), "--rth", "250", "-o", str(model),
                 "-q"]) == 0
    doc = json.loads(model.read_text())
    f = Foster([s["r_k_per_w"] for s in doc["stages"]],
               [s["c_j_per_k"] for s in doc["stages"]])
    assert f.rth == pytest.approx(250.0, rel=1e-12)
    assert np.max(np.abs(f.zth(t) / z - 1)) < 0.05
    assert min(f.tau) < 1e-3  # a stage for the first decade
    assert doc["provenance"]["fit"]["weighting"].startswith("relative")


@pytest.mark.parametrize("name", sorted(VENDOR))
def test_vendor_curve_read_off_a_plot(name) -> None:
    """A vendor Zth curve (1 us .. 100 s) read to 2 significant digits: the relative fit stays
    within 1 % of Rth everywhere and 3 % of Zth from 1 us on; the absolute fit drops the
    smallest stages and misses the first decades by far more."""
    true = Cauer(*VENDOR[name]).to_foster()
    t = np.logspace(-6, 2, 81)
    z = _digitized(true.zth(t), 2)
    for weighting in ("relative", "absolute"):
        res = fit_foster(t, z, rth_k_per_w=true.rth, weighting=weighting)
        err = res.foster.zth(t) - true.zth(t)
        rel = np.max(np.abs(err / true.zth(t)))
        if weighting == "relative":
            assert np.max(np.abs(err)) < 0.01 * true.rth and rel < 0.03
        else:
            assert rel > 0.1


def test_relative_weighting_recovers_a_ladder_exactly_and_checks_its_input() -> None:
    true = Foster.from_tau([0.01, 0.3, 2.0], [1e-5, 1e-3, 1.0])
    t = np.logspace(-6, 1, 50)
    res = fit_foster(t, true.zth(t), weighting="relative")
    assert res.order == 3
    assert np.allclose(res.foster.tau, true.tau, rtol=1e-6)
    with pytest.raises(DataFormatError, match="exclude each other"):
        fit_foster(t, true.zth(t), sigma=1e-3, weighting="relative")
    with pytest.raises(DataFormatError, match="weighting"):
        fit_foster(t, true.zth(t), weighting="log")
