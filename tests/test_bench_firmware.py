"""The firmware's own C unit tests and the PIC-layer check, run through make (gcc only)."""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import pytest

FIRMWARE = Path(__file__).parent.parent / "firmware"


@pytest.mark.skipif(shutil.which("make") is None or shutil.which("gcc") is None,
                    reason="needs make and gcc")
def test_make_firmware_test_passes():
    res = subprocess.run(["make", "-s", "-C", str(FIRMWARE), "test"], capture_output=True,
                         text=True, timeout=120)
    assert res.returncode == 0, res.stdout + res.stderr
    m = re.search(r"(\d+) passed, (\d+) failed", res.stdout)
    assert m and int(m.group(1)) > 200 and m.group(2) == "0", res.stdout
    assert "PIC layer: syntax and link check passed" in res.stdout


def test_protocol_constants_agree_between_c_and_python():
    from spicethermal.bench import protocol as p

    header = (FIRMWARE / "src" / "st_proto.h").read_text()

    def define(name: str) -> int:
        m = re.search(rf"#define {name} (0x[0-9A-Fa-f]+|\d+)u?", header)
        assert m, name
        return int(m.group(1), 0)

    assert define("ST_PROTO_VERSION") == p.PROTOCOL_VERSION
    assert define("ST_MAX_PAYLOAD") == p.MAX_PAYLOAD
    assert define("ST_LEN_SAMPLE") == len(p.Sample().payload())
    assert define("ST_LEN_INFO_FIXED") == len(p.Info().payload())  # name empty
    assert define("ST_SETTLE_MAX_MS") == p.Info().settle_max_ms
    assert define("ST_CURVE_MAX_MS") == p.CURVE_MAX_MS
    for c_name, cls in [("ST_CMD_HELLO", p.Hello), ("ST_CMD_ACK", p.Ack), ("ST_CMD_NAK", p.Nak),
                        ("ST_CMD_ABORT", p.Abort), ("ST_CMD_CALIBRATE", p.Calibrate),
                        ("ST_CMD_RTH", p.Rth), ("ST_CMD_COOLING", p.Cooling),
                        ("ST_CMD_PWM", p.Pwm), ("ST_CMD_FORWARD", p.Forward),
                        ("ST_CMD_COUPLING", p.Coupling), ("ST_MSG_INFO", p.Info),
                        ("ST_MSG_ACK", p.CommandAck), ("ST_MSG_SAMPLE", p.Sample),
                        ("ST_MSG_STATUS", p.Status), ("ST_MSG_DONE", p.Done),
                        ("ST_MSG_SYNC", p.Sync), ("ST_MSG_ERROR", p.DeviceError),
                        ("ST_MSG_ARRAY_SAMPLE", p.ArraySample)]:
        assert define(c_name) == cls.TYPE, c_name
    assert len(p.MESSAGES) == 18  # the 18 message classes: no code used twice
    for name, value in p.PROC_NAMES.items():
        assert define(f"ST_PROC_{'CAL' if value == 'calibrate' else value.upper()}") == name
    for kind in ("CURVE", "STEADY", "CAL", "POWER", "FORWARD", "COLD"):
        assert define(f"ST_KIND_{kind}") == getattr(p, f"KIND_{kind}"), kind
    assert define("ST_LEN_ARRAY_SAMPLE") == len(p.ArraySample().payload())
    assert define("ST_LEN_COUPLING") == len(p.Coupling().payload())
    assert define("ST_FW_MINOR") == 3 and define("ST_CAP_PORTS_SHIFT") == p.CAP_PORTS_SHIFT
    core = (FIRMWARE / "src" / "st_core.c").read_text()
    # payload lengths the firmware accepts equal the Python encodings
    for cls, n in [(p.Calibrate, 12), (p.Rth, 12), (p.Cooling, 21), (p.Pwm, 22)]:
        assert len(cls().payload()) == n
        assert f"len != {n}" in core
