"""The bench client against the simulated bench: full runs, exactness of the measurement
chain, link faults (nothing lost, nothing silently wrong), and the error messages."""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest

from spicethermal.bench import client as bc
from spicethermal.bench import protocol as p
from spicethermal.bench.devices import preset
from spicethermal.bench.session import run_bench
from spicethermal.cli.main import main
from spicethermal.core.errors import DataFormatError, InstrumentError
from spicethermal.engines.pwm import steady_state
from spicethermal.io.bundle import Bundle

SMALL = dict(calibration_c=(25.0, 45.0, 65.0), calibration_settle_s=100.0,
             cooling_powers_w=(0.094, 0.3), cooling_t_last_s=30.0, settle_s=90.0,
             pwm_freqs_hz=(1000.0, 25000.0), pwm_duties=(0.2, 0.8), pwm_settle_s=90.0)
CSVS = ("calibration.csv", "cooling_1.csv", "cooling_2.csv", "pwm.csv")


@pytest.fixture(scope="module")
def full_run(tmp_path_factory) -> Path:
    return run_bench("sim://actuator?seed=3", tmp_path_factory.mktemp("full") / "bundle")


@pytest.fixture(scope="module")
def exact_run(tmp_path_factory) -> Path:
    return run_bench("sim://actuator?seed=7&noise=0.01&effects=sample-window",
                        tmp_path_factory.mktemp("exact") / "bundle",
                        actions=("calibrate", "cooling", "pwm"), **SMALL)


@pytest.fixture(scope="module")
def clean_small(tmp_path_factory) -> Path:
    return run_bench("sim://actuator?seed=11", tmp_path_factory.mktemp("clean") / "b",
                        actions=("calibrate", "cooling", "pwm"), **SMALL)


# ------------------------------------------------------------------------------ full run
def test_full_run_writes_a_valid_bundle(full_run):
    b = Bundle.read(full_run)
    assert b.reference == "ambient" and abs(b.ambient_c - 25.0) < 0.2
    assert b.calibration.temp_c.size == 6
    assert [round(c.power_w, 2) for c in b.cooling] == [0.09, 0.3]
    for c in b.cooling:
        assert c.t_s[0] == pytest.approx(1e-4) and c.t_s[-1] > 40
        assert np.all(np.diff(c.t_s) > 0) and c.tj_c is not None and c.tref_c is not None
        k = np.arange(c.t_s.size)
        exact = 1e-4 * 10 ** (k / 10)  # ten points per decade, integer microseconds
        assert np.all(np.abs(c.t_s - exact) <= 0.5e-6 + 5e-4 * exact)
    assert b.pwm.freq_hz.size == 18 and b.pwm.sample_window_s == pytest.approx(1e-4)
    assert sorted(set(b.pwm.freq_hz)) == [500, 1000, 3000, 5000, 10000, 25000]
    assert sorted(set(b.pwm.duty)) == [0.2, 0.5, 0.8]
    # readings grow with duty at every frequency
    for f in set(b.pwm.freq_hz):
        tj = b.pwm.tj_c[b.pwm.freq_hz == f]
        assert np.all(np.diff(tj[np.argsort(b.pwm.duty[b.pwm.freq_hz == f])]) > 2.0)


def test_full_run_keeps_the_raw_frames(full_run):
    raw = next((full_run / "raw").iterdir())
    data = (raw / "raw_frames.bin").read_bytes()
    frames = [f for _, f in p.FrameReader().feed(data) if isinstance(f, p.Frame)]
    manifest = json.loads((full_run / "bundle.json").read_text())
    assert len(frames) == manifest["bench"]["link"]["frames"]
    samples = [p.decode_message(f) for f in frames if f.type == p.Sample.TYPE]
    assert [s.index for s in samples] == list(range(len(samples)))
    log = [json.loads(line) for line in (raw / "frames.jsonl").read_text().splitlines()]
    assert {r["dir"] for r in log} == {"rx", "tx"}


def test_rth_reads_the_junction_at_the_end_of_the_window(full_run):
    rth = json.loads((full_run / "bundle.json").read_text())["rth"]
    ladder = preset("actuator").foster
    # the 100 us window cools the junction by P·(Rth − cooling(100 us)): what the bench reads
    assert rth["rth_k_per_w"] == pytest.approx(float(ladder.cooling(1e-4)), rel=5e-3)
    assert rth["power_w"] == pytest.approx(0.094, rel=5e-3)


# ------------------------------------------------------------------------------ exactness
def test_cooling_curves_match_the_plants_ladder(exact_run):
    b = Bundle.read(exact_run)
    ladder = preset("actuator").foster
    for c in b.cooling:
        expected = c.tref_steady_c + c.power_w * ladder.cooling(c.t_s)
        assert np.max(np.abs(c.tj_c - expected)) < 0.12, c.file


def test_pwm_readings_match_the_analytic_steady_state(exact_run):
    b = Bundle.read(exact_run)
    ladder = preset("actuator").foster
    for f, d, tj, tref, pw in zip(b.pwm.freq_hz, b.pwm.duty, b.pwm.tj_c, b.pwm.tref_c,
                                  b.pwm.powers_w, strict=True):
        s = steady_state(ladder, pw, f, d, window_s=b.pwm.sample_window_s)
        assert tj == pytest.approx(tref + s.reading_k, abs=0.12), (f, d)
    assert b.pwm.sample_window_s == pytest.approx(1e-4)


def test_ideal_hold_records_a_zero_window(tmp_path):
    with pytest.raises(DataFormatError, match="needs a calibration"):
        run_bench("sim://actuator?seed=2&effects=none", tmp_path / "b", actions=("pwm",))
    path = run_bench("sim://actuator?seed=2&effects=none", tmp_path / "b",
                        actions=("calibrate", "pwm"), calibration_c=(25.0, 45.0),
                        pwm_freqs_hz=(25000.0,), pwm_duties=(0.5,))
    b = Bundle.read(path)
    assert b.pwm.sample_window_s == 0.0
    s = steady_state(preset("actuator").foster, b.pwm.powers_w[0], 25000.0, 0.5)
    assert b.pwm.tj_c[0] == pytest.approx(b.pwm.tref_c[0] + s.peak_k, abs=0.15)


def test_sub_actions_update_the_bundle(tmp_path):
    out = tmp_path / "b"
    run_bench("sim://mur880e?seed=1", out, actions=("calibrate",),
                 calibration_c=(25.0, 50.0, 75.0))
    run_bench("sim://mur880e?seed=1", out, actions=("cooling",), cooling_powers_w=(10.0,))
    b = Bundle.read(out)
    assert b.calibration.temp_c.size == 3 and len(b.cooling) == 1
    assert b.reference == "case"
    assert len(list((out / "raw").iterdir())) == 2
    c = b.cooling[0]
    zth = (c.tj_c[0] - c.tref_c[0]) / c.power_w  # junction to case, 100 us after the cut
    assert 1.51 * 0.9 < zth < 1.51  # the first 100 us of cooling are not seen


# ------------------------------------------------------------------------------ faults
def test_link_faults_lose_nothing_and_change_nothing(clean_small, tmp_path):
    faulty = run_bench("sim://actuator?seed=11&faults=1e-3&stall=20", tmp_path / "f",
                          actions=("calibrate", "cooling", "pwm"), **SMALL)
    link = json.loads((faulty / "bundle.json").read_text())["bench"]["link"]
    assert link["corrupt"] > 5 and link["naks"] > 5 and link["timeouts"] > 0
    for name in CSVS:
        assert (faulty / name).read_bytes() == (clean_small / name).read_bytes(), name


@pytest.mark.parametrize("rate", [1e-2, 2e-2])
def test_heavy_link_faults_still_lose_nothing(clean_small, tmp_path, rate):
    faulty = run_bench(f"sim://actuator?seed=11&faults={rate}", tmp_path / "f",
                       actions=("calibrate", "cooling", "pwm"), **SMALL)
    link = json.loads((faulty / "bundle.json").read_text())["bench"]["link"]
    assert link["corrupt"] > 50
    # the rate measured from the share of corrupt frames is the rate injected per byte
    assert rate / 1.5 < link["byte_error_rate"] < rate * 1.5
    for name in CSVS:
        assert (faulty / name).read_bytes() == (clean_small / name).read_bytes(), name


def test_a_noisy_line_is_not_reported_as_a_silent_device(tmp_path):
    # 10 % of the bytes damaged: after the handshake no 50-byte frame gets through intact
    with pytest.raises(InstrumentError, match=r"noisy line, not a silent device: \d+ resend "
                                              r"requests .*byte-error rate of about \d\.\de-0[12]"):
        with bc.BenchClient("sim://actuator?seed=2&faults=0.1") as bench:
            bench.rth(0.094, 10.0, 1e-4, 16)
    with pytest.raises(InstrumentError, match="no response from the device") as info:
        run_bench("sim://actuator?mute=1", tmp_path / "m", actions=("rth",))
    assert "noisy" not in str(info.value)


class FrameMangler:
    """A port wrapper that drops, duplicates and reorders whole device frames."""

    def __init__(self, port) -> None:
        self.port = port
        self.timeout = port.timeout
        self.is_open = True
        self._partial = b""
        self._count = 0
        self._held: bytes | None = None
        self.mangled = 0

    @property
    def in_waiting(self) -> int:
        return self.port.in_waiting

    def read(self, size: int = 1) -> bytes:
        data = self._partial + self.port.read(size)
        *frames, self._partial = data.split(b"\x00")
        out = bytearray()
        for f in frames:
            self._count += 1
            wire = f + b"\x00"
            if self._count % 13 == 5:
                self.mangled += 1
                continue  # dropped
            if self._count % 11 == 3:
                self.mangled += 1
                out += wire  # duplicated
            if self._count % 17 == 8 and self._held is None:
                self.mangled += 1
                self._held = wire  # delivered after the next one
                continue
            out += wire
            if self._held is not None:
                out += self._held
                self._held = None
        return bytes(out)

    def write(self, data: bytes) -> int:
        return self.port.write(data)

    def reset_input_buffer(self) -> None:
        self.port.reset_input_buffer()

    def close(self) -> None:
        self.port.close()
        self.is_open = False


def test_dropped_duplicated_reordered_frames_are_recovered(clean_small, tmp_path, monkeypatch):
    opened = []
    real_open = bc.open_port

    def mangled(url, timeout_s=0.05):
        port = FrameMangler(real_open(url, timeout_s))
        opened.append(port)
        return port

    monkeypatch.setattr(bc, "open_port", mangled)
    out = run_bench("sim://actuator?seed=11", tmp_path / "m",
                       actions=("calibrate", "cooling", "pwm"), **SMALL)
    assert opened[0].mangled > 100
    link = json.loads((out / "bundle.json").read_text())["bench"]["link"]
    assert link["duplicates"] > 10 and link["gaps"] > 10
    for name in CSVS:
        assert (out / name).read_bytes() == (clean_small / name).read_bytes(), name


# ------------------------------------------------------------------------------ errors
class GoesSilent(FrameMangler):
    def read(self, size: int = 1) -> bytes:
        self._count += 1
        return b"" if self._count > 60 else self.port.read(size)


def test_a_device_that_stops_answering_stops_the_run_clearly(tmp_path, monkeypatch):
    real_open = bc.open_port
    monkeypatch.setattr(bc, "open_port", lambda url, timeout_s=0.05: GoesSilent(
        real_open(url, timeout_s)))
    with pytest.raises(InstrumentError, match=r"no response .* for 5 s.*raw data .* kept"):
        run_bench("sim://actuator?seed=1", tmp_path / "b")
    # the raw log stays inside the (still empty, valid) bundle
    assert Bundle.read(tmp_path / "b").cooling == ()
    kept = list((tmp_path / "b" / "raw").iterdir())
    assert kept and (kept[0] / "raw_frames.bin").stat().st_size > 0


@pytest.mark.parametrize("url,message", [
    ("/dev/ttyDOESNOTEXIST", "cannot open port /dev/ttyDOESNOTEXIST"),
    ("sim://actuator?mute=1", "no response from the device"),
    ("sim://actuator?firmware=2.1.0", "wrong firmware version 2.1.0"),
    ("sim://toaster", "unknown simulated device"),
    ("sim://actuator?colour=red", "unknown option 'colour'"),
    ("loop://", "loopback, not the bench"),
])
def test_clear_instrument_errors(tmp_path, url, message):
    with pytest.raises(InstrumentError, match=message):
        run_bench(url, tmp_path / "b", actions=("rth",))
    # raw data are kept (in the bundle) only when some arrived; else nothing is left
    for run in (tmp_path / "b" / "raw").glob("*"):
        assert (run / "raw_frames.bin").stat().st_size > 0
    assert sorted(os.listdir(tmp_path)) in ([], ["b"])


def test_bad_plans_are_refused_before_touching_the_bench(tmp_path):
    with pytest.raises(DataFormatError, match="duties"):
        run_bench("sim://actuator?mute=1", tmp_path / "b", pwm_duties=(1.5,))
    with pytest.raises(DataFormatError, match="unknown plan fields"):
        run_bench("sim://actuator", tmp_path / "b", power=3)
    (tmp_path / "notabundle").mkdir()
    (tmp_path / "notabundle" / "x.txt").write_text("keep me")
    with pytest.raises(DataFormatError, match="not a bundle"):
        run_bench("sim://actuator", tmp_path / "notabundle", actions=("rth",))


# ------------------------------------------------------------------------------ CLI
def test_cli_bench_calibrate_and_errors(tmp_path, capsys):
    out = tmp_path / "cli"
    assert main(["bench", "calibrate", "--port", "sim://actuator?seed=1", "-o", str(out),
                 "--setpoint", "25,50", "-q"]) == 0
    assert Bundle.read(out).calibration.temp_c.size == 2
    assert main(["bench", "rth", "--port", "sim://actuator?mute=1", "-o", str(out), "-q"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "no response from the device" in err[0]
    with pytest.raises(SystemExit) as info:
        main(["bench", "pwm", "--port", "sim://actuator", "-o", str(out), "--duty", "x"])
    assert info.value.code == 2


def test_the_fitter_turns_the_bundle_back_into_the_plants_ladder(full_run):
    from spicethermal.fit.ladder import fit_model
    from spicethermal.identify.curves import ZthCurve

    truth = preset("actuator").foster
    for curve in ZthCurve.from_bundle(Bundle.read(full_run)):
        model, result = fit_model(curve)
        assert model.rth == pytest.approx(truth.rth, rel=0.01), curve.label
        assert result.order == truth.order
        tau = np.sort(model.ladder.time_constants())
        assert tau == pytest.approx(np.asarray(truth.tau), rel=0.15)


def test_temperature_coefficient_shows_in_pwm_readings_as_thermal_model_predicts(tmp_path):
    from spicethermal.bench.plant import Plant
    from spicethermal.effects import Effect
    from spicethermal.model import ThermalModel

    out = run_bench("sim://actuator?seed=1&noise=0.01&effects=temperature-coefficient,"
                       "sample-window", tmp_path / "tc", actions=("calibrate", "pwm"),
                       calibration_c=(25.0, 45.0, 65.0), pwm_freqs_hz=(25000.0,),
                       pwm_duties=(0.2, 0.8))
    b = Bundle.read(out)
    dev = preset("actuator")
    cauer = Plant(dev).cauer
    name = "temperature-coefficient"
    with_tc = ThermalModel(cauer, (Effect(name, dev.effect_params[name]),))
    linear = ThermalModel(cauer)
    for f, d, tj, tref, pw in zip(b.pwm.freq_hz, b.pwm.duty, b.pwm.tj_c, b.pwm.tref_c,
                                  b.pwm.powers_w, strict=True):
        model = tref + with_tc.pwm(pw, f, d, window_s=1e-4, tref_c=tref).reading_k
        assert tj == pytest.approx(model, abs=0.08), (f, d)
    lin = b.pwm.tref_c[-1] + linear.pwm(b.pwm.powers_w[-1], 25000.0, 0.8, window_s=1e-4,
                                         tref_c=b.pwm.tref_c[-1]).reading_k
    assert lin - b.pwm.tj_c[-1] > 0.15  # Rth falls with temperature: the bench reads cooler


class LosesCommands(FrameMangler):
    """Drops the first transmission of every command frame on its way to the device."""

    def __init__(self, port) -> None:
        super().__init__(port)
        self.seen: set[bytes] = set()

    def read(self, size: int = 1) -> bytes:
        return self.port.read(size)

    def write(self, data: bytes) -> int:
        frame = p.decode_block(data[:-1])
        if frame.type not in (p.Ack.TYPE, p.Nak.TYPE) and data not in self.seen:
            self.seen.add(data)
            self.mangled += 1
            return len(data)  # lost on the wire
        return self.port.write(data)


def test_lost_commands_are_sent_again(clean_small, tmp_path, monkeypatch):
    real_open = bc.open_port
    opened = []
    monkeypatch.setattr(bc, "open_port", lambda url, timeout_s=0.05: opened.append(
        LosesCommands(real_open(url, timeout_s))) or opened[-1])
    out = run_bench("sim://actuator?seed=11", tmp_path / "lc",
                       actions=("calibrate", "cooling", "pwm"), **SMALL)
    link = json.loads((out / "bundle.json").read_text())["bench"]["link"]
    assert link["command_resends"] == opened[0].mangled > 5
    for name in CSVS:
        assert (out / name).read_bytes() == (clean_small / name).read_bytes(), name


def test_a_clipped_tsp_reading_stops_the_run(tmp_path):
    # 85 degC is 60 K above the reference diode: beyond the amplifier's range
    with pytest.raises(InstrumentError, match="out of the amplifier's range"):
        run_bench("sim://actuator?seed=1", tmp_path / "b", actions=("calibrate",),
                  calibration_c=(25.0, 85.0), calibration_settle_s=200.0)
    assert Bundle.read(tmp_path / "b").calibration is None  # nothing recorded but the raw log


def test_mur880e_bench_gives_back_the_datasheet_impedance(tmp_path):
    from spicethermal.fit.ladder import fit_model
    from spicethermal.identify.curves import ZthCurve

    out = run_bench("sim://mur880e?seed=2", tmp_path / "m", actions=("calibrate", "cooling"),
                       calibration_c=(25.0, 50.0, 75.0), cooling_powers_w=(10.0,))
    curve = ZthCurve.from_bundle(Bundle.read(out))[0]
    model, _ = fit_model(curve)
    assert model.rth == pytest.approx(1.51, rel=0.01)
    t = np.array([1e-3, 1e-2, 1e-1, 1.0])  # the paper's Table 1, datasheet column
    r = np.interp(np.log(t), np.log(curve.t_s), curve.zth_k_per_w) / 1.51
    assert r == pytest.approx([0.18, 0.39, 0.60, 0.90], abs=0.012)
