"""Regenerate firmware/protocol_vectors.json from the written spec's examples.

The vectors are checked by both implementations (firmware/tests/test_core.c and
tests/test_protocol_vectors.py). Anchors that do not come from either implementation: the CRC
catalogue's check value (CRC-16/CCITT-FALSE of "123456789" = 0x29B1) and the COBS examples of
Cheshire & Baker / Wikipedia, written out by hand below. Run from the repository root:

    .venv/bin/python firmware/tools/make_vectors.py
"""

from __future__ import annotations

import json
import random
from pathlib import Path

from spicethermal.bench import protocol as p

OUT = Path(__file__).resolve().parents[1] / "protocol_vectors.json"

# (raw, encoded) written out by hand from the published COBS examples
COBS_EXAMPLES = [
    ("00", "0101"),
    ("0000", "010101"),
    ("001100", "01021101"),
    ("11220033", "0311220233"),
    ("11223344", "0511223344"),
    ("11000000", "0211010101"),
    (bytes(range(1, 255)).hex(), "ff" + bytes(range(1, 255)).hex()),
    (bytes(range(0, 255)).hex(), "01ff" + bytes(range(1, 255)).hex()),
    (bytes(range(1, 256)).hex(), "ff" + bytes(range(1, 255)).hex() + "02ff"),
    ((bytes(range(2, 256)) + b"\x00").hex(), "ff" + bytes(range(2, 256)).hex() + "0101"),
    ((bytes(range(3, 256)) + b"\x00\x01").hex(), "fe" + bytes(range(3, 256)).hex() + "0201"),
]


def main() -> None:
    rng = random.Random(20240521)
    crc = [{"kind": "crc16", "data_hex": b"123456789".hex(), "crc": 0x29B1},
           {"kind": "crc16", "data_hex": "", "crc": 0xFFFF}]
    for n in (1, 2, 5, 48, 53):
        data = bytes(rng.randrange(256) for _ in range(n))
        crc.append({"kind": "crc16", "data_hex": data.hex(), "crc": p.crc16(data)})
    cobs = []
    for raw, enc in COBS_EXAMPLES:
        assert p.cobs_encode(bytes.fromhex(raw)).hex() == enc, raw
        cobs.append({"kind": "cobs", "raw_hex": raw, "encoded_hex": enc})

    messages = [
        ("hello", 0x1234, p.Hello(3)),
        ("hello_v4", 0x1235, p.Hello(4)),
        ("ack", 7, p.Ack(0x0102)),
        ("nak", 8, p.Nak(0xFFFF)),
        ("abort", 9, p.Abort()),
        ("calibrate", 10, p.Calibrate(45000, 300000, 16, 100)),
        ("calibrate_negative", 11, p.Calibrate(-5000, 1000, 1, 0)),
        ("rth", 12, p.Rth(94000, 120000, 100, 16)),
        ("cooling", 13, p.Cooling(94000, 120000, 100, 16, 100, 60000, 10)),
        ("pwm", 14, p.Pwm(94000, 25000000, 200000, 60000, 100, 8, 100)),
        ("forward", 15, p.Forward(45000, 5000, 40, 8, 20, (5000, 20000, 120000, 350000))),
        ("forward_one", 16, p.Forward(-5000, 0, 10, 1, 1, (1,))),
        ("coupling", 17, p.Coupling(2, 8, 250000, 300000, 100, 4, 100, 300000, 10)),
        ("info_v2", 1, p.Info(2, 1, 1, 0, 10, 32, 1, 86_400_000, "actuator")),
        ("info", 1, p.Info(3, 1, 2, 0, 10, 32, 1, 86_400_000, "actuator", 1000)),
        ("info_v4", 1, p.Info(4, 1, 3, 0, 10, 32, 0x0801, 86_400_000, "array", 1000)),
        ("command_ack", 0, p.CommandAck(0x1234, 0x01, 0)),
        ("command_ack_busy", 65535, p.CommandAck(13, 0x12, 1)),
        ("sample", 300, p.Sample(3, 0, 123456, 100, -27400, 641000, 134000, 25012, 24950,
                                  560, 131, 274, 256, 711)),
        ("sample_zeros", 0, p.Sample(0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0)),
        ("array_sample", 301, p.ArraySample(6, 0, 123457, 120, -27400, 641000, 134000, 25012,
                                            24950, 560, 131, 274, 256, 711, 7)),
        ("status", 42, p.Status(3, 1, 5, 59, 61000)),
        ("done", 43, p.Done(3, 0, 59, 1000)),
        ("sync", 44, p.Sync(0x1234, 1, 44)),
        ("error_lost", 45, p.DeviceError(1, 3, 45)),
    ]
    frames = []
    for name, seq, msg in messages:
        payload = msg.payload()
        entry = {"kind": "frame", "name": name, "type": msg.TYPE, "seq": seq,
                 "payload_hex": payload.hex(), "wire_hex": msg.frame(seq).hex()}
        for k, v in msg.__dict__.items():
            if k != "next_seq":
                entry[f"f_{k}"] = list(v) if isinstance(v, tuple) else v
        frames.append(entry)
    for seq, payload in ((0xFFFF, bytes(48)), (0x00FF, b"\xff" * 48), (0x0100, b"\x00\x01")):
        frames.append({"kind": "frame", "name": f"raw_{seq:04x}", "type": 0x82, "seq": seq,
                       "payload_hex": payload.hex(),
                       "wire_hex": p.encode_frame(0x82, seq, payload).hex()})

    good = bytes.fromhex(frames[0]["wire_hex"])[:-1]
    flipped = bytearray(good)
    flipped[3] ^= 0x10
    bad = [
        {"kind": "bad", "name": "bit_flip", "block_hex": bytes(flipped).hex(), "error": "crc"},
        {"kind": "bad", "name": "truncated_wire", "block_hex": good[:-1].hex(), "error": "cobs"},
        {"kind": "bad", "name": "truncated_body",
         "block_hex": p.cobs_encode(p.cobs_decode(good)[:-1]).hex(), "error": "crc"},
        {"kind": "bad", "name": "too_short", "block_hex": p.cobs_encode(b"\x01\x02\x03").hex(),
         "error": "length"},
        {"kind": "bad", "name": "cobs_overrun", "block_hex": "05112233", "error": "cobs"},
        {"kind": "bad", "name": "too_long",
         "block_hex": p.cobs_encode(bytes(range(1, 60))).hex(), "error": "length"},
    ]
    for b in bad:
        try:
            p.decode_block(bytes.fromhex(b["block_hex"]))
        except p.FrameError as exc:
            assert exc.reason == b["error"], (b, exc.reason)
        else:
            raise AssertionError(b)

    doc = {"format": "spicethermal-protocol-vectors/1",
           "protocol_version": p.PROTOCOL_VERSION,
           "crc": "CRC-16/CCITT-FALSE: poly 0x1021, init 0xFFFF, refin/refout false, xorout 0",
           "crc16": crc, "cobs": cobs, "frames": frames, "bad_frames": bad}
    OUT.write_text(json.dumps(doc, indent=1) + "\n", encoding="utf-8")
    print(f"wrote {OUT}")


if __name__ == "__main__":
    main()
