"""Datasheet-style outputs: Foster table CSV, duty-cycle Zth family CSV, early-time figure."""

from __future__ import annotations

import numpy as np
import pytest

from spicethermal.cli.main import main
from spicethermal.core.ladder import Foster
from spicethermal.core.synthetic import synthetic_cooling
from spicethermal.engines.pwm import steady_state
from spicethermal.io.bundle import Bundle, CoolingTable, format_columns, read_columns
from spicethermal.io.datasheet import read_foster_table
from spicethermal.model import ThermalModel

LADDER = Foster.from_tau([0.4, 1.1, 2.5], [2e-4, 2e-2, 1.5])


def test_duty_family_csv_is_the_pwm_peak_per_watt(tmp_path, capsys) -> None:
    """Each column is the periodic-steady-state peak per watt of pulses of width t at duty D,
    checked against the independent PWM solver."""
    model = tmp_path / "m.json"
    ThermalModel(LADDER).save(model)
    assert main(["curves", str(model), "-o", str(tmp_path / "fig8.csv"), "--duty", "0.1,0.5"]) == 0
    cols = read_columns(tmp_path / "fig8.csv", ["t_s", "zth_k_per_w_d0.1", "zth_k_per_w_d0.5"])
    for d in (0.1, 0.5):
        for t, z in list(zip(cols["t_s"], cols[f"zth_k_per_w_d{d:g}"], strict=True))[::7]:
            peak = steady_state(LADDER, 1.0, d / t, d).peak_k  # width t: period t / D
            assert z == pytest.approx(peak, rel=1e-9)
    assert str(tmp_path / "fig8.csv") in capsys.readouterr().out


def test_fit_writes_the_foster_table_and_the_early_time_figure(tmp_path) -> None:
    t, tj = synthetic_cooling(LADDER, 2.0, np.geomspace(1e-6, 30.0, 500), transient_s=5e-5,
                              ambient_c=25.0)
    bundle = Bundle(ambient_c=25.0, cooling=(CoolingTable(t, 2.0, tj_c=tj,
                                                          tref_steady_c=25.0),)).write(
        tmp_path / "b")
    table, fig = tmp_path / "foster.csv", tmp_path / "early.png"
    assert main(["fit", str(bundle), "-o", str(tmp_path / "m.json"), "--foster-table",
                 str(table), "--early-plot", str(fig),
                 "-q"]) == 0
    foster = read_foster_table(table)
    cols = read_columns(table, ["r_k_per_w", "u_r_k_per_w", "tau_s", "u_tau_s"])
    assert np.all(cols["u_r_k_per_w"] > 0) and np.all(cols["u_tau_s"] > 0)
    assert foster.rth == pytest.approx(LADDER.rth, rel=0.02)
    assert fig.stat().st_size > 10000
    # a Zth table has no early-time correction to draw
    zth = tmp_path / "zth.csv"
    tz = np.geomspace(1e-5, 10, 50)
    zth.write_text(format_columns({"t_s": tz, "zth_k_per_w": LADDER.zth(tz)}))
    assert main(["fit", str(zth), "-o", str(tmp_path / "z.json"), "--early-plot",
                 str(tmp_path / "x.png")]) == 2
