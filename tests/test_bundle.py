"""Bundles: round trip, atomic writing, and a clear message for every kind of bad input."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest

from spicethermal.core.errors import DataFormatError
from spicethermal.identify.readings import calibration_fit, cooling_tj_c
from spicethermal.io import bundle as bmod
from spicethermal.io.bundle import (
    Bundle,
    CalibrationTable,
    CoolingTable,
    KFactorLaw,
    PwmTable,
    ZthTable,
    read_columns,
)


def full_bundle() -> Bundle:
    t = np.geomspace(1e-5, 10, 31)
    return Bundle(
        device="MUR880E on heatsink", reference="case", ambient_c=24.5,
        calibration=CalibrationTable([25.0, 50.0, 75.0], [0.61, 0.56, 0.51]),
        cooling=(
            CoolingTable(t_s=t, tj_c=40 - np.sqrt(t), tref_c=25 + 0 * t, power_w=10.0,
                         tj_steady_c=40.0, tref_steady_c=25.0),
            CoolingTable(t_s=t, v_tsp_v=0.58 + 1e-3 * np.sqrt(t), power_w=5.0,
                         extra={"note": "raw TSP"}),
        ),
        pwm=PwmTable(freq_hz=[500, 1000, 25000], duty=[0.2, 0.5, 0.8],
                     tj_c=[27.2, 32.16, 37.7], power_w=0.094, row_power_w=[0.09, 0.094, 0.1],
                     sample_window_s=1e-4),
        zth=(ZthTable(t_s=[1e-5, 1e-4, 1e-3], r=[0.018, 0.06, 0.18], rth_k_per_w=1.51),
             ZthTable(t_s=[1e-3, 1e-2], zth_k_per_w=[0.3, 0.6])),
        extra={"operator": "lab 3", "bench": {"firmware": "1.0"}},
    )


def test_round_trip(tmp_path: Path) -> None:
    b = full_bundle()
    path = b.write(tmp_path / "b1")
    r = Bundle.read(path)
    assert r.device == b.device and r.reference == "case" and r.ambient_c == 24.5
    assert r.extra == b.extra
    np.testing.assert_array_equal(r.calibration.v_tsp_v, b.calibration.v_tsp_v)
    for x, y in zip(r.cooling, b.cooling, strict=True):
        for col in ("t_s", "tj_c", "v_tsp_v", "tref_c"):
            a1, a2 = getattr(x, col), getattr(y, col)
            assert (a1 is None) == (a2 is None)
            if a1 is not None:
                np.testing.assert_array_equal(a1, a2)  # exact: floats written with repr
        assert (x.power_w, x.tj_steady_c, x.tref_steady_c) == (
            y.power_w, y.tj_steady_c, y.tref_steady_c)
    assert r.cooling[1].extra == {"note": "raw TSP"}
    np.testing.assert_array_equal(r.pwm.powers_w, [0.09, 0.094, 0.1])
    assert r.pwm.sample_window_s == 1e-4 and r.pwm.power_w == 0.094
    assert r.zth[0].normalized and r.zth[0].rth_k_per_w == 1.51
    assert not r.zth[1].normalized
    # writing what was read gives the same manifest and the same files
    again = r.write(tmp_path / "b2")
    assert json.loads((again / "bundle.json").read_text()) == json.loads(
        (path / "bundle.json").read_text())
    for f in path.iterdir():
        assert (again / f.name).read_text() == f.read_text()


def test_arrays_are_immutable() -> None:
    b = full_bundle()
    with pytest.raises(ValueError):
        b.cooling[0].t_s[0] = 1.0
    with pytest.raises(AttributeError):
        b.device = "x"  # type: ignore[misc]


def test_cooling_tj_from_calibration() -> None:
    b = full_bundle()
    tj = cooling_tj_c(b, 1)
    # V = 0.66 - 0.002 T exactly on the calibration line
    np.testing.assert_allclose(tj, (0.66 - b.cooling[1].v_tsp_v) / 2e-3, rtol=1e-12)
    assert b.cooling_reference_c(1) == (None, 24.5)  # falls back to ambient_c


def test_write_is_atomic(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    calls = []
    real = bmod.format_columns

    def failing(*a, **k):
        calls.append(1)
        if len(calls) == 3:
            raise OSError("disk full")
        return real(*a, **k)

    monkeypatch.setattr(bmod, "format_columns", failing)
    with pytest.raises(OSError):
        full_bundle().write(tmp_path / "b")
    assert list(tmp_path.iterdir()) == []  # neither the bundle nor a temporary directory


def test_write_replaces_a_bundle_but_never_another_directory(tmp_path: Path) -> None:
    b = full_bundle()
    b.write(tmp_path / "b")
    Bundle(device="second").write(tmp_path / "b")
    assert Bundle.read(tmp_path / "b").device == "second"
    assert (tmp_path / "b" / "pwm.csv").exists()  # unlisted now, but a write deletes nothing
    assert sorted(p.name for p in tmp_path.iterdir()) == ["b"]
    other = tmp_path / "photos"
    other.mkdir()
    (other / "a.jpg").write_text("x")
    with pytest.raises(DataFormatError, match="not a bundle"):
        b.write(other)
    assert (other / "a.jpg").exists()


def _bundle(tmp_path: Path, files: dict[str, str], manifest: dict | None = None) -> Path:
    d = tmp_path / "bad"
    d.mkdir()
    doc = manifest or {"format": "spicethermal-bundle/1",
                       "cooling": [{"file": "cooling_1.csv", "power_w": 1.0,
                                    "tref_steady_c": 25.0}]}
    (d / "bundle.json").write_text(json.dumps(doc))
    for name, text in files.items():
        (d / name).write_text(text)
    return d


GOOD = "t_s,tj_c\n1e-4,40\n1e-3,39\n1e-2,37\n"

# (csv text, line, column, words in the message)
BAD_CSV = [
    ("t_s,temp\n1e-4,40\n", 1, None, "missing column tj_c or v_tsp_v"),
    ("time,tj_c\n1e-4,40\n", 1, None, "missing column t_s"),
    ("t_ms,tj_c\n0.1,40\n", 1, "t_ms", "wrong unit"),
    ("t_s,tj_k\n1e-4,313\n", 1, "tj_k", "wrong unit"),
    ("t_s,tj_c\n1e-4,40\n1e-3,nan\n", 3, "tj_c", "not a finite number"),
    ("t_s,tj_c\n1e-4,40\n1e-3,inf\n", 3, "tj_c", "not a finite number"),
    ("# a comment\nt_s,tj_c\n1e-4,40\n1e-5,39\n", 4, "t_s", "time goes backwards"),
    ("t_s,tj_c\n-1e-4,40\n1e-3,39\n", 2, "t_s", "negative time"),
    ("t_s,tj_c\n1e-4,40\n1e-3,39\n1e-3,38\n", 4, "t_s", "duplicate time"),
    ("t_s,tj_c\n1e-4,40\n1e-3,-300\n", 3, "tj_c", "below absolute zero"),
    ("t_s,tj_c\n1e-4,40\n1e-3,3 9\n", 3, "tj_c", "malformed number"),
    ("t_s,tj_c\n1e-4,40\n1e-3,1.2.3\n", 3, "tj_c", "malformed number"),
    ("t_s,tj_c\n1e-4,40\n1e-3,\n", 3, "tj_c", "empty field"),
    ("t_s,tj_c\n1e-4,40\n1e-3,39,1\n", 3, None, "3 fields, the header has 2"),
    ("", None, None, "file is empty"),
    ("# only a comment\n\n", None, None, "file is empty"),
    ("t_s,tj_c\n# no rows\n", None, None, "no data rows"),
    ("1e-4,40\n1e-3,39\n", 1, None, "must be a header"),
    ("t_s,tj_c,tref_c\n1e-4,40,25\n1e-3,39,-274\n", 3, "tref_c", "below absolute zero"),
]


@pytest.mark.parametrize(("text", "row", "column", "words"), BAD_CSV)
def test_bad_cooling_csv_names_file_row_column(tmp_path: Path, text, row, column, words) -> None:
    d = _bundle(tmp_path, {"cooling_1.csv": text})
    with pytest.raises(DataFormatError) as err:
        Bundle.read(d)
    msg = str(err.value)
    assert str(d / "cooling_1.csv") in msg
    assert words in msg
    if row is not None:
        assert f"row {row}" in msg
    if column is not None:
        assert f"column {column}" in msg


BAD_PWM = [
    ("freq_hz,duty,tj_c,power_w\n500,0.2,27,0.1\n1000,0.2,28,0\n", 3, "power_w", "> 0"),
    ("freq_hz,duty,tj_c\n500,1.2,27\n", 2, "duty", "[0, 1]"),
    ("freq_hz,duty,tj_c\n-5,0.2,27\n", 2, "freq_hz", "> 0"),
    ("freq_khz,duty,tj_c\n0.5,0.2,27\n", 1, "freq_khz", "wrong unit"),
    ("freq_hz,duty,tj_c,power_mw\n500,0.2,27,90\n", 1, "power_mw", "wrong unit"),
]


@pytest.mark.parametrize(("text", "row", "column", "words"), BAD_PWM)
def test_bad_pwm_csv(tmp_path: Path, text, row, column, words) -> None:
    d = _bundle(tmp_path, {"pwm.csv": text},
                {"format": "spicethermal-bundle/1", "pwm": {"file": "pwm.csv", "power_w": 0.1}})
    with pytest.raises(DataFormatError) as err:
        Bundle.read(d)
    msg = str(err.value)
    assert str(d / "pwm.csv") in msg and f"row {row}" in msg and f"column {column}" in msg
    assert words in msg


BAD_MANIFEST = [
    ({"format": "spicethermal-bundle/4"}, "key format"),
    ({"device": "no format"}, "key format"),
    ({"format": "spicethermal-bundle/1", "cooling": [{"file": "cooling_1.csv", "power_w": 0}]},
     "key cooling[0].power_w: 0.0 must be > 0"),
    ({"format": "spicethermal-bundle/1", "cooling": [{"file": "cooling_1.csv"}]},
     "key cooling[0].power_w: missing"),
    ({"format": "spicethermal-bundle/1", "cooling": [{"file": "cooling_1.csv",
                                                      "power_w": "ten"}]},
     "key cooling[0].power_w: 'ten' is not a number"),
    ({"format": "spicethermal-bundle/1", "cooling": [{"file": "cooling_1.csv", "power_w": 1,
                                                      "tj_steady_c": -280}]},
     "key cooling[0].tj_steady_c: -280.0 degC is below absolute zero"),
    ({"format": "spicethermal-bundle/1", "cooling": [{"power_w": 1}]},
     "key cooling[0].file: missing"),
    ({"format": "spicethermal-bundle/1", "cooling": [{"file": "nope.csv", "power_w": 1}]},
     "nope.csv: file not found"),
    ({"format": "spicethermal-bundle/1", "reference": "junction"}, "key reference"),
    ({"format": "spicethermal-bundle/1", "zth": [{"file": "zth.csv", "normalized": True}]},
     "key zth[0].normalized: True but zth.csv has no column r"),
    ({"format": "spicethermal-bundle/1", "pwm": {"file": "cooling_1.csv"}}, "missing column"),
]


@pytest.mark.parametrize(("manifest", "words"), BAD_MANIFEST)
def test_bad_manifest(tmp_path: Path, manifest, words) -> None:
    d = _bundle(tmp_path, {"cooling_1.csv": GOOD, "zth.csv": "t_s,zth_k_per_w\n1,2\n"},
                manifest)
    with pytest.raises(DataFormatError) as err:
        Bundle.read(d)
    assert words in str(err.value)


def test_raw_voltage_needs_a_calibration(tmp_path: Path) -> None:
    d = _bundle(tmp_path, {"cooling_1.csv": "t_s,v_tsp_v\n1e-4,0.5\n1e-3,0.51\n"})
    with pytest.raises(DataFormatError, match=r"key cooling\[0\]: .*no calibration"):
        Bundle.read(d)


def test_unknown_keys_and_columns_are_tolerated(tmp_path: Path) -> None:
    d = _bundle(tmp_path, {"cooling_1.csv": "t_s,tj_c,comment_id\n1e-4,40,1\n1e-3,39,2\n"},
                {"format": "spicethermal-bundle/1", "future_key": [1, 2],
                 "cooling": [{"file": "cooling_1.csv", "power_w": 2.0, "humidity": 0.4}]})
    b = Bundle.read(d)
    assert b.extra == {"future_key": [1, 2]} and b.cooling[0].extra == {"humidity": 0.4}
    np.testing.assert_array_equal(b.cooling[0].tj_c, [40, 39])


def test_not_a_bundle(tmp_path: Path) -> None:
    with pytest.raises(DataFormatError, match="no bundle.json"):
        Bundle.read(tmp_path)
    (tmp_path / "bundle.json").write_text("{not json")
    with pytest.raises(DataFormatError, match="row 1: not valid JSON"):
        Bundle.read(tmp_path)


def test_in_memory_tables_are_validated() -> None:
    dup = r"row 3, column t_s: duplicate time 0.2 \(also on row 2\)"
    with pytest.raises(DataFormatError, match=dup):
        CoolingTable(t_s=[0.1, 0.2, 0.2], tj_c=[3, 2, 1], power_w=1.0, file="c.csv")
    with pytest.raises(DataFormatError, match="power_w: -1.0 must be > 0"):
        CoolingTable(t_s=[0.1, 0.2], tj_c=[3, 2], power_w=-1.0)
    with pytest.raises(DataFormatError, match="3 values, expected 2"):
        CoolingTable(t_s=[0.1, 0.2], tj_c=[3, 2, 1], power_w=1.0)
    with pytest.raises(DataFormatError, match="exactly one of the columns"):
        ZthTable(t_s=[1.0], zth_k_per_w=[1.0], r=[0.5])
    with pytest.raises(DataFormatError, match="two sections use the file"):
        Bundle(cooling=(CoolingTable([1.0], 1.0, tj_c=[30], file="a.csv"),
                        CoolingTable([1.0], 1.0, tj_c=[30], file="a.csv")))


def test_read_columns_comments_and_rows(tmp_path: Path) -> None:
    p = tmp_path / "z.csv"
    p.write_text("# datasheet\n t_s , r # trailing comment\n\n1e-3,0.18\n# mid\n1e-2,0.39\n")
    cols = read_columns(p, ["t_s", "r"])
    assert cols.rows.tolist() == [4, 6]
    np.testing.assert_array_equal(cols["r"], [0.18, 0.39])


# ------------------------------------------------------------------------ calibration kinds
RAW = "t_s,v_tsp_v\n1e-4,0.55\n1e-3,0.56\n1e-2,0.58\n"
CAL = "temp_c,v_tsp_v\n25,2.6127\n40,2.5899\n55,2.5670\n"
V2 = "spicethermal-bundle/2"


def _kind_bundle(tmp_path: Path, calibration: dict, fmt: str = V2) -> Path:
    return _bundle(tmp_path, {"cooling_1.csv": RAW, "calibration.csv": CAL},
                   {"format": fmt, "ambient_c": 25.0, "calibration": calibration,
                    "cooling": [{"file": "cooling_1.csv", "power_w": 1.0}]})


def test_k_factor_bundle_converts_and_round_trips(tmp_path: Path) -> None:
    d = _kind_bundle(tmp_path, {"kind": "k-factor", "k_mv_per_k": -2.0, "v_ref_v": 0.6,
                                "t_ref_c": 25.0})
    b = Bundle.read(d)
    assert isinstance(b.calibration, KFactorLaw) and b.calibration.kind == "k-factor"
    assert np.allclose(cooling_tj_c(b, 0), 25.0 + (np.array([0.55, 0.56, 0.58]) - 0.6) / -2e-3)
    again = Bundle.read(b.write(tmp_path / "copy"))
    assert again.calibration == b.calibration and not (tmp_path / "copy" /
                                                      "calibration.csv").exists()
    assert json.loads((tmp_path / "copy" / "bundle.json").read_text())["format"] == V2


def test_polynomial_bundle_keeps_coefficients_and_residuals(tmp_path: Path) -> None:
    d = _kind_bundle(tmp_path, {"kind": "polynomial", "file": "calibration.csv",
                                "coefficients_v": [2.6505, -1.5098e-3]})
    b = Bundle.read(d)
    cal = calibration_fit(b)
    assert cal.coefficients == (2.6505, -1.5098e-3) and cal.kind == "polynomial"
    expect = (np.array([2.6127, 2.5899, 2.5670]) - (2.6505 - 1.5098e-3 * np.array([25, 40, 55])))
    assert np.allclose(cal.residuals_mv, expect * 1e3, atol=1e-9)
    again = Bundle.read(b.write(tmp_path / "copy"))
    assert calibration_fit(again).coefficients == cal.coefficients


def test_table_bundles_are_still_written_as_version_1(tmp_path: Path) -> None:
    b = Bundle(calibration=CalibrationTable([25, 75], [0.6, 0.5]))
    doc = json.loads((b.write(tmp_path / "t") / "bundle.json").read_text())
    assert doc["format"] == "spicethermal-bundle/1" and "kind" not in doc["calibration"]


@pytest.mark.parametrize(("calibration", "fmt", "words"), [
    ({"kind": "k-factor", "k_mv_per_k": -2, "v_ref_v": 0.6, "t_ref_c": 25},
     "spicethermal-bundle/1", "calibration.kind: calibration kinds need format"),
    ({"kind": "oven"}, V2, "calibration.kind: 'oven', expected one of"),
    ({"kind": "k-factor", "v_ref_v": 0.6, "t_ref_c": 25}, V2, "exactly one of k_mv_per_k"),
    ({"kind": "k-factor", "k_mv_per_k": -2, "t_ref_c": 25}, V2, "calibration.v_ref_v: missing"),
    ({"kind": "k-factor", "k_mv_per_k": 0, "v_ref_v": 0.6, "t_ref_c": 25}, V2, "zero"),
    ({"kind": "k-factor", "k_mv_per_k": "-2", "v_ref_v": 0.6, "t_ref_c": 25}, V2,
     "k_mv_per_k: '-2' is not a number"),
    ({"kind": "k-factor", "k_mv_per_k": -2, "v_ref_v": 0.6, "t_ref_c": 25, "file": "c.csv"},
     V2, "calibration.file: not a key of a k-factor"),
    ({"kind": "polynomial", "file": "calibration.csv"}, V2, "coefficients_v"),
    ({"kind": "polynomial", "file": "calibration.csv", "coefficients_v": [1.0]}, V2, "2 or 3"),
])
def test_bad_calibration_kind_names_the_key(tmp_path: Path, calibration, fmt, words) -> None:
    with pytest.raises(DataFormatError, match=re.escape(words)):
        Bundle.read(_kind_bundle(tmp_path, calibration, fmt))
