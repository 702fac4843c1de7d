"""Reliability of bundles: two writers at once, kill -9 at any moment, hostile files, modes.

Every promise of docs/reliability.md about bundles is checked here with real processes: the
writers are ``spicethermal bench`` subprocesses on the simulated bench, the kills are SIGKILL.
"""

from __future__ import annotations

import json
import os
import random
import re
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from spicethermal.bench.session import run_bench
from spicethermal.cli.main import main
from spicethermal.core.errors import DataFormatError
from spicethermal.io import files
from spicethermal.io.bundle import Bundle, CoolingTable

CLI = [sys.executable, "-m", "spicethermal.cli.main"]
QUICK = ["--cooling-power", "0.094", "--t-last", "5", "--settle", "20", "-q"]


def bench_cooling(out: Path, seed: int, *extra: str) -> subprocess.Popen:
    return subprocess.Popen(CLI + ["bench", "cooling", "--port", f"sim://actuator?seed={seed}",
                                   "-o", str(out), *QUICK, *extra],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def snapshot(root: Path) -> dict[str, bytes]:
    return {str(p.relative_to(root)): p.read_bytes() for p in sorted(root.rglob("*"))
            if p.is_file()}


@pytest.fixture
def base(tmp_path: Path) -> Path:
    """A bundle with a calibration, one cooling curve, its raw log and an operator's note."""
    out = tmp_path / "b"
    run_bench("sim://actuator?seed=1", out, actions=("calibrate", "cooling"),
              calibration_c=(25.0, 45.0), cooling_powers_w=(0.094,), cooling_t_last_s=5.0,
              settle_s=20.0)
    (out / "notes.txt").write_text("operator's notes\n")
    return out


def assert_nothing_lost(before: dict[str, bytes], out: Path) -> None:
    """Every file of ``before`` is still there: data files identical, raw logs at least as
    long (a killed session may have appended), and the bundle reads."""
    b = Bundle.read(out)
    listed = {t.file for t in (b.calibration, *b.cooling, b.pwm) if t is not None}
    for name, data in before.items():
        now = (out / name).read_bytes()
        if name.startswith("raw/"):
            assert now.startswith(data), name
        elif name != "bundle.json":
            assert now == data, name
    before_doc = json.loads(before["bundle.json"])
    assert {c["file"] for c in before_doc["cooling"]} <= listed
    assert before_doc["calibration"]["file"] in listed


# ------------------------------------------------------------------------ two writers
def test_two_concurrent_writers_with_wait_both_add_their_data(base: Path) -> None:
    before = snapshot(base)
    with files.locked(base):  # both start while the bundle is busy, then race for it
        procs = [bench_cooling(base, seed, "--wait") for seed in (5, 6)]
        time.sleep(1.0)
        assert all(p.poll() is None for p in procs)  # both are waiting, neither wrote
        assert snapshot(base) == before
    results = [p.communicate(timeout=120) for p in procs]
    assert [p.returncode for p in procs] == [0, 0], results
    assert_nothing_lost(before, base)
    b = Bundle.read(base)
    assert [c.file for c in b.cooling] == ["cooling_1.csv", "cooling_2.csv", "cooling_3.csv"]
    sessions = sorted((base / "raw").iterdir())
    assert len(sessions) == 3
    assert all((s / "raw_frames.bin").stat().st_size > 0 for s in sessions)
    assert sorted({c.extra["raw"] for c in b.cooling}) == sorted(
        f"raw/{s.name}/" for s in sessions)
    assert sorted(os.listdir(base.parent)) == ["b"]  # no lock file, no leftovers


def test_two_concurrent_writers_without_wait_one_stops_cleanly(base: Path) -> None:
    procs = [bench_cooling(base, seed) for seed in (5, 6)]
    results = [p.communicate(timeout=120) for p in procs]
    codes = sorted(p.returncode for p in procs)
    assert codes in ([0, 0], [0, 2]), results  # 0, 0 only if they did not overlap
    for p, (_, err) in zip(procs, results, strict=True):
        if p.returncode == 2:
            assert len(err.strip().splitlines()) == 1 and "another process" in err
    assert len(Bundle.read(base).cooling) == 1 + codes.count(0)


def test_a_busy_bundle_is_a_one_line_error_and_stays_untouched(base: Path) -> None:
    before = snapshot(base)
    with files.locked(base):
        p = bench_cooling(base, 5)
        _, err = p.communicate(timeout=120)
        with files.locked(base):  # re-entrant in the process that holds it
            pass
    assert p.returncode == 2
    assert err.count("\n") == 1 and f"another process (pid {os.getpid()})" in err
    assert "--wait" in err
    assert snapshot(base) == before


# ------------------------------------------------------------------------ kill -9
def test_kill_9_at_random_moments_loses_nothing(base: Path) -> None:
    rng = random.Random(17)
    t0 = time.monotonic()
    p = bench_cooling(base, 2)
    assert p.communicate(timeout=120) and p.returncode == 0
    duration = time.monotonic() - t0
    for trial in range(8):
        before = snapshot(base)
        p = bench_cooling(base, 10 + trial)
        time.sleep(rng.uniform(0.0, 1.2 * duration))
        p.send_signal(signal.SIGKILL)
        p.communicate(timeout=60)
        assert_nothing_lost(before, base)
        assert (base / "notes.txt").read_text() == "operator's notes\n"
        assert not (base.parent / "b.raw").exists()
    p = bench_cooling(base, 99)  # the next writer cleans up what the kills left
    assert p.communicate(timeout=120) and p.returncode == 0
    assert sorted(os.listdir(base.parent)) == ["b"]
    b = Bundle.read(base)
    assert len(b.cooling) >= 3 and len({c.file for c in b.cooling}) == len(b.cooling)


KILLER = textwrap.dedent("""
    import os, signal, sys
    from spicethermal.io import bundle, files
    from spicethermal.io.bundle import Bundle
    where = sys.argv[2]
    real = files.replace_dir

    def dying(new, path):
        if where == "before":
            os.kill(os.getpid(), signal.SIGKILL)
        real(new, path) if where == "after" else files._renameat2_exchange(str(new), str(path))
        os.kill(os.getpid(), signal.SIGKILL)

    bundle.replace_dir = dying
    b = Bundle.read(sys.argv[1])
    Bundle(device="new", cooling=b.cooling[:1]).write(sys.argv[1])
""")


@pytest.mark.parametrize("where,device", [("before", "old"), ("swapped", "new"),
                                          ("after", "new")])
def test_kill_9_inside_the_directory_swap_leaves_a_complete_bundle(tmp_path: Path, where: str,
                                                                   device: str) -> None:
    out = tmp_path / "b"
    Bundle(device="old", cooling=(CoolingTable([1e-3, 1e-2], 0.1, [30.0, 29.0]),
                                  CoolingTable([1e-3, 1e-2], 0.2, [35.0, 33.0]))).write(out)
    (out / "notes.txt").write_text("keep")
    p = subprocess.run([sys.executable, "-c", KILLER, str(out), where], capture_output=True)
    assert p.returncode == -signal.SIGKILL
    b = Bundle.read(out)
    assert b.device == device and (out / "notes.txt").read_text() == "keep"
    assert len(b.cooling) == (2 if device == "old" else 1)
    if where != "after":
        assert any(n.endswith(".tmp") for n in os.listdir(tmp_path))  # a leftover...
    Bundle.read(out).write(out)  # ...that the next write removes
    assert sorted(os.listdir(tmp_path)) == ["b"]


# ------------------------------------------------------------------------ never drop
def test_reruns_add_data_sets_and_replace_is_explicit(base: Path, capsys) -> None:
    port = ["--port", "sim://actuator?seed=4", "-o", str(base)]
    assert main(["bench", "cooling", *port, *QUICK]) == 0
    assert main(["bench", "calibrate", *port, "--setpoint", "25,45", "-q"]) == 0
    b = Bundle.read(base)
    assert [c.file for c in b.cooling] == ["cooling_1.csv", "cooling_2.csv"]
    assert b.calibration.file == "calibration_2.csv"
    assert b.extra["superseded"][0]["file"] == "calibration.csv"
    assert (base / "calibration.csv").exists() and (base / "notes.txt").exists()
    old = (base / "cooling_1.csv").read_bytes()
    assert main(["bench", "cooling", *port, *QUICK, "--replace", "cooling_1.csv"]) == 0
    b = Bundle.read(base)
    assert [c.file for c in b.cooling] == ["cooling_1.csv", "cooling_2.csv"]
    assert (base / "cooling_1.csv").read_bytes() != old
    capsys.readouterr()
    assert main(["bench", "cooling", *port, *QUICK, "--replace", "notes.txt"]) == 2
    err = capsys.readouterr().err
    assert "--replace notes.txt: not a data file" in err and err.count("\n") == 1
    assert main(["bench", "rth", *port, "-q", "--replace", "cooling_2.csv"]) == 2
    assert "measures no cooling data set" in capsys.readouterr().err


def test_raw_logs_that_an_older_version_moved_out_come_back(base: Path) -> None:
    old = base.parent / "b.raw" / "20250101T000000-cooling"
    old.mkdir(parents=True)
    (old / "raw_frames.bin").write_bytes(b"\x00\x01")
    run_bench("sim://actuator?seed=4", base, actions=("rth",))
    assert (base / "raw" / old.name / "raw_frames.bin").read_bytes() == b"\x00\x01"
    assert sorted(os.listdir(base.parent)) == ["b"]


def test_a_write_never_overwrites_a_file_the_manifest_does_not_list(tmp_path: Path) -> None:
    out = tmp_path / "b"
    Bundle(device="d").write(out)
    (out / "cooling_1.csv").write_text("my own file\n")
    with pytest.raises(DataFormatError, match="not part of the bundle"):
        Bundle(cooling=(CoolingTable([1e-3, 1e-2], 0.1, [30.0, 29.0]),)).write(out)
    assert (out / "cooling_1.csv").read_text() == "my own file\n"


# ------------------------------------------------------------------------ hostile files
def hostile_bundle(tmp_path: Path, make) -> Path:
    out = tmp_path / "h"
    Bundle(cooling=(CoolingTable([1e-3, 1e-2], 0.1, [30.0, 29.0], tj_steady_c=31.0),)
           ).write(out)
    (out / "cooling_1.csv").unlink()
    make(out / "cooling_1.csv")
    return out


@pytest.mark.parametrize("make,message", [
    (lambda p: p.symlink_to("/etc/passwd"), "leads outside the bundle"),
    (lambda p: p.symlink_to("/dev/zero"), "leads outside the bundle"),
    (lambda p: os.mkfifo(p), "not a regular file"),
    (lambda p: p.mkdir(), "is a directory"),
])
def test_hostile_files_in_a_bundle_are_refused_unread(tmp_path: Path, make, message) -> None:
    out = hostile_bundle(tmp_path, make)
    p = subprocess.run(CLI + ["fit", str(out), "-o", str(tmp_path / "m.json")],
                       capture_output=True, text=True, timeout=60)  # a FIFO must not hang
    assert p.returncode == 2 and p.stderr.count("\n") == 1, p.stderr
    assert message in p.stderr and "cooling_1.csv" in p.stderr
    assert "root:" not in p.stderr


def test_a_link_inside_the_bundle_is_followed(tmp_path: Path) -> None:
    out = tmp_path / "h"
    Bundle(cooling=(CoolingTable([1e-3, 1e-2], 0.1, [30.0, 29.0], tj_steady_c=31.0),)
           ).write(out)
    (out / "cooling_1.csv").rename(out / "data.csv")
    (out / "cooling_1.csv").symlink_to("data.csv")
    assert Bundle.read(out).cooling[0].tj_c.tolist() == [30.0, 29.0]


def test_size_and_row_limits_are_named(tmp_path: Path, monkeypatch) -> None:
    out = hostile_bundle(tmp_path, lambda p: p.write_text(
        "t_s,tj_c\n" + "".join(f"{k}e-3,30\n" for k in range(1, 30))))
    monkeypatch.setattr(files, "MAX_ROWS", 20)  # bundle.json has fewer, the curve more
    with pytest.raises(DataFormatError, match=r"cooling_1.csv: more than 20 lines, the limit"):
        Bundle.read(out)
    monkeypatch.setattr(files, "MAX_ROWS", 100)
    limit = (out / "bundle.json").stat().st_size
    monkeypatch.setattr(files, "MAX_BYTES", limit)
    with pytest.raises(DataFormatError, match=rf"cooling_1.csv: \d+ bytes, above the limit of "
                                              rf"{limit} bytes"):
        Bundle.read(out)


def test_a_file_name_with_a_nul_character_is_a_clean_error(tmp_path: Path) -> None:
    with pytest.raises(DataFormatError, match="NUL character"):
        files.read_text(tmp_path / "a\x00b.csv")


# ------------------------------------------------------------------------ JSON and modes
@pytest.mark.parametrize("text,message", [
    ('{"a": 1e400}', "out of range"),
    ('{"a": NaN}', "not a number JSON allows"),
    ('{"a": -Infinity}', "not a number JSON allows"),
    ("[" * 100000 + "]" * 100000, "nested 100000 levels deep"),
    ('{"a": "[[[[["}', None),
])
def test_json_is_read_strictly(text: str, message: str | None) -> None:
    if message is None:
        assert files.loads_json(text) == {"a": "[[[[["}
    else:
        with pytest.raises(DataFormatError, match=message):
            files.loads_json(text, "x.json")


def test_json_output_never_carries_nan_or_infinity() -> None:
    text = files.dumps_json({"rms_k": float("inf"), "points": [{"r": float("nan")}], "n": 1})
    doc = json.loads(text, parse_constant=lambda c: pytest.fail(c))
    assert doc["rms_k"] is None and doc["points"][0]["r"] is None
    assert doc["null_reasons"] == {"rms_k": "inf: not a finite number",
                                   "points[0].r": "nan: not a finite number"}


@pytest.mark.parametrize("mask,file_mode,dir_mode", [(0o022, 0o644, 0o755),
                                                     (0o077, 0o600, 0o700)])
def test_written_files_follow_the_umask(tmp_path: Path, mask: int, file_mode: int,
                                        dir_mode: int) -> None:
    old = os.umask(mask)
    try:
        out = Bundle(cooling=(CoolingTable([1e-3, 1e-2], 0.1, [30.0, 29.0]),)).write(
            tmp_path / "b")
        files.atomic_write_text(tmp_path / "m.json", "{}")
    finally:
        os.umask(old)
    assert (out.stat().st_mode & 0o777) == dir_mode
    for p in (out / "bundle.json", out / "cooling_1.csv", tmp_path / "m.json"):
        assert (p.stat().st_mode & 0o777) == file_mode, p


# ------------------------------------------------------------------------ bench limits
def test_a_procedure_that_needs_a_calibration_is_refused_before_measuring(tmp_path) -> None:
    for action in ("cooling", "pwm"):
        with pytest.raises(DataFormatError, match=f"bench {action}: needs a calibration"):
            run_bench("sim://actuator?seed=1", tmp_path / "b", actions=(action,))
    assert not (tmp_path / "b").exists()  # nothing measured, nothing left


def test_a_settle_time_above_the_devices_limit_is_refused_before_heating(tmp_path) -> None:
    with pytest.raises(DataFormatError, match="settle time 90000 s is above the limit of "
                                              "86400 s that the device reports"):
        run_bench("sim://actuator?seed=1", tmp_path / "b", actions=("rth",), settle_s=9e4)
    with pytest.raises(DataFormatError, match="above the device's limit of 2000 s"):
        run_bench("sim://actuator?seed=1", tmp_path / "c", actions=("calibrate", "cooling"),
                  calibration_c=(25.0, 45.0), cooling_t_last_s=2500.0)
    raw = next((tmp_path / "c" / "raw").iterdir()) / "frames.jsonl"
    types = {json.loads(r).get("type") for r in raw.read_text().splitlines()}
    assert 0x80 in types and not types & {0x10, 0x11, 0x12, 0x13}  # after INFO, no procedure


# ------------------------------------------------------------------------ every writer
#: Places that write files without spicethermal.io.files, each with its reason.
DIRECT_WRITES = {
    ("spice/ngspice.py", '(work / ".spiceinit").write_text('): "private temporary directory",
    ("spice/ngspice.py", '(work / "deck.cir").write_text('): "private temporary directory",
    ("engines/pwmsim.py", "lib.write_text("): "private temporary directory",
    ("io/bundle.py", 'with open(tmp / name, "w"'): "inside Bundle.write's temporary directory",
    ("bench/link.py", 'open(directory / "raw_frames.bin", "ab")'): "append-only raw log",
    ("bench/link.py", 'open(directory / "frames.jsonl", "a"'): "append-only raw log",
    ("bench/link.py", "json.dumps(rec)"): "raw log records: times and hex strings only",
    ("batch/device.py", "(local / file).write_bytes(data)"): "worker's private temporary copy",
    ("batch/device.py", "local.write_bytes(next(iter(source.files.values())))"):
        "worker's private temporary copy",
    ("engines/interface.py", "lib.write_text("): "private temporary directory",
    ("spice/array_lib.py", "lib.write_text("): "private temporary directory",
    ("engines/circuit.py", "lib.write_text("): "private temporary directory",
}
WRITE_CALL = re.compile(r"\.write_(text|bytes)\(|\bopen\([^)]*['\"][wax]b?['\"]|\.savefig\(|"
                        r"shutil\.copy|np\.save|\.to_csv\(|json\.dumps?\(")


def test_every_output_file_is_written_through_files_py() -> None:
    package = Path(files.__file__).parents[1]
    found = []
    for path in sorted(package.rglob("*.py")):
        rel = str(path.relative_to(package))
        if rel == "io/files.py":
            continue
        for lineno, line in enumerate(path.read_text().splitlines(), start=1):
            code = line.split("#", 1)[0]
            if ">>>" in line or "..." in line.strip()[:3] or not WRITE_CALL.search(code):
                continue
            if "atomic_open" in code or any(rel == f and snippet in code
                                            for f, snippet in DIRECT_WRITES):
                continue
            if ".savefig(handle" in code:  # into an atomic_open handle (plots.save)
                continue
            found.append(f"{rel}:{lineno}: {line.strip()}")
    assert not found, ("write these through spicethermal.io.files (atomic_write_text, "
                       "atomic_open, write_json; JSON text through dumps_json) or add them "
                       "to DIRECT_WRITES with the reason:\n" + "\n".join(found))


def test_an_interrupted_write_leaves_the_old_file(tmp_path: Path) -> None:
    target = tmp_path / "model.json"
    files.write_json(target, {"v": 1})
    with pytest.raises(RuntimeError):
        with files.atomic_open(target) as handle:
            handle.write('{"v": 2, "trunc')
            raise RuntimeError("killed mid-write")
    assert json.loads(target.read_text()) == {"v": 1}
    assert sorted(os.listdir(tmp_path)) == ["model.json"]


def test_raw_bytes_are_on_disk_before_the_device_forgets_them(tmp_path: Path,
                                                              monkeypatch) -> None:
    """Every ACK or NAK the host sends (the device then drops the frames it covers) comes
    after an fsync of every raw byte received before it; so does the end of a procedure."""
    from spicethermal.bench import client

    raw = tmp_path / "raw"
    events: list[tuple[str, int]] = []
    real_fsync, real_send = os.fsync, client.Link._send

    def fsync(fd: int) -> None:
        real_fsync(fd)
        if os.fstat(fd).st_size and os.path.samefile(f"/proc/self/fd/{fd}",
                                                     raw / "raw_frames.bin"):
            events.append(("fsync", os.fstat(fd).st_size))

    def send(self, msg, seq):
        if isinstance(msg, (client.p.Ack, client.p.Nak)):
            events.append(("ack", self.log._bin.tell()))
        return real_send(self, msg, seq)

    monkeypatch.setattr(os, "fsync", fsync)
    monkeypatch.setattr(client.Link, "_send", send)
    with client.BenchClient("sim://actuator?seed=3&faults=1e-3", raw) as bench:
        bench.rth(0.094, 5.0, 1e-4, 8)
        synced = max(n for e, n in events if e == "fsync")
        assert synced == (raw / "raw_frames.bin").stat().st_size  # all, at DONE
    acks = [(k, n) for k, (e, n) in enumerate(events) if e == "ack"]
    assert len(acks) >= 3
    for k, received in acks:
        assert max((n for e, n in events[:k] if e == "fsync"), default=0) >= received


def test_a_bundle_reached_through_a_link_is_updated_in_place(tmp_path: Path) -> None:
    real = Bundle(device="v1").write(tmp_path / "run5")
    (tmp_path / "current").symlink_to("run5")
    assert files.lock_path(tmp_path / "current") == files.lock_path(real)
    Bundle(device="v2").write(tmp_path / "current")
    assert (tmp_path / "current").is_symlink()
    assert Bundle.read(real).device == "v2"
    assert sorted(os.listdir(tmp_path)) == ["current", "run5"]


def test_cleaning_leftovers_touches_only_this_bundles(tmp_path: Path) -> None:
    mine = files.temp_dir_for(tmp_path / "b")
    other = files.temp_dir_for(tmp_path / "b.x")  # another bundle's write in progress
    assert files.clean_leftovers(tmp_path / "b") == [mine]
    assert other.is_dir() and not mine.exists()


@pytest.mark.parametrize("settle_s", [0.1, 0.5])
def test_a_short_settle_does_not_freeze_the_bench(tmp_path: Path, settle_s: float) -> None:
    # an ADC due at the same instant as a stale heartbeat used to make the core busy-poll
    # and the simulated bench wait forever (found by the fuzz: bench rth --settle-s 0.5)
    out = run_bench("sim://actuator?seed=1", tmp_path / "b", actions=("rth",),
                    settle_s=settle_s)
    assert Bundle.read(out).extra["rth"]["readings"] == 16
