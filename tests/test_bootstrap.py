"""Bootstrap uncertainty: bands that cover the truth, spreads that match the covariance."""

from __future__ import annotations

import json

import numpy as np
import pytest

from spicethermal.cli.main import main
from spicethermal.core.errors import DataFormatError
from spicethermal.core.ladder import Foster
from spicethermal.fit.bootstrap import Band, fit_bootstrap, resamples
from spicethermal.fit.ladder import fit_foster
from spicethermal.io.bundle import format_columns

TRUE = Foster.from_tau([0.3, 1.0, 2.0], [1e-3, 3e-2, 1.0])
T = np.logspace(-4, 1.3, 80)
SIGMA = 2e-3


def _noisy(seed: int) -> np.ndarray:
    return TRUE.zth(T) + np.random.default_rng(seed).normal(0.0, SIGMA, T.size)


def test_band_of_samples_is_their_central_interval() -> None:
    samples = np.arange(101.0)[:, None] * np.ones((1, 3))
    band = Band.of(np.arange(3.0), samples, level=0.9)
    assert np.allclose(band.lo, 5.0) and np.allclose(band.hi, 95.0)
    with pytest.raises(DataFormatError, match="at least 2"):
        next(resamples(np.zeros(3), np.ones(3), 1))


def test_fit_band_covers_the_true_curve_and_spreads_match_the_covariance() -> None:
    """Over 4 independent noisy data sets, the 95 % band holds the true Zth at most points,
    and the bootstrap spread of each R agrees with the fit's covariance within a factor 2."""
    covered = []
    for seed in range(4):
        res = fit_foster(T, _noisy(seed), rth_k_per_w=TRUE.rth)
        assert res.order == 3
        fb = fit_bootstrap(res, n=60, seed=seed)
        truth = TRUE.zth(T)
        covered.append(np.mean((fb.zth.lo <= truth) & (truth <= fb.zth.hi)))
        ratio = np.array(fb.u_r_k_per_w) / np.array(res.u_r_k_per_w)
        assert np.all((ratio > 0.5) & (ratio < 2.0)), ratio
    assert np.mean(covered) > 0.8


def test_commands_write_bands(tmp_path, capsys) -> None:
    zth = tmp_path / "zth.csv"
    zth.write_text(format_columns({"t_s": T, "zth_k_per_w": _noisy(7)}))
    model, fig = tmp_path / "m.json", tmp_path / "fit.png"
    assert main(["fit", str(zth), "-o", str(model), "--bootstrap", "20", "--plot",
                 str(fig)]) == 0
    assert "bootstrap (20 resamples)" in capsys.readouterr().out
    boot = json.loads(model.read_text())["provenance"]["fit"]["bootstrap"]
    assert boot["n"] == 20 and len(boot["u_r_k_per_w"]) == len(boot["u_tau_s"]) == 3
    assert fig.stat().st_size > 10000
    sfig = tmp_path / "spec.png"
    assert main(["spectrum", str(zth), "--json", "--bootstrap", "4", "--iterations", "300",
                 "-o", str(sfig)]) == 0
    spec = json.loads(capsys.readouterr().out)["bootstrap"]["spectrum"]
    assert len(spec["tau_s"]) == len(spec["r_density_k_per_w_lo"])
    assert np.all(np.array(spec["r_density_k_per_w_lo"]) <= spec["r_density_k_per_w_hi"])
    assert sfig.stat().st_size > 10000
    assert main(["structure", str(zth), "--json", "--bootstrap", "3", "--iterations",
                 "300"]) == 0
    band = json.loads(capsys.readouterr().out)["band"]
    assert np.all(np.array(band["c_j_per_k_lo"]) <= np.array(band["c_j_per_k_hi"]))
