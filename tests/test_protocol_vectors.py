"""The Python side of the bench protocol against the shared vectors
(firmware/protocol_vectors.json), which the C unit tests check too."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from spicethermal.bench import protocol as p

VECTORS = json.loads((Path(__file__).parent.parent / "firmware" / "protocol_vectors.json")
                     .read_text(encoding="utf-8"))


def test_vector_file_is_for_this_protocol_version():
    assert VECTORS["format"] == "spicethermal-protocol-vectors/1"
    assert VECTORS["protocol_version"] == p.PROTOCOL_VERSION


def test_crc_check_value_from_the_catalogue():
    assert p.crc16(b"123456789") == 0x29B1


@pytest.mark.parametrize("v", VECTORS["crc16"])
def test_crc16(v):
    assert p.crc16(bytes.fromhex(v["data_hex"])) == v["crc"]


@pytest.mark.parametrize("v", VECTORS["cobs"])
def test_cobs_both_ways(v):
    raw, enc = bytes.fromhex(v["raw_hex"]), bytes.fromhex(v["encoded_hex"])
    assert p.cobs_encode(raw) == enc
    assert p.cobs_decode(enc) == raw
    assert 0 not in enc


@pytest.mark.parametrize("v", VECTORS["frames"], ids=lambda v: v["name"])
def test_frames_encode_decode_and_fields(v):
    wire = bytes.fromhex(v["wire_hex"])
    payload = bytes.fromhex(v["payload_hex"])
    assert p.encode_frame(v["type"], v["seq"], payload) == wire
    assert wire.endswith(b"\x00") and 0 not in wire[:-1]
    frame = p.decode_block(wire[:-1])
    assert frame == p.Frame(v["type"], v["seq"], payload)
    fields = {k[2:]: val for k, val in v.items() if k.startswith("f_")}
    if fields:
        msg = p.decode_message(frame)
        for name, value in fields.items():
            got = getattr(msg, name)
            assert (list(got) if isinstance(got, tuple) else got) == value, name
        assert msg.payload() == payload


@pytest.mark.parametrize("v", VECTORS["bad_frames"], ids=lambda v: v["name"])
def test_bad_frames_are_rejected_with_the_reason(v):
    with pytest.raises(p.FrameError) as info:
        p.decode_block(bytes.fromhex(v["block_hex"]))
    assert info.value.reason == v["error"]


def test_every_single_bit_flip_of_a_sample_frame_is_detected():
    sample = next(v for v in VECTORS["frames"] if v["name"] == "sample")
    block = bytes.fromhex(sample["wire_hex"])[:-1]
    for i in range(len(block)):
        for bit in range(8):
            bad = bytearray(block)
            bad[i] ^= 1 << bit
            if 0 in bad:  # the byte became a delimiter: the reader splits the frame instead
                continue
            with pytest.raises(p.FrameError):
                p.decode_block(bytes(bad))


def test_reader_splits_stream_and_survives_garbage():
    frames = [p.encode_frame(0x83, s, bytes(10)) for s in range(3)]
    stream = b"\x00\x00\x07garbage" + b"\x00" + b"".join(frames)
    out = list(p.FrameReader().feed(stream))
    good = [x for _, x in out if isinstance(x, p.Frame)]
    bad = [x for _, x in out if isinstance(x, p.FrameError)]
    assert [f.seq for f in good] == [0, 1, 2]
    assert len(bad) == 1


def test_unknown_type_and_wrong_length_are_errors():
    with pytest.raises(p.FrameError):
        p.decode_message(p.Frame(0x7E, 0, b""))
    with pytest.raises(p.FrameError):
        p.decode_message(p.Frame(p.Sample.TYPE, 0, bytes(39)))


def test_sample_si_properties():
    s = p.Sample(3, 0, 1, 250, -27400, 700000, 134000, 25012, 24950)
    assert s.t_s == pytest.approx(250e-6)
    assert s.v_tsp_v == pytest.approx(-0.0274)
    assert s.power_w == pytest.approx(0.7 * 0.134)
    assert s.tamb_c == pytest.approx(25.012)
