"""Structure functions: exact Cauer at any order, recovery of a known layered ladder from
noisy Zth data, separation of two mountings (synthetic and the real MOSFET transients)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from conftest import DATA

from spicethermal.core.errors import DataFormatError
from spicethermal.core.ladder import Cauer, Foster
from spicethermal.identify.spectrum import time_constant_spectrum
from spicethermal.identify.structure import (
    StructureFunction,
    cauer_ladder,
    separation,
    structure_function,
)

MOSFET = DATA / "pyrth_mosfet"

#: The known heat path of the recovery test: die, die attach, base plate, heat sink
#: (r in K/W, c in J/K); its Foster time constants are 0.1 ms, 27 ms, 0.53 s and 31 s.
LAYERS = Cauer([0.1, 0.3, 0.5, 1.0], [0.001, 0.1, 1.0, 30.0])


# ------------------------------------------------------------------ exact Cauer ladder
def test_lanczos_cauer_equals_the_rational_continued_fraction():
    f = Foster.from_tau([0.3, 1.0, 0.2, 2.0, 0.5, 0.1, 1.5, 0.7, 0.05, 0.4, 3.0, 0.25, 0.6, 1.1],
                        np.logspace(-6, 2, 14))
    exact = f.to_cauer("rational")
    import spicethermal.core.ladder as ld

    assert f.order > ld.RATIONAL_MAX_ORDER  # the Lanczos path
    fast = cauer_ladder(f)
    assert np.allclose(fast.r, exact.r, rtol=1e-13, atol=0)
    assert np.allclose(fast.c, exact.c, rtol=1e-13, atol=0)


def test_lanczos_cauer_detects_lost_precision_and_retries(monkeypatch):
    import spicethermal.core.ladder as ld

    f = Foster.from_tau(np.linspace(1, 3, 20), np.logspace(-6, 2, 20))
    good = cauer_ladder(f)
    monkeypatch.setattr(ld, "_lanczos_digits", lambda ladder: 30)  # far too few digits
    again = cauer_ladder(f)
    assert np.allclose(again.r, good.r, rtol=1e-9) and np.allclose(again.c, good.c, rtol=1e-9)


def test_lanczos_cauer_round_trips_at_order_20():
    f = Foster.from_tau(np.linspace(1, 3, 20), np.logspace(-6, 2, 20))
    back = cauer_ladder(f).to_foster()
    assert np.allclose(back.r, f.r, rtol=1e-13) and np.allclose(back.tau, f.tau, rtol=1e-13)


def test_cumulative_and_differential_of_a_known_ladder():
    sf = StructureFunction.from_ladder(Cauer([1.0, 2.0, 4.0], [0.5, 1.5, 6.0]))
    assert sf.r_k_per_w.tolist() == [1.0, 3.0, 7.0]
    assert sf.c_j_per_k.tolist() == [0.5, 2.0, 8.0]
    r, k = sf.differential()
    assert r.tolist() == [2.0, 5.0] and k.tolist() == [0.75, 1.5]
    assert sf.c_at(3.0) == pytest.approx(2.0) and sf.r_at(8.0) == pytest.approx(7.0)
    assert sf.to_dict() == {"cumulative": {"r_k_per_w": [1.0, 3.0, 7.0],
                                           "c_j_per_k": [0.5, 2.0, 8.0]}}
    with pytest.raises(ValueError):
        sf.r_k_per_w[0] = 2.0
    with pytest.raises(AttributeError):
        sf.label = "x"  # type: ignore[misc]
    # a Foster input goes through the exact conversion: same structure function
    same = structure_function(sf.cauer.to_foster())
    assert np.allclose(same.r_k_per_w, sf.r_k_per_w) and np.allclose(same.c_j_per_k,
                                                                      sf.c_j_per_k)


# --------------------------------------------------- recovery of a known layered ladder
@pytest.mark.parametrize("seed", [1, 2, 3])
def test_identified_structure_function_matches_the_true_ladder(seed):
    """Known 4-layer Cauer ladder → Foster → Zth(t) at 40 points per decade from 1 µs to
    1000 s with 0.1 % (of Rth) Gaussian noise → spectrum → Foster (10 per decade) → Cauer.

    At equal ΣC, the identified ΣR matches the true ladder's within 2 % of Rth over the
    resolved ΣC range (:meth:`StructureFunction.resolved_c_range`, about 1e-3 .. 80-340 J/K
    here), except within a factor 2 in ΣC of the true staircase's corners (the corner
    itself is a jump of ΣR at one ΣC, which any method of finite resolution rounds off).
    Measured over 10 seeds (bench/bench_spectrum.py): at most 0.93 % of Rth. At the middle
    of each riser (geometric mean of its two ΣC levels) ΣR is within 2 % of the local ΣR, or
    0.5 % of Rth where the local ΣR is small (the die: 0.1 K/W, 5 % of Rth; measured at most
    1.6 % on the other risers and 4 % = 0.2 % of Rth on the die).
    """
    true = LAYERS.to_foster()
    t = np.logspace(-6, 3, 361)
    z = true.zth(t) + np.random.default_rng(seed).normal(0.0, 1e-3 * true.rth, t.size)
    sf = structure_function(time_constant_spectrum(t, z))
    ref = StructureFunction.from_ladder(LAYERS)
    c_true, r_true = ref.c_j_per_k, ref.r_k_per_w
    lo, hi = sf.resolved_c_range()
    assert lo < 2e-3 and hi > 50.0
    compared = 0
    for k in range(1, LAYERS.order):  # riser k: ΣR = r_true[k-1] for c_true[k-1] < ΣC < c_true[k]
        a, b = max(2 * c_true[k - 1], lo), min(c_true[k] / 2, hi)
        cc = np.geomspace(a, b, 60)
        assert np.max(np.abs(sf.r_at(cc) - r_true[k - 1])) < 0.02 * LAYERS.rth
        mid = np.sqrt(c_true[k - 1] * c_true[k])
        assert abs(float(sf.r_at(mid)) - r_true[k - 1]) < max(0.02 * r_true[k - 1],
                                                               0.005 * LAYERS.rth)
        compared += 1
    assert compared == 3
    assert sf.rth_k_per_w == pytest.approx(LAYERS.rth, rel=5e-3)


def test_separation_of_two_synthetic_mountings():
    """Same die and attach; a thin (0.3 K/W) or a thick (1.5 K/W) interface to the same heat
    sink. The structure functions part just after the shared 0.4 K/W, and well before the
    dry interface ends."""
    dry = Cauer([0.1, 0.3, 1.5, 1.0], [0.001, 0.1, 0.02, 30.0])
    wet = Cauer([0.1, 0.3, 0.3, 1.0], [0.001, 0.1, 0.02, 30.0])
    t = np.logspace(-6, 3, 361)
    sfs = [structure_function(time_constant_spectrum(t, lad.to_foster().zth(t)))
           for lad in (dry, wet)]
    sep = separation(*sfs)
    assert sep.r_k_per_w is not None and 0.4 <= sep.r_k_per_w <= 0.75
    assert "separate at" in str(sep)
    same = separation(sfs[0], sfs[0])
    assert same.r_k_per_w is None and same.max_difference_decades == 0.0
    with pytest.raises(DataFormatError, match="threshold"):
        separation(*sfs, threshold_decades=0.0)


# ------------------------------------------------------------------- real MOSFET data
@pytest.fixture(scope="module")
def mosfet():
    from spicethermal.identify.sources import read_source

    out = {}
    for name in ("dry", "tim"):
        curve = read_source(MOSFET / f"MOSFET_{name}.txt", calibration=MOSFET / "calibration.csv",
                                tref_c=25.0).curve()
        out[name] = (curve, structure_function(curve))
    return out


def test_mosfet_dry_and_paste_separate_after_the_die_and_package(mosfet):
    """The dry mounting has the larger Rth; the two structure functions coincide over the
    die and package and separate at the interface.

    "Die and package" is the heat path the first 10 ms explore (a silicon die of 0.3 mm
    takes about 1 ms, a 1 mm copper lead frame L²/α ≈ 10 ms); the two Zth curves agree
    there (checked: within 4 % in log-time bins up to 10 ms), so the separation must lie
    beyond Zth(10 ms). The Zth curves themselves part for good (ratio > 1.05 from then on)
    at t_part (~0.1 s); the structure functions, which resolve the path better, must part
    no later than the paste mounting's Zth(t_part) (+25 %).
    """
    (dry_c, dry), (tim_c, tim) = mosfet["dry"], mosfet["tim"]
    assert dry.rth_k_per_w > tim.rth_k_per_w * 2
    sep = separation(dry, tim)
    assert sep.r_k_per_w is not None
    # near the junction the two records wiggle apart and together again (see separation())
    assert sep.first_exceeds_r_k_per_w is not None
    assert sep.first_exceeds_r_k_per_w <= sep.r_k_per_w

    a = dry_c.resample_log(20, t_min=1e-4, t_max=50.0)
    b = tim_c.resample_log(20, t_min=1e-4, t_max=50.0)
    ratio = a.zth_k_per_w / b.zth_k_per_w
    assert np.all(np.abs(ratio[a.t_s <= 1e-2] - 1) < 0.04)
    t_part = a.t_s[int(np.flatnonzero(ratio <= 1.05)[-1]) + 1]
    assert 1e-2 < t_part < 1.0
    lo = max(float(dry_c.at(1e-2)), float(tim_c.at(1e-2)))
    hi = 1.25 * float(tim_c.at(t_part))
    assert lo < sep.r_k_per_w < hi, (lo, sep.r_k_per_w, hi)
    # beyond the separation the paste mounting reaches the heat sink's mass first
    r = np.linspace(sep.r_k_per_w + 0.5, tim.resolved_r_range()[1], 20)
    assert np.all(tim.c_at(r) > dry.c_at(r))


# ------------------------------------------------------------------------------- CLI
def test_cli_structure_json_one_and_two_sources(tmp_path, capsys):
    from spicethermal.cli.main import main

    paths = []
    for name, lad in (("dry", Cauer([0.1, 0.3, 1.5, 1.0], [0.001, 0.1, 0.02, 30.0])),
                      ("wet", Cauer([0.1, 0.3, 0.3, 1.0], [0.001, 0.1, 0.02, 30.0]))):
        t = np.logspace(-6, 3, 181)
        p = tmp_path / f"{name}.csv"
        p.write_text("t_s,zth_k_per_w\n" + "".join(
            f"{a:.17g},{b:.17g}\n" for a, b in zip(t, lad.to_foster().zth(t), strict=True)))
        paths.append(str(p))
    assert main(["structure", paths[0], "--json"]) == 0
    one = json.loads(capsys.readouterr().out)
    assert set(one) == {"cumulative"} and set(one["cumulative"]) == {"r_k_per_w", "c_j_per_k"}
    r, c = np.array(one["cumulative"]["r_k_per_w"]), np.array(one["cumulative"]["c_j_per_k"])
    assert np.all(np.diff(r) > 0) and np.all(np.diff(c) > 0)
    assert r[-1] == pytest.approx(2.9, rel=5e-3)

    fig = tmp_path / "sf.png"
    assert main(["structure", *paths, "--json", "--plot", str(fig)]) == 0
    two = json.loads(capsys.readouterr().out)
    assert isinstance(two, list) and [x["source"] for x in two] == paths
    assert two[0]["separation"] == two[1]["separation"]
    assert 0.4 <= two[0]["separation"]["r_k_per_w"] <= 0.75
    assert fig.stat().st_size > 10000

    assert main(["structure", *paths, paths[0]]) == 2
    assert "one or two" in capsys.readouterr().err
