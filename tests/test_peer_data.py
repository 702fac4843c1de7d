"""Two bugs found with a peer's database of datasheet Zth curves (issue #44, point 5):
``fit --rth`` below the curve's own plateau is refused with the reason; ``compare`` takes the
model's reference for a file that does not state one, and ``--reference``."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import DATA

from spicethermal.cli.main import main
from spicethermal.core.errors import DataFormatError
from spicethermal.core.ladder import Foster
from spicethermal.fit.ladder import check_rth
from spicethermal.model import ThermalModel

#: A datasheet-like junction-to-case curve: Rth 2 K/W.
CURVE = Foster.from_tau([0.2, 0.6, 1.2], [1e-4, 1e-2, 0.5])


def zth_csv(tmp_path, t, z, name="zth.csv"):
    path = tmp_path / name
    rows = "".join(f"{float(a)!r},{float(b)!r}\n" for a, b in zip(t, z, strict=True))
    path.write_text("t_s,zth_k_per_w\n" + rows)
    return path


@pytest.mark.parametrize("rth, ok", [(2.0, True), (2.5, True), (1.97, True), (1.9, False),
                                     (1.4, False)])
def test_fit_refuses_an_rth_below_the_datasheet_curves_plateau(tmp_path, capsys, rth, ok):
    t = np.logspace(-5, 1, 17)  # 17 digitized points, as the peer's curves
    csv = zth_csv(tmp_path, t, CURVE.zth(t))
    out = tmp_path / "m.json"
    code = main(["fit", str(csv), "--rth", str(rth), "-q", "-o", str(out)])
    err = capsys.readouterr().err
    if ok:
        assert code == 0 and out.exists()
        return
    assert code == 2 and not out.exists() and err.count("\n") == 1
    assert f"--rth {rth:g} K/W is below zth's own plateau: its Zth reaches 2 K/W at t = 10 s" in err
    assert "never exceeds its Rth" in err


def test_the_plateau_allows_for_the_noise_of_a_dense_curve():
    rng = np.random.default_rng(7)
    t = np.geomspace(1e-5, 10.0, 4000)
    z = CURVE.zth(t) + 0.02 * rng.standard_normal(t.size)  # 1 % of Rth
    check_rth(t, z, CURVE.rth)  # its noisy maximum is well above 2 K/W: not refused
    assert np.max(z) > 1.02 * CURVE.rth
    with pytest.raises(DataFormatError, match="below the curve's own plateau"):
        check_rth(t, z, 0.95 * CURVE.rth)


@pytest.fixture
def case_model(tmp_path):
    t = np.logspace(-5, 1, 40)
    csv = zth_csv(tmp_path, t, CURVE.zth(t))
    model = tmp_path / "m.json"
    assert main(["fit", str(csv), "--reference", "case", "-q", "-o", str(model)]) == 0
    assert ThermalModel.load(model).reference == "case"
    return csv, model


def test_compare_takes_the_models_reference_for_a_file_that_does_not_state_one(case_model,
                                                                              capsys):
    csv, model = case_model
    capsys.readouterr()
    assert main(["compare", str(model), str(csv)]) == 0
    err = capsys.readouterr().err
    assert "does not state its reference: the model's (case)" in err
    assert main(["compare", str(model), str(csv), "--reference", "case"]) == 0
    assert "does not state" not in capsys.readouterr().err
    assert main(["compare", str(model), str(csv), "--reference", "ambient"]) == 2
    err = capsys.readouterr().err
    assert err.count("error:") == 1 and err.endswith("\n") and "Traceback" not in err
    assert "measured against the ambient but the model's reference is case" in err


def test_a_bundle_states_its_reference_and_keeps_it(case_model, capsys):
    _, model = case_model
    bundle = DATA / "sample_bundle"  # measured to the ambient
    assert main(["compare", str(model), str(bundle), "--reference", "case"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert "the bundle states its reference, ambient; --reference case contradicts it" in err
    assert main(["compare", str(model), str(bundle)]) == 2
    assert "measured against the ambient but the model's reference is case" in \
        capsys.readouterr().err
