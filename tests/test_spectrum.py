"""Time-constant spectrum (NID): closed forms, recovery of known ladders, real MOSFET data."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from conftest import DATA

from spicethermal.core.errors import DataFormatError
from spicethermal.core.ladder import Cauer, Foster
from spicethermal.core.synthetic import synthetic_cooling
from spicethermal.identify.spectrum import (
    Spectrum,
    kernel,
    log_derivative,
    time_constant_spectrum,
)

MOSFET = DATA / "pyrth_mosfet"


# ------------------------------------------------------------------------ closed forms
def test_kernel_is_the_log_time_derivative_of_one_stage_and_integrates_to_one():
    x = np.linspace(-40, 5, 200001)
    assert np.trapezoid(kernel(x), x) == pytest.approx(1.0, abs=1e-9)
    assert kernel(0.0) == pytest.approx(math.exp(-1.0), rel=1e-15)
    tau = 2e-3
    t = np.geomspace(1e-6, 1.0, 241)
    one = Foster.from_tau([1.0], [tau])
    d = log_derivative(t, one.zth(t))
    # 5-point Savitzky–Golay derivative on a 40-per-decade grid: within 0.3 % of the peak
    assert np.max(np.abs(d - kernel(np.log(t / tau)))) < 3e-3 * kernel(0.0)


@pytest.mark.parametrize("method", ["bayes", "nnls"])
def test_single_time_constant_is_recovered_within_the_resolution(method):
    tau = 3e-3
    t = np.geomspace(1e-6, 10, 281)
    s = time_constant_spectrum(t, Foster.from_tau([2.0], [tau]).zth(t), method=method)
    assert s.rth_k_per_w == pytest.approx(2.0, rel=1e-3)
    (peak,) = s.peaks_s()
    assert abs(math.log10(peak / tau)) < 0.5 * s.resolution_decades
    assert 0.0 < s.resolution_decades < 0.6
    # lumped into one stage: the same ladder
    f = s.to_foster(order=1)
    assert f.r[0] == pytest.approx(2.0, rel=1e-3)
    assert f.tau[0] == pytest.approx(tau, rel=0.02)


def test_bayes_resolution_sharpens_with_iterations():
    t = np.geomspace(1e-5, 10, 241)
    z = Foster.from_tau([1.0], [1e-2]).zth(t)
    res = [time_constant_spectrum(t, z, iterations=n).resolution_decades for n in (250, 1000, 4000)]
    assert res[0] > res[1] > res[2] > 0


def test_two_close_stages_a_decade_apart_are_resolved_and_lumped_back():
    true = Foster.from_tau([1.0, 2.0], [1e-3, 1e-2])
    t = np.geomspace(1e-6, 10, 281)
    s = time_constant_spectrum(t, true.zth(t))
    assert len(s.peaks_s()) == 2
    f = s.to_foster(order=2)
    assert np.allclose(f.r, true.r, rtol=0.01)
    assert np.allclose(np.log10(f.tau), np.log10(true.tau), atol=0.02)


def test_noisy_layered_ladder_reconstructs_zth_within_noise():
    """Four-layer Cauer ladder, 0.1 % noise: the spectrum's Foster ladder (any order) gives
    back Zth(t) within 0.5 % of Rth everywhere; ΣR is the curve's final value within the
    noise and every lumping keeps it."""
    true = Cauer([0.1, 0.3, 0.5, 1.0], [0.001, 0.1, 1.0, 30.0]).to_foster()
    t = np.logspace(-6, 3, 361)
    z = true.zth(t) + np.random.default_rng(3).normal(0, 1e-3 * true.rth, t.size)
    s = time_constant_spectrum(t, z)
    assert s.rth_k_per_w == pytest.approx(true.rth, rel=5e-3)
    for n in (5, 10, 20):
        f = s.to_foster(n)
        assert f.rth == pytest.approx(s.rth_k_per_w, rel=1e-12)
        assert np.max(np.abs(f.zth(t) - true.zth(t))) < 5e-3 * true.rth


def test_spectrum_is_immutable_and_validated():
    t = np.geomspace(1e-5, 1, 121)
    s = time_constant_spectrum(t, Foster.from_tau([1.0], [1e-3]).zth(t))
    with pytest.raises(AttributeError):
        s.method = "nnls"  # type: ignore[misc]
    with pytest.raises(ValueError):
        s.r_density_k_per_w[0] = 1.0
    with pytest.raises(DataFormatError, match="uniform"):
        Spectrum([1e-3, 1e-2, 1e0], [1, 1, 1], "bayes", 0.1, (1e-3, 1))
    with pytest.raises(DataFormatError, match=">= 0"):
        Spectrum([1e-3, 1e-2, 1e-1], [1, -1, 1], "bayes", 0.1, (1e-3, 1))
    with pytest.raises(DataFormatError, match="method"):
        time_constant_spectrum(t, t, method="fft")  # type: ignore[arg-type]
    with pytest.raises(DataFormatError, match="points_per_decade"):
        time_constant_spectrum(t, t, points_per_decade=2)
    with pytest.raises(DataFormatError, match="too short"):
        time_constant_spectrum([1e-3, 1.1e-3, 1.2e-3], [1, 2, 3])
    with pytest.raises(DataFormatError, match="order"):
        s.to_foster(order=0)
    d = s.to_dict()
    assert d["format"] == "spicethermal-spectrum/1" and len(d["tau_s"]) == s.tau_s.size


# ------------------------------------------------------------------- real MOSFET data
@pytest.fixture(scope="module")
def mosfet():
    from spicethermal.identify.sources import read_source

    cal = MOSFET / "calibration.csv"
    curves = {name: read_source(MOSFET / f"MOSFET_{name}.txt", calibration=cal,
                                tref_c=25.0).curve() for name in ("dry", "tim")}
    return {name: (c, time_constant_spectrum(c)) for name, c in curves.items()}


@pytest.mark.parametrize("name", ["dry", "tim"])
def test_mosfet_ladder_reproduces_measured_zth_within_1_percent_from_10_us(mosfet, name):
    """The real transients: Zth (after masking the electrical transient and the √t
    correction) against the spectrum's Foster ladder, at every sample from 10 µs on."""
    curve, spec = mosfet[name]
    assert curve.early is not None and curve.early.detected
    keep = curve.t_s >= 1e-5
    for ladder in (spec.to_foster(10), spec.to_foster(order=12)):
        err = ladder.zth(curve.t_s[keep]) - curve.zth_k_per_w[keep]
        assert np.max(np.abs(err)) < 0.01 * curve.rth_k_per_w
        assert ladder.rth == pytest.approx(curve.zth_k_per_w[-1], rel=2e-3)


def test_mosfet_spectra_differ_in_the_long_time_constants(mosfet):
    """The die and package (τ < 10 ms) hold about the same resistance in both mountings;
    the dry mounting's extra resistance sits at long time constants."""
    (_, dry), (_, tim) = mosfet["dry"], mosfet["tim"]
    assert dry.rth_k_per_w > 2 * tim.rth_k_per_w

    def below(s: Spectrum, tau: float) -> float:
        return float(s.r_k_per_w[s.tau_s <= tau].sum())

    assert below(dry, 1e-2) == pytest.approx(below(tim, 1e-2), rel=0.1)
    assert dry.rth_k_per_w - below(dry, 0.1) > 2 * (tim.rth_k_per_w - below(tim, 0.1))


# ------------------------------------------------------------------------------- CLI
def test_cli_spectrum_json_and_figure(tmp_path, capsys):
    from spicethermal.cli.main import main

    true = Foster.from_tau([1.0, 2.0], [1e-3, 1e-1])
    t = np.geomspace(1e-5, 10, 121)
    csv = tmp_path / "zth.csv"
    csv.write_text("t_s,zth_k_per_w\n" + "".join(f"{a:.17g},{b:.17g}\n" for a, b in
                                                 zip(t, true.zth(t), strict=True)))
    fig = tmp_path / "spec.png"
    model = tmp_path / "model.json"
    assert main(["spectrum", str(csv), "--json", "-o", str(fig), "--order", "2",
                 "--model", str(model)]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["method"] == "bayes" and out["rth_k_per_w"] == pytest.approx(3.0, rel=1e-3)
    assert np.allclose(out["foster"]["r_k_per_w"], [1.0, 2.0], rtol=0.01)
    assert fig.stat().st_size > 10000
    assert json.loads(model.read_text())["format"] == "spicethermal-model/3"


def test_cli_spectrum_bad_input_exits_2_with_one_line(tmp_path, capsys):
    from spicethermal.cli.main import main

    bad = tmp_path / "bad.txt"
    bad.write_text("no data here\n")
    assert main(["spectrum", str(bad)]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "DATA" in err
    assert main(["spectrum", str(tmp_path / "missing.csv")]) == 2
    assert "no such file" in capsys.readouterr().err


def test_pyrth_text_source_with_calibration_csv_and_power(tmp_path):
    """A PyRth-format file made from a known ladder: Zth comes back through the given
    calibration (V = 0.6 V − 2 mV/K · (T − 20 °C)) and power (2 W)."""
    from spicethermal.identify.sources import read_source

    ladder = Foster.from_tau([1.0, 3.0], [1e-3, 1e-1])
    t = np.geomspace(1e-6, 20.0, 700)
    tj = 25.0 + 2.0 * ladder.cooling(t)            # 2 W cut at t = 0, ambient 25 °C
    volts = 0.6 - 2e-3 * (tj - 20.0)
    src = tmp_path / "device.txt"
    src.write_text("DATA\n#Time [s]  Usens [V]\n" + "".join(
        f"{a:.9e} {b:.9e}\n" for a, b in zip(t, volts, strict=True)))
    cal = tmp_path / "cal.csv"
    cal.write_text("temp_c,v_tsp_v\n20,0.6\n40,0.56\n60,0.52\n")
    curve = read_source(src, calibration=cal, power_w=2.0).curve()
    assert curve.label == "device"
    # Tj at the cut is extrapolated by √t from the first samples (the importer has no
    # steady value); for this lumped ladder that overshoots by about 0.05 % of Rth
    assert curve.rth_k_per_w == pytest.approx(ladder.rth, rel=1e-3)
    offset = curve.rth_k_per_w - ladder.rth
    assert np.allclose(curve.zth_k_per_w, ladder.zth(curve.t_s) + offset, atol=1e-6)


def test_bundle_source(tmp_path, capsys):
    """A bundle directory with a cooling curve (electrical transient included, no steady
    junction temperature: Tj at the cut is extrapolated by √t) is read through the
    early-time correction; the spectrum holds the curve's Rth."""
    from spicethermal.cli.main import main
    from spicethermal.identify.sources import read_source
    from spicethermal.io.bundle import Bundle, CoolingTable

    ladder = Foster.from_tau([1.0, 3.0], [1e-3, 1e-1])
    t, tj = synthetic_cooling(ladder, 2.0, np.geomspace(1e-6, 20.0, 600), transient_s=3e-5)
    bundle = Bundle(device="test", reference="ambient", ambient_c=25.0, cooling=(
        CoolingTable(t, 2.0, tj_c=tj, tref_steady_c=25.0),))
    path = bundle.write(tmp_path / "run1")
    curve = read_source(path).curve()
    assert curve.label.startswith("run1") and curve.early is not None and curve.early.detected
    # √t is not this lumped ladder's early law: Tj at the cut comes out ~0.4 % high
    assert curve.rth_k_per_w == pytest.approx(4.0, rel=0.03)
    assert main(["spectrum", str(path), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["rth_k_per_w"] == pytest.approx(curve.rth_k_per_w, rel=2e-3)
    assert out["t_resolved_s"][0] == pytest.approx(curve.early.masked_s[1])
