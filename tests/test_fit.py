"""Ladder fitting: exact recovery, ΣR = Rth, automatic order on synthetic ladders, uncertainties,
bad input, and the ``spicethermal fit`` command."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest
from conftest import bench_script

from spicethermal.core.errors import DataFormatError, FitError
from spicethermal.core.ladder import Foster
from spicethermal.fit.ladder import DENSE_POINTS, FitResult, fit_foster, fit_model

#: The synthetic-case generator of the benchmark study (bench/bench_fit.py).
bench = bench_script("bench_fit")

LADDERS = [
    ([2.0], [1e-2]),
    ([0.5, 1.0, 2.0], [1e-3, 1e-2, 1e-1]),
    ([10.0, 30.0, 60.0, 46.0], [2e-4, 3e-3, 4e-2, 0.6]),  # the paper's Rth = 146 K/W
    ([0.01, 0.04, 0.17, 0.38, 0.29, 0.62], [3e-4, 2.5e-3, 1.2e-2, 5.4e-2, 0.25, 1.2]),
]


# ------------------------------------------------------------------------ exact recovery
@pytest.mark.parametrize("held", [False, True])
@pytest.mark.parametrize("r,tau", LADDERS)
def test_noise_free_data_are_recovered_exactly(r, tau, held):
    truth = Foster.from_tau(r, tau)
    t = np.logspace(-4, math.log10(30 * max(tau)), 61)
    res = fit_foster(t, truth.zth(t), rth_k_per_w=truth.rth if held else None)
    assert res.order == truth.order
    assert res.converged
    np.testing.assert_allclose(res.foster.r, truth.r, rtol=1e-6)
    np.testing.assert_allclose(res.foster.tau, truth.tau, rtol=1e-6)
    assert res.rms_k_per_w < 1e-9 * truth.rth


def test_given_order_is_fitted_even_if_the_data_want_more():
    truth = Foster.from_tau(*LADDERS[2])
    t = np.logspace(-4, 1, 51)
    res = fit_foster(t, truth.zth(t), order=2)
    assert res.order == 2 and res.criterion == "fixed"
    assert res.rms_k_per_w > 1e-3 * truth.rth  # an underfit, but the requested one


# ------------------------------------------------------------------------- ΣR = Rth
@pytest.mark.parametrize("order", ["auto", 3, 5])
def test_sum_of_r_equals_given_rth_exactly(order):
    case = bench.make_case(7)
    rth = case.truth.rth * 1.003  # even a slightly inconsistent Rth is held
    res = fit_foster(case.t_s, case.zth_k_per_w, order=order, rth_k_per_w=rth)
    assert res.rth_fixed
    assert abs(sum(res.foster.r) - rth) <= 4 * np.finfo(float).eps * rth
    assert all(r > 0 for r in res.foster.r) and all(c > 0 for c in res.foster.c)


# --------------------------------------------------------------- automatic order study
def test_automatic_order_on_30_random_ladders():
    """Deterministic subset of the 200-case study (bench/bench_fit.py has the full one)."""
    wrong = []
    for seed in range(30):
        case = bench.make_case(seed)
        res = fit_foster(case.t_s, case.zth_k_per_w)
        e_rth, e_zth, _ = bench.errors(case, res.foster)
        assert e_rth <= 2e-3, f"seed {seed}: Rth off by {e_rth:.2%}"
        assert e_zth <= 5e-3, f"seed {seed}: Zth off by {e_zth:.2%} of Rth"
        if res.order != case.truth.order:
            wrong.append((seed, case.truth.order, res.order))
    assert len(wrong) <= 1, wrong  # ≥ 95 % in the long run; 30 cases allow one miss


def test_order_selection_rejects_split_and_negligible_stages():
    case = bench.make_case(3)
    res = fit_foster(case.t_s, case.zth_k_per_w)
    assert res.criterion == "BIC"
    values = res.criterion_values
    assert set(values) == {tr.order for tr in res.trials}
    accepted = {tr.order: tr.criterion_value for tr in res.trials if tr.accepted}
    assert res.order == min(accepted, key=accepted.get)
    assert any(not tr.accepted and tr.reason for tr in res.trials)  # higher orders refused
    tau = np.asarray(res.foster.tau)
    assert np.all(tau[1:] / tau[:-1] >= 2)
    assert min(res.foster.r) >= 2e-3 * res.rth_k_per_w


# ------------------------------------------------------------------------ uncertainties
@pytest.mark.parametrize("held", [False, True])
def test_uncertainties_match_the_scatter_of_repeated_fits(held):
    truth = Foster.from_tau([1.0, 3.0, 2.0], [1e-3, 2e-2, 0.3])
    t = np.logspace(-4, 1, 51)
    rng = np.random.default_rng(5)
    est, unc = [], []
    for _ in range(60):
        z = truth.zth(t) + rng.normal(0, 5e-3, t.size)
        res = fit_foster(t, z, order=3, rth_k_per_w=truth.rth if held else None)
        est.append(res.foster.r + res.foster.tau)
        unc.append(res.u_r_k_per_w + res.u_tau_s)
    spread = np.std(est, axis=0, ddof=1)
    reported = np.mean(unc, axis=0)
    np.testing.assert_allclose(reported, spread, rtol=0.35)
    if held:  # the constraint is in the covariance: the r's are anti-correlated
        assert np.all(np.std(np.sum(np.asarray(est)[:, :3], axis=1)) < 1e-12)


def test_sigma_weights_and_absolute_uncertainties():
    truth = Foster.from_tau([1.0, 2.0], [1e-3, 1e-1])
    t = np.logspace(-4, 1, 51)
    rng = np.random.default_rng(2)
    z = truth.zth(t) + rng.normal(0, 2e-3, t.size)
    a = fit_foster(t, z, sigma=2e-3)
    b = fit_foster(t, z, sigma=4e-3)
    assert a.order == b.order == 2
    np.testing.assert_allclose(a.foster.r, b.foster.r, rtol=1e-7)  # same weights up to scale
    np.testing.assert_allclose(np.array(b.u_r_k_per_w) / a.u_r_k_per_w, 2.0, rtol=1e-6)


# ------------------------------------------------------------------------------ dense data
def test_dense_data_are_binned_and_residuals_reported_at_every_point():
    truth = Foster.from_tau(*LADDERS[2])
    t = np.linspace(3e-4, 3.0, 10_000)
    rng = np.random.default_rng(4)
    z = truth.zth(t) + rng.normal(0, 1e-3 * truth.rth, t.size)
    res = fit_foster(t, z)
    assert t.size > DENSE_POINTS and res.resampled and res.n_fit_points < 400
    assert res.residuals.shape == t.shape
    assert res.order == 4
    tt = np.logspace(math.log10(3e-4), math.log10(3.0), 200)
    assert np.max(np.abs(res.foster.zth(tt) - truth.zth(tt))) < 2e-3 * truth.rth
    np.testing.assert_allclose(np.sqrt(np.mean(res.residuals**2)), 1e-3 * truth.rth, rtol=0.05)


# ------------------------------------------------------------------------------ result
def test_result_is_immutable_prints_and_serialises():
    truth = Foster.from_tau(*LADDERS[1])
    t = np.logspace(-4, 0, 41)
    res = fit_foster(t, truth.zth(t) + np.random.default_rng(0).normal(0, 1e-3, t.size))
    assert isinstance(res, FitResult)
    with pytest.raises(dataclasses.FrozenInstanceError):
        res.foster = truth
    with pytest.raises(ValueError):
        res.residuals[0] = 1.0
    t[0] = t[0]  # the caller's arrays stay writable: the result holds copies
    assert res.t_s is not t and res.t_s[0] == t[0]
    text = str(res)
    assert "stage" in text and "± u" in text and "BIC" in text
    assert len([ln for ln in text.splitlines() if ln.strip().startswith(("1 ", "2 ", "3 "))]) == 3
    data = json.loads(res.to_json())
    assert data["order"] == 3 and data["criterion"] == "BIC"
    assert [s["r_k_per_w"] for s in data["stages"]] == list(res.foster.r)
    assert data["stages"][0]["u_tau_s"] == res.u_tau_s[0]
    assert set(data["criterion_values"]) == {str(k) for k in res.criterion_values}


def test_fit_model_puts_the_report_in_the_provenance(tmp_path):
    from types import SimpleNamespace

    from spicethermal.model import ThermalModel

    truth = Foster.from_tau(*LADDERS[1])
    t = np.logspace(-4, 0, 41)
    curve = SimpleNamespace(t_s=t, zth_k_per_w=truth.zth(t), rth_k_per_w=truth.rth)
    model, res = fit_model(curve)
    assert model.ladder == res.foster
    loaded = ThermalModel.load(model.save(tmp_path / "m.json"))
    assert loaded.provenance["fit"]["order"] == 3
    assert loaded.provenance["fit"]["stages"][1]["tau_s"] == pytest.approx(1e-2, rel=1e-6)
    with pytest.raises(FitError, match="effect"):
        fit_model(curve, effects=["temperature-coefficient"])


# ----------------------------------------------------------------------------- bad input
T = np.logspace(-4, 0, 20)
Z = Foster.from_tau([1.0], [1e-2]).zth(T)


@pytest.mark.parametrize("t,z,kw,match", [
    (T, np.where(np.arange(20) == 4, np.nan, Z), {}, r"zth_k_per_w\[4\]"),
    (T[::-1], Z, {}, r"t_s\[1\].*increase"),
    (np.r_[T[:5], T[4:]], np.r_[Z[:5], Z[4:]], {}, r"t_s\[5\]"),
    (T - T[0], Z, {}, r"t_s\[0\].*positive"),
    (T, Z[:-1], {}, "19"),
    (T, Z, {"order": 0}, "order"),
    (T, Z, {"order": "three"}, "order"),
    (T, Z, {"rth_k_per_w": -1.0}, "rth_k_per_w"),
    (T, Z, {"sigma": 0.0}, "sigma"),
])
def test_bad_input_names_the_problem(t, z, kw, match):
    with pytest.raises(DataFormatError, match=match):
        fit_foster(t, z, **kw)


def test_no_acceptable_fit_raises_instead_of_returning_nonsense():
    t = np.logspace(-4, 1, 51)
    with pytest.raises(FitError, match="no acceptable ladder"):
        fit_foster(t, 3.0 * t)  # a ramp: no finite ladder, every order refused
    with pytest.raises(FitError, match="free parameters"):
        fit_foster(T[:6], Z[:6], order=4)


# ------------------------------------------------------------------------------ figures
def test_fig7_and_plot_functions(tmp_path):
    from spicethermal.viz.plots import fig7, new_figure, plot_fit, plot_ladder, plot_residuals

    truth = Foster.from_tau(*LADDERS[2])
    t = np.logspace(-4, 0.5, 46)
    res = fit_foster(t, truth.zth(t) + np.random.default_rng(1).normal(0, 0.1, t.size))
    path = fig7(res, tmp_path / "fig7.png")
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    fig = new_figure()
    ax = fig.add_subplot()
    assert plot_fit(res, ax=ax) is ax and ax.get_xscale() == "log"
    np.testing.assert_allclose(ax.lines[0].get_ydata(), res.zth_k_per_w)
    ax = plot_residuals(res)
    np.testing.assert_allclose(ax.lines[-1].get_ydata(), res.residuals)
    for lad in (res.foster, res.foster.to_cauer()):
        labels = [x.get_text() for x in plot_ladder(lad).texts]
        assert sum(lb.startswith("R") for lb in labels) == lad.order
        assert sum(lb.startswith("C") for lb in labels) == lad.order


# ---------------------------------------------------------------------------------- CLI
def _write_csv(path, columns, rows):
    path.write_text(",".join(columns) + "\n" + "".join(
        ",".join(f"{v:.10g}" for v in row) + "\n" for row in rows))
    return path


@pytest.fixture
def zth_csv(tmp_path):
    truth = Foster.from_tau(*LADDERS[2])
    t = np.logspace(-4, math.log10(4.5), 47)
    z = truth.zth(t) + np.random.default_rng(3).normal(0, 0.146, t.size)
    return _write_csv(tmp_path / "zth.csv", ["t_s", "zth_k_per_w"], zip(t, z, strict=True))


def test_cli_fit_writes_a_model(zth_csv, tmp_path, capsys):
    from spicethermal.cli.main import main
    from spicethermal.model import ThermalModel

    out = tmp_path / "model.json"
    assert main(["fit", str(zth_csv), "-o", str(out), "--rth", "146",
                 "--plot", str(tmp_path / "f.png")]) == 0
    printed = capsys.readouterr().out
    assert "order 4" in printed and "± u" in printed
    model = ThermalModel.load(out)
    assert model.ladder.order == 4 and model.rth == pytest.approx(146.0, rel=1e-14)
    fit = model.provenance["fit"]
    assert fit["criterion"] == "BIC" and len(fit["stages"]) == 4
    assert all(s["u_r_k_per_w"] > 0 and s["u_tau_s"] > 0 for s in fit["stages"])
    assert (tmp_path / "f.png").stat().st_size > 10_000
    assert main(["fit", str(zth_csv), "-o", str(out), "--order", "2", "-q",
                 "--topology", "cauer"]) == 0
    model = ThermalModel.load(out)
    assert model.ladder.topology == "cauer" and model.ladder.order == 2


def test_cli_fit_normalized_csv_and_bundle(tmp_path):
    from spicethermal.cli.main import main
    from spicethermal.core.synthetic import synthetic_cooling
    from spicethermal.io.bundle import Bundle, CoolingTable
    from spicethermal.model import ThermalModel

    truth = Foster.from_tau([0.5, 1.0], [1e-3, 1e-1])
    t = np.logspace(-4, 1, 51)
    csv = _write_csv(tmp_path / "r.csv", ["t_s", "r"], zip(t, truth.r_norm(t), strict=True))
    assert main(["fit", str(csv), "-o", str(tmp_path / "a.json"), "--rth", "1.5", "-q"]) == 0
    assert ThermalModel.load(tmp_path / "a.json").ladder.order == 2

    tc, tj = synthetic_cooling(truth, 10.0, np.geomspace(1e-4, 10, 200), ambient_c=25.0)
    bundle = Bundle(reference="case", cooling=(CoolingTable(
        t_s=tc, tj_c=tj, power_w=10.0, tj_steady_c=40.0, tref_steady_c=25.0),))
    path = bundle.write(tmp_path / "run")
    assert main(["fit", str(path), "-o", str(tmp_path / "b.json"), "-q"]) == 0
    model = ThermalModel.load(tmp_path / "b.json")
    assert model.reference == "case" and model.rth == pytest.approx(1.5, rel=1e-12)
    np.testing.assert_allclose(model.ladder.zth(t), truth.zth(t), atol=2e-4 * truth.rth)


@pytest.mark.parametrize("body,message", [
    ("t_s,temp_c\n1e-4,1\n1e-3,2\n1e-2,3\n", "missing column zth_k_per_w"),
    ("t_s,zth_k_per_w\n1e-4,1\n1e-3,nan\n1e-2,3\n", "row 3, column zth_k_per_w"),
    ("t_s,zth_k_per_w\n1e-4,1\n1e-2,2\n1e-3,3\n", "row 4, column t_s"),
    ("t_s,r\n1e-4,0.1\n1e-3,0.5\n1e-2,0.9\n", "--rth"),
])
def test_cli_fit_bad_input_exits_2_with_one_line(tmp_path, capsys, body, message):
    from spicethermal.cli.main import main

    src = tmp_path / "bad.csv"
    src.write_text(body)
    out = tmp_path / "never.json"
    assert main(["fit", str(src), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1 and "Traceback" not in err
    assert not out.exists()


def test_cli_fit_effects_are_checked(zth_csv, tmp_path, capsys):
    from spicethermal.cli.main import main

    out = str(tmp_path / "m.json")
    assert main(["fit", str(zth_csv), "-o", out, "--effect", "no-such-effect"]) == 2
    assert "known effects" in capsys.readouterr().err
    assert main(["fit", str(zth_csv), "-o", out, "--effect", "temperature-coefficient"]) == 2
    assert "needs a bundle directory" in capsys.readouterr().err
