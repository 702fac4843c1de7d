"""The bench protocol, host side: framing, CRC, message encode/decode. Pure functions, no I/O.

The one written specification is ``firmware/PROTOCOL.md``; ``firmware/protocol_vectors.json``
holds test vectors that both the C unit tests and the Python tests check. In short:

* frame body ``type u8 | seq u16 | payload | crc u16`` (little-endian), CRC-16/CCITT-FALSE
  (poly 0x1021, init 0xFFFF, no reflection, no final xor) over type, seq and payload;
* on the wire the body is COBS-encoded and followed by one ``0x00`` delimiter;
* device frames are numbered; the host acknowledges them cumulatively (``Ack``) and asks for a
  resend from a sequence number (``Nak``); ``Sync`` and ``DeviceError`` are unsequenced.

>>> wire = encode_frame(0x01, 7, b"\\x01")
>>> decode_block(wire[:-1])
Frame(type=1, seq=7, payload=b'\\x01')
>>> decode_message(decode_block(encode_frame(0x85, 3, bytes([5, 0, 1]))[:-1]))
Sync(last_cmd_seq=5, busy=1, next_seq=3)
"""

from __future__ import annotations

import struct
from dataclasses import dataclass, fields
from typing import ClassVar

from .framing import (  # noqa: F401  (the framing's names, re-exported: one protocol module)
    CRC_INIT,
    MAX_PAYLOAD,
    Frame,
    FrameError,
    FrameReader,
    cobs_decode,
    cobs_encode,
    crc16,
    decode_block,
    encode_frame,
)

PROTOCOL_VERSION = 4
#: Device protocol versions this host speaks: 2 has no FORWARD procedure and no sense current in
#: INFO, 3 no COUPLING procedure (nor ARRAY_SAMPLE, nor ports in INFO's caps); everything else
#: is the same.
PROTOCOLS = (2, 3, 4)
#: Last cooling-curve sample the device accepts, ms after the cut (ST_CURVE_MAX_MS).
CURVE_MAX_MS = 2_000_000

# procedures and sample kinds (st_proto.h)
PROC_CAL, PROC_RTH, PROC_COOLING, PROC_PWM, PROC_FORWARD, PROC_COUPLING = 1, 2, 3, 4, 5, 6
PROC_NAMES = {PROC_CAL: "calibrate", PROC_RTH: "rth", PROC_COOLING: "cooling", PROC_PWM: "pwm",
              PROC_FORWARD: "forward", PROC_COUPLING: "coupling"}
KIND_CURVE, KIND_STEADY, KIND_CAL, KIND_POWER, KIND_FORWARD, KIND_COLD = 0, 1, 2, 3, 4, 5
#: Currents of one FORWARD command at most (ST_FORWARD_MAX).
FORWARD_MAX = 8
CAP_IDEAL_HOLD = 0x0001
CAP_PORTS_SHIFT = 8  # INFO caps bits 8..15 (protocol 4): an array board's heaters (0: one)
ACK_STATUS = {0: "ok", 1: "busy", 2: "bad length", 3: "bad parameter", 4: "unknown command"}
DONE_STATUS = {0: "ok", 2: "sample buffer overflow (the host read too slowly)"}
ERROR_CODES = {1: "frame lost for good (no longer in the device's ring buffer)",
               2: "sample buffer overflow", 3: "resend asked for a frame never sent"}


# ------------------------------------------------------------------------------- messages
@dataclass(frozen=True)
class Message:
    """Base of all messages: ``TYPE`` and the struct ``FORMAT`` of the fixed part."""

    TYPE: ClassVar[int] = 0
    FORMAT: ClassVar[str] = "<"

    def payload(self) -> bytes:
        return struct.pack(self.FORMAT, *(getattr(self, f.name) for f in fields(self)
                                          if f.name in self._wire_fields()))

    @classmethod
    def _wire_fields(cls) -> tuple[str, ...]:
        count = len(struct.unpack(cls.FORMAT, bytes(struct.calcsize(cls.FORMAT))))
        return tuple(f.name for f in fields(cls))[:count]

    @classmethod
    def from_payload(cls, payload: bytes, seq: int) -> Message:
        size = struct.calcsize(cls.FORMAT)
        if len(payload) != size:
            raise FrameError("length", payload)
        return cls(*struct.unpack(cls.FORMAT, payload))

    def frame(self, seq: int) -> bytes:
        """Wire bytes of this message with sequence number ``seq``."""
        return encode_frame(self.TYPE, seq, self.payload())


# host -> device ------------------------------------------------------------------------
@dataclass(frozen=True)
class Hello(Message):
    TYPE: ClassVar[int] = 0x01
    FORMAT: ClassVar[str] = "<B"
    proto: int = PROTOCOL_VERSION


@dataclass(frozen=True)
class Ack(Message):
    """Cumulative acknowledgement: every device frame before ``next_expected`` arrived."""

    TYPE: ClassVar[int] = 0x02
    FORMAT: ClassVar[str] = "<H"
    next_expected: int = 0


@dataclass(frozen=True)
class Nak(Message):
    """Acknowledge before ``next_expected`` and resend every frame from it on."""

    TYPE: ClassVar[int] = 0x03
    FORMAT: ClassVar[str] = "<H"
    next_expected: int = 0


@dataclass(frozen=True)
class Abort(Message):
    TYPE: ClassVar[int] = 0x04
    FORMAT: ClassVar[str] = "<"


@dataclass(frozen=True)
class Calibrate(Message):
    TYPE: ClassVar[int] = 0x10
    FORMAT: ClassVar[str] = "<iIHH"
    setpoint_mc: int = 25000
    settle_ms: int = 300000
    n: int = 16
    interval_ms: int = 100


@dataclass(frozen=True)
class Rth(Message):
    TYPE: ClassVar[int] = 0x11
    FORMAT: ClassVar[str] = "<IIHH"
    power_uw: int = 94000
    settle_ms: int = 120000
    window_us: int = 100
    n: int = 16


@dataclass(frozen=True)
class Cooling(Message):
    TYPE: ClassVar[int] = 0x12
    FORMAT: ClassVar[str] = "<IIHHIIB"
    power_uw: int = 94000
    settle_ms: int = 120000
    window_us: int = 100
    n: int = 16
    t_first_us: int = 100
    t_last_ms: int = 60000
    per_decade: int = 10


@dataclass(frozen=True)
class Pwm(Message):
    TYPE: ClassVar[int] = 0x13
    FORMAT: ClassVar[str] = "<IIIIHHH"
    power_uw: int = 94000
    freq_mhz: int = 1000000
    duty_ppm: int = 500000
    settle_ms: int = 60000
    window_us: int = 100
    n: int = 8
    interval_ms: int = 100


@dataclass(frozen=True)
class Forward(Message):
    """Forward voltage on the fixture at ``setpoint_mc``: after ``settle_ms``, ``n`` pulses of
    ``pulse_us`` at each current of ``currents_ua`` (1 to :data:`FORWARD_MAX`), ``interval_ms``
    apart, each read in its middle (protocol 3)."""

    TYPE: ClassVar[int] = 0x14
    FORMAT: ClassVar[str] = "<iIHHHB"
    setpoint_mc: int = 25000
    settle_ms: int = 5000
    pulse_us: int = 40
    n: int = 8
    interval_ms: int = 20
    currents_ua: tuple[int, ...] = (10000,)

    def payload(self) -> bytes:
        return struct.pack(self.FORMAT, self.setpoint_mc, self.settle_ms, self.pulse_us,
                           self.n, self.interval_ms, len(self.currents_ua)) + \
            b"".join(struct.pack("<I", i) for i in self.currents_ua)

    @classmethod
    def from_payload(cls, payload: bytes, seq: int) -> Forward:
        size = struct.calcsize(cls.FORMAT)
        if len(payload) < size or len(payload) != size + 4 * payload[size - 1]:
            raise FrameError("length", payload)
        *head, count = struct.unpack_from(cls.FORMAT, payload)
        return cls(*head, currents_ua=struct.unpack_from(f"<{count}I", payload, size))


@dataclass(frozen=True)
class Coupling(Message):
    """Array boards: heat ``heater``, read ports ``0 .. ports-1`` (protocol 4)."""

    TYPE: ClassVar[int] = 0x15
    FORMAT: ClassVar[str] = "<BBIIHHIIB"
    heater: int = 0
    ports: int = 2
    power_uw: int = 250000
    settle_ms: int = 300000
    window_us: int = 100
    n: int = 4
    t_first_us: int = 100
    t_last_ms: int = 300000
    per_decade: int = 10


# device -> host ------------------------------------------------------------------------
@dataclass(frozen=True)
class Info(Message):
    """The device's identity; ``i_sense_ua`` (the sense current) only from protocol 3 on."""

    TYPE: ClassVar[int] = 0x80
    FORMAT: ClassVar[str] = "<BBBBBBHI"
    proto: int = PROTOCOL_VERSION
    fw_major: int = 1
    fw_minor: int = 0
    fw_patch: int = 0
    adc_bits: int = 10
    ring: int = 32
    caps: int = 0
    settle_max_ms: int = 86_400_000
    name: str = ""
    i_sense_ua: int = 0

    @property
    def firmware(self) -> str:
        return f"{self.fw_major}.{self.fw_minor}.{self.fw_patch}"

    @property
    def ports(self) -> int:  # heaters of an array board (0: a single-heater board)
        return self.caps >> CAP_PORTS_SHIFT if self.proto >= 4 else 0

    def payload(self) -> bytes:
        sense = struct.pack("<I", self.i_sense_ua) if self.proto >= 3 else b""
        return struct.pack(self.FORMAT, self.proto, self.fw_major, self.fw_minor, self.fw_patch,
                           self.adc_bits, self.ring, self.caps, self.settle_max_ms
                           ) + sense + self.name.encode("ascii")

    @classmethod
    def from_payload(cls, payload: bytes, seq: int) -> Info:
        size = struct.calcsize(cls.FORMAT)
        if len(payload) < size or (payload[0] >= 3 and len(payload) < size + 4):
            raise FrameError("length", payload)
        sense = struct.unpack_from("<I", payload, size)[0] if payload[0] >= 3 else 0
        size += 4 if payload[0] >= 3 else 0
        name = payload[size:].decode("ascii", errors="replace")
        return cls(*struct.unpack_from(cls.FORMAT, payload), name=name, i_sense_ua=sense)


@dataclass(frozen=True)
class CommandAck(Message):
    TYPE: ClassVar[int] = 0x81
    FORMAT: ClassVar[str] = "<HBB"
    cmd_seq: int = 0
    cmd_type: int = 0
    status: int = 0


@dataclass(frozen=True)
class Sample(Message):
    """One reading of all channels, already converted by the firmware (fixed point)."""

    TYPE: ClassVar[int] = 0x82
    FORMAT: ClassVar[str] = "<BBII5i5H"
    proc: int = 0
    kind: int = 0
    index: int = 0
    t_us: int = 0
    v_tsp_uv: int = 0
    v_d_uv: int = 0
    i_ua: int = 0
    tamb_mc: int = 0
    taux_mc: int = 0
    code_tsp: int = 0
    code_vd: int = 0
    code_id: int = 0
    code_tamb: int = 0
    code_taux: int = 0

    @property
    def t_s(self) -> float:
        return self.t_us / 1e6

    @property
    def v_tsp_v(self) -> float:
        """TSP: heater-diode voltage minus reference-diode voltage, V (negative when hot)."""
        return self.v_tsp_uv / 1e6

    @property
    def power_w(self) -> float:
        return self.v_d_uv * self.i_ua / 1e12

    @property
    def tamb_c(self) -> float:
        return self.tamb_mc / 1e3

    @property
    def taux_c(self) -> float:
        return self.taux_mc / 1e3


@dataclass(frozen=True)
class ArraySample(Sample):
    """A sample of the coupling procedure (protocol 4): the port read (the diode; a power
    reading's heater)."""
    TYPE: ClassVar[int] = 0x87
    FORMAT: ClassVar[str] = "<BBII5i5HB"
    port: int = 0


@dataclass(frozen=True)
class Status(Message):
    TYPE: ClassVar[int] = 0x83
    FORMAT: ClassVar[str] = "<BBHHI"
    proc: int = 0
    state: int = 0
    done: int = 0
    total: int = 0
    elapsed_ms: int = 0


@dataclass(frozen=True)
class Done(Message):
    TYPE: ClassVar[int] = 0x84
    FORMAT: ClassVar[str] = "<BBHI"
    proc: int = 0
    status: int = 0
    n_samples: int = 0
    first_index: int = 0


@dataclass(frozen=True)
class Sync(Message):
    """Unsequenced: the device's next sequence number (in the frame's seq) and last command."""

    TYPE: ClassVar[int] = 0x85
    FORMAT: ClassVar[str] = "<HB"
    last_cmd_seq: int = 0
    busy: int = 0
    next_seq: int = 0

    @classmethod
    def from_payload(cls, payload: bytes, seq: int) -> Sync:
        if len(payload) != 3:
            raise FrameError("length", payload)
        last, busy = struct.unpack("<HB", payload)
        return cls(last, busy, seq)


@dataclass(frozen=True)
class DeviceError(Message):
    """Unsequenced link error (frame lost for good, resend out of range)."""

    TYPE: ClassVar[int] = 0x86
    FORMAT: ClassVar[str] = "<BH"
    code: int = 0
    detail: int = 0
    next_seq: int = 0

    @classmethod
    def from_payload(cls, payload: bytes, seq: int) -> DeviceError:
        if len(payload) != 3:
            raise FrameError("length", payload)
        code, detail = struct.unpack("<BH", payload)
        return cls(code, detail, seq)

    def describe(self) -> str:
        return f"{ERROR_CODES.get(self.code, f'code {self.code}')} (seq {self.detail})"


MESSAGES: dict[int, type[Message]] = {cls.TYPE: cls for cls in (
    Hello, Ack, Nak, Abort, Calibrate, Rth, Cooling, Pwm, Forward, Coupling,
    Info, CommandAck, Sample, ArraySample, Status, Done, Sync, DeviceError)}
UNSEQUENCED = frozenset({Sync.TYPE, DeviceError.TYPE})


def decode_message(frame: Frame) -> Message:
    """The message a frame carries; :class:`FrameError` for an unknown type or bad length.

    >>> decode_message(Frame(0x81, 0, bytes([7, 0, 0x12, 0])))
    CommandAck(cmd_seq=7, cmd_type=18, status=0)
    """
    cls = MESSAGES.get(frame.type)
    if cls is None:
        raise FrameError("type", bytes([frame.type]))
    return cls.from_payload(frame.payload, frame.seq)


def is_sequenced(frame: Frame) -> bool:
    """True for device frames that take part in the sequence (all but Sync and DeviceError)."""
    return frame.type not in UNSEQUENCED
