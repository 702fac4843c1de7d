"""Long records: a vectorised CSV pass that reads as the careful one, and cooling curves
compared as means over log-time bins."""

from __future__ import annotations

import numpy as np
import pytest

from spicethermal.analysis.compare import (
    MAX_COOLING_POINTS,
    compare,
    cooling_rise_k,
    log_bin_means,
)
from spicethermal.core.errors import DataFormatError
from spicethermal.io.bundle import Bundle, CoolingTable, parse_columns
from spicethermal.model import ThermalModel


def _csv(n: int, comment: bool = False) -> str:
    t = np.linspace(1e-4, 10.0, n)
    rows = [f"{a:.9g},{25 + 3 * np.exp(-a):.9g}" for a in t]
    if comment:
        rows[n // 2] += "  # a remark"
    return "# cooling\nt_s,tj_c\n" + "\n".join(rows) + "\n"


def test_vectorised_parse_reads_as_the_per_field_parse():
    fast = parse_columns(_csv(3000), ["t_s", "tj_c"])
    slow = parse_columns(_csv(3000, comment=True), ["t_s", "tj_c"])  # the comment: per field
    for col in ("t_s", "tj_c"):
        np.testing.assert_array_equal(fast[col], slow[col])
    np.testing.assert_array_equal(fast.rows, slow.rows)
    assert fast.rows[0] == 3 and fast.rows[-1] == 3002


@pytest.mark.parametrize("bad, message", [("x1.5", "malformed number"), ("inf", "not a finite"),
                                          ("", "empty field")])
def test_a_bad_field_in_a_long_file_is_named_by_row_and_column(bad, message):
    lines = _csv(3000).splitlines()
    lines[1500] = lines[1500].split(",")[0] + "," + bad
    with pytest.raises(DataFormatError, match=rf"row 1501.*tj_c.*{message}|line 1501.*{message}"):
        parse_columns("\n".join(lines), ["t_s", "tj_c"], label="c.csv")


def test_log_bin_means_average_exactly():
    t = np.array([0.0, 1.0, 1.2, 1.4, 100.0])
    tb, yb = log_bin_means(t, 2 * t + 1, per_decade=5)
    np.testing.assert_allclose(tb, [0.0, 1.2, 100.0])
    np.testing.assert_allclose(yb, 2 * tb + 1)  # linear in t: the bin mean is exact


def test_long_cooling_curve_is_compared_in_log_bins(actuator):
    model = ThermalModel(actuator)
    t = np.linspace(1e-4, 100.0, 20 * MAX_COOLING_POINTS)
    rng = np.random.default_rng(1)
    noise = rng.normal(0.0, 0.05, t.size)
    tj = 25.0 + cooling_rise_k(model, 0.094, t) + noise
    bundle = Bundle(device="long", ambient_c=25.0,
                    cooling=(CoolingTable(t, 0.094, tj_c=tj, tref_steady_c=25.0),))
    points = compare(model, bundle).points
    assert len(points) < 800  # 6 decades at 100 bins per decade, empty bins dropped
    times = [p.at["t_s"] for p in points]
    assert times == sorted(times) and times[0] < 2e-3 and times[-1] > 90
    # each residual is the mean noise of its bin: at most a few σ/√n, far below one sample's
    resid = np.array([p.residual_k for p in points])
    _, counts = np.unique(np.floor(np.log10(t / t[0]) * 100 + 1e-9), return_counts=True)
    assert np.all(np.abs(resid) < 5 * 0.05 / np.sqrt(counts) + 1e-9)
