"""The one curve-source reader: kinds, options, errors, thinning, Zth as cooling."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from spicethermal.analysis.compare import compare
from spicethermal.core.errors import DataFormatError
from spicethermal.core.ladder import Foster
from spicethermal.identify.sources import read_source, thin
from spicethermal.io.bundle import CoolingTable, format_columns
from spicethermal.model import ThermalModel

LADDER = Foster.from_tau([0.3, 1.2], [1e-3, 0.5])
T = np.geomspace(1e-5, 20.0, 80)


def test_zth_csv_compares_as_the_cooling_curve_it_implies(tmp_path: Path) -> None:
    """Superposition: a step Zth(t) is the cooling Rth − Zth(t) at 1 W; the exact ladder
    then matches it to rounding."""
    p = tmp_path / "zth.csv"
    p.write_text(format_columns({"t_s": T, "zth_k_per_w": LADDER.zth(T)}))
    src = read_source(p)
    assert src.kind == "zth-csv" and not src.rth_held()
    bundle, notes = src.comparable()
    assert bundle.zth == () and len(bundle.cooling) == 1 and "implies at 1 W" in notes[0]
    result = compare(ThermalModel(LADDER), bundle)
    assert result.max_abs_k < 1e-3 * LADDER.rth  # the record ends before the steady state


def test_normalized_csv_needs_rth_and_holds_it(tmp_path: Path) -> None:
    p = tmp_path / "r.csv"
    p.write_text(format_columns({"t_s": T, "r": LADDER.r_norm(T)}))
    with pytest.raises(DataFormatError, match="give --rth"):
        read_source(p)
    src = read_source(p, rth_k_per_w=1.5)
    assert src.rth_held() and src.curve().rth_k_per_w == 1.5


def test_cooling_csv_with_raw_voltage_and_k_factor(tmp_path: Path) -> None:
    """v = 0.6 V − 2 mV/K (T − 25 °C) recorded at 2 W; the K-factor anchored at the end of
    the record (back at 25 °C) returns the ladder's Zth exactly (Tj at the cut given)."""
    tj = 25.0 + 2.0 * LADDER.cooling(T)
    p = tmp_path / "raw.csv"
    p.write_text(format_columns({"t_s": T, "v_tsp_v": 0.6 - 2e-3 * (tj - 25.0)}))
    with pytest.raises(DataFormatError, match="--calibration CSV"):
        read_source(p, tref_c=25.0)
    with pytest.raises(DataFormatError, match="--k-factor needs --ambient"):
        read_source(p, k_factor_mv_per_k=-2.0)
    src = read_source(p, k_factor_mv_per_k=-2.0, tref_c=25.0, power_w=2.0)
    assert any("anchored" in n for n in src.notes)
    curve = src.curve(mask_s=None, tj_steady_c=25.0 + 2.0 * LADDER.rth)
    # the end of the record is 1e-17 K off 25 degC: 20 s is 40 τ of the slow stage
    assert np.allclose(curve.zth_k_per_w, LADDER.zth(T), atol=1e-9)


def test_calibration_and_k_factor_exclude_each_other(tmp_path: Path) -> None:
    with pytest.raises(DataFormatError, match="not both"):
        read_source(tmp_path, calibration=tmp_path / "c.csv", k_factor_mv_per_k=-2.0)
    with pytest.raises(DataFormatError, match="no such file"):
        read_source(tmp_path / "missing.txt")


def test_thin_averages_in_log_bins_and_keeps_short_curves() -> None:
    t = np.geomspace(1e-6, 10.0, 5000)
    c = CoolingTable(t, 1.0, tj_c=30.0 - 0.5 * np.log10(t), tref_steady_c=25.0)
    th = thin(c, 20)
    assert th.t_s.size == 7 * 20 + 1
    # Tj linear in log t: a bin's mean Tj belongs to its mean log t, and its mean t lies
    # within the same bin, so the two agree to less than one bin width in log t
    lt = np.log10(th.t_s)
    assert np.all(np.abs((30.0 - th.tj_c) / 0.5 - lt) < 1.0 / 20)
    short = CoolingTable(t[:100], 1.0, tj_c=np.full(100, 30.0), tref_steady_c=25.0)
    assert thin(short) is short


def test_bundle_without_calibration_takes_one_from_the_command_line(tmp_path: Path) -> None:
    """A bundle of raw v_tsp_v and no calibration: the error names the options, and with
    --k-factor/--tref the record reads back as the ladder's Zth."""
    from spicethermal.io.bundle import Bundle

    t = np.geomspace(1e-5, 20.0, 80)
    tj = 25.0 + LADDER.cooling(t)
    raw = CoolingTable(t, 1.0, v_tsp_v=0.6 - 2e-3 * (tj - 25.0),
                       tj_steady_c=25.0 + LADDER.rth, file="cooling_1.csv")
    d = tmp_path / "raw"
    d.mkdir()
    (d / "cooling_1.csv").write_text(format_columns(raw.columns()))
    (d / "bundle.json").write_text('{"format": "spicethermal-bundle/1", "ambient_c": 25.0, '
                                   '"cooling": [{"file": '
                                   '"cooling_1.csv", "power_w": 1.0, "tj_steady_c": %r}]}'
                                   % (25.0 + LADDER.rth))
    with pytest.raises(DataFormatError, match="--calibration CSV or --k-factor"):
        Bundle.read(d)
    src = read_source(d, k_factor_mv_per_k=-2.0, tref_c=25.0)
    assert any("anchored" in n for n in src.notes)
    curve = src.curve(mask_s=None)
    assert np.allclose(curve.zth_k_per_w, LADDER.zth(t), atol=1e-9)
