"""The bench protocol's framing, host side: CRC-16, COBS, frames and a stream splitter
(``firmware/PROTOCOL.md`` §2). Pure functions, no I/O; :mod:`spicethermal.bench.protocol`
re-exports every name.

>>> decode_block(encode_frame(0x01, 7, b"\\x01")[:-1])
Frame(type=1, seq=7, payload=b'\\x01')
"""

from __future__ import annotations

import struct
from collections.abc import Iterator
from dataclasses import dataclass

from ..core.errors import InstrumentError

MAX_PAYLOAD = 48
CRC_INIT = 0xFFFF


class FrameError(InstrumentError):
    """A received block that is not a valid frame (``reason``: cobs, length or crc)."""

    def __init__(self, reason: str, block: bytes) -> None:
        super().__init__(f"bad frame ({reason}): {block.hex()}")
        self.reason = reason
        self.block = block


# ------------------------------------------------------------------------------- CRC, COBS
def _crc_table() -> tuple[int, ...]:
    table = []
    for byte in range(256):
        crc = byte << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1021) if crc & 0x8000 else crc << 1
        table.append(crc & 0xFFFF)
    return tuple(table)


_CRC_TABLE = _crc_table()


def crc16(data: bytes, crc: int = CRC_INIT) -> int:
    """CRC-16/CCITT-FALSE of ``data``.

    >>> hex(crc16(b"123456789"))
    '0x29b1'
    """
    for b in data:
        crc = ((crc << 8) & 0xFFFF) ^ _CRC_TABLE[((crc >> 8) ^ b) & 0xFF]
    return crc


def cobs_encode(data: bytes) -> bytes:
    """COBS-encode ``data`` (the result holds no zero byte; no delimiter appended).

    >>> cobs_encode(b"\\x11\\x22\\x00\\x33").hex()
    '0311220233'
    """
    out = bytearray([0])
    code_at, code = 0, 1
    for i, b in enumerate(data):
        if b == 0:
            out[code_at] = code
            code_at, code = len(out), 1
            out.append(0)
        else:
            out.append(b)
            code += 1
            if code == 0xFF:
                out[code_at] = code
                code = 1
                if i + 1 == len(data):
                    return bytes(out)  # a full block ends the data: no trailing code
                code_at = len(out)
                out.append(0)
    out[code_at] = code
    return bytes(out)


def cobs_decode(block: bytes) -> bytes:
    """Decode one COBS block (no delimiter); raises :class:`FrameError` when malformed.

    >>> cobs_decode(bytes.fromhex("0311220233"))
    b'\\x11"\\x003'
    """
    out = bytearray()
    i, n = 0, len(block)
    while i < n:
        code = block[i]
        i += 1
        if code == 0 or i + code - 1 > n:
            raise FrameError("cobs", bytes(block))
        chunk = block[i:i + code - 1]
        if 0 in chunk:
            raise FrameError("cobs", bytes(block))
        out += chunk
        i += code - 1
        if code != 0xFF and i < n:
            out.append(0)
    return bytes(out)


# ------------------------------------------------------------------------------- frames
@dataclass(frozen=True)
class Frame:
    """One frame: message type, sequence number and payload bytes."""

    type: int
    seq: int
    payload: bytes


def encode_frame(type_: int, seq: int, payload: bytes = b"") -> bytes:
    """Wire form of a frame: COBS(type | seq | payload | crc) followed by ``0x00``.

    >>> encode_frame(0x04, 1).hex()
    '030401036d2300'
    """
    if len(payload) > MAX_PAYLOAD:
        raise InstrumentError(f"payload of {len(payload)} bytes exceeds {MAX_PAYLOAD}")
    body = struct.pack("<BH", type_, seq & 0xFFFF) + bytes(payload)
    body += struct.pack("<H", crc16(body))
    return cobs_encode(body) + b"\x00"


def decode_block(block: bytes) -> Frame:
    """Decode the bytes between two delimiters; raises :class:`FrameError` (cobs, length, crc).

    >>> decode_block(bytes.fromhex("030401036d23"))
    Frame(type=4, seq=1, payload=b'')
    """
    body = cobs_decode(block)
    if not 5 <= len(body) <= 5 + MAX_PAYLOAD:
        raise FrameError("length", bytes(block))
    if crc16(body[:-2]) != struct.unpack_from("<H", body, len(body) - 2)[0]:
        raise FrameError("crc", bytes(block))
    type_, seq = struct.unpack_from("<BH", body)
    return Frame(type_, seq, bytes(body[3:-2]))


class FrameReader:
    """Split a byte stream at ``0x00`` delimiters and decode each block.

    >>> r = FrameReader()
    >>> [x for _, x in r.feed(encode_frame(4, 1) + b"\\x05\\x00")][0]
    Frame(type=4, seq=1, payload=b'')
    """

    MAX_BLOCK = 2 * (5 + MAX_PAYLOAD) + 8

    def __init__(self) -> None:
        self._buf = bytearray()

    def feed(self, data: bytes) -> Iterator[tuple[bytes, Frame | FrameError]]:
        """Yield ``(block, Frame or FrameError)`` for every complete block in ``data``."""
        for b in data:
            if b != 0:
                self._buf.append(b)
                continue
            if not self._buf:
                continue  # spare delimiter
            block = bytes(self._buf)
            self._buf.clear()
            if len(block) > self.MAX_BLOCK:
                yield block, FrameError("length", block)
                continue
            try:
                yield block, decode_block(block)
            except FrameError as exc:
                yield block, exc
