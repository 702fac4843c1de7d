"""The host side of the link protocol (firmware/PROTOCOL.md §4): in-order, exactly-once
delivery of device frames with cumulative ACKs, NAK/resend on a bad frame or a gap, command
resend when SYNC shows the device never got it, timeouts and a silent-device error; and the
link's statistics (:class:`LinkStats`). Every byte goes to a :class:`RawLog` first: the raw
records of a session, written before the link decodes them.
"""

from __future__ import annotations

import json
import os
import secrets
import time
from collections import deque
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import IO

from ..core.errors import InstrumentError
from . import protocol as p


# --------------------------------------------------------------------------- raw log
class RawLog:
    """Append-only raw records of a session in ``directory`` (created).

    Received bytes are written to the file (they survive a crash of this process) before
    the link decodes them, and fsynced (:meth:`sync`) before the host acknowledges them to
    the device, which then forgets them: no frame is lost from both sides at once.
    """

    def __init__(self, directory: Path | None) -> None:
        self.directory = directory
        self._bin: IO[bytes] | None = None
        self._jsonl: IO[str] | None = None
        self._t0 = time.monotonic()
        self._unsynced = False
        if directory is not None:
            directory.mkdir(parents=True, exist_ok=True)
            self._bin = open(directory / "raw_frames.bin", "ab")
            self._jsonl = open(directory / "frames.jsonl", "a", encoding="utf-8")

    def received(self, data: bytes) -> None:
        """Append ``data`` to ``raw_frames.bin``, written through to the kernel."""
        if self._bin is not None and data:
            self._bin.write(data)
            self._bin.flush()
            self._unsynced = True

    def sync(self) -> None:
        """fsync what was received so far (before acknowledging it to the device)."""
        if self._bin is not None and self._unsynced:
            os.fsync(self._bin.fileno())
            self._unsynced = False

    def frame(self, direction: str, block: bytes, status: str, frame: p.Frame | None = None
              ) -> None:
        if self._jsonl is None:
            return
        rec = {"t_s": round(time.monotonic() - self._t0, 6), "dir": direction,
               "status": status, "hex": block.hex()}
        if frame is not None:
            rec["type"], rec["seq"] = frame.type, frame.seq
        self._jsonl.write(json.dumps(rec) + "\n")
        self._jsonl.flush()

    def close(self) -> None:
        for f in (self._bin, self._jsonl):
            if f is not None:
                f.flush()
                os.fsync(f.fileno())
                f.close()
        self._bin = self._jsonl = None


# --------------------------------------------------------------------------- link
@dataclass
class LinkStats:
    """Counters of one link: ``frames`` delivered in order, ``received`` blocks of any kind
    (``received_bytes`` on the wire), ``corrupt`` ones (CRC or framing), and the recovery
    traffic."""

    frames: int = 0
    corrupt: int = 0
    duplicates: int = 0
    gaps: int = 0
    naks: int = 0
    acks: int = 0
    command_resends: int = 0
    timeouts: int = 0
    received: int = 0
    received_bytes: int = 0

    @property
    def byte_error_rate(self) -> float:
        """Per-byte error rate that explains the corrupt fraction of received frames, if each
        byte fails independently: a frame of ``L`` bytes survives with ``(1 - p)^L``.

        >>> round(LinkStats(corrupt=64, received=100, received_bytes=5000).byte_error_rate, 4)
        0.0202
        """
        if not self.received:
            return 0.0
        survived = 1.0 - self.corrupt / self.received
        mean_len = self.received_bytes / self.received
        return 1.0 - survived ** (1.0 / mean_len) if survived > 0 else 1.0

    def describe(self) -> str:
        """One phrase for messages: how many frames failed and the byte-error rate."""
        return (f"{self.corrupt} of {self.received} frames received failed their check (CRC "
                f"or framing), {self.naks} resends requested: a byte-error rate of about "
                f"{self.byte_error_rate:.1e} (a sound serial line has below 1e-6)")

    def report(self) -> dict:
        """The counters and the byte-error rate, for the bundle's ``bench.link``."""
        return {**asdict(self), "byte_error_rate": float(f"{self.byte_error_rate:.3g}")}


class Link:
    """Reliable in-order delivery of device messages over an open pyserial port.

    Parameters
    ----------
    port : an open pyserial port (its ``timeout`` is the unit of waiting).
    log : where raw bytes and frames go.
    nak_after_s : silence after which the host sends NAK (asks for a resend or a SYNC).
    silent_after_s : silence after which the device is declared silent (an error: "no
        response").
    max_rounds : resend requests in a row that bring bytes but no good frame, after which
        the line is declared too noisy (an error naming the measured byte-error rate).
    name : how messages name the port.
    """

    def __init__(self, port, log: RawLog, *, nak_after_s: float = 0.5,
                 silent_after_s: float = 5.0, max_rounds: int = 40,
                 name: str = "port") -> None:
        self.port = port
        self.log = log
        self.nak_after_s = nak_after_s
        self.silent_after_s = silent_after_s
        self.max_rounds = max_rounds
        self.name = name
        self.reader = p.FrameReader()
        self.expected = 0
        self.ring = 32
        self.stats = LinkStats()
        self._queue: deque[p.Message] = deque()
        self._cmd_seq = 1 + secrets.randbelow(0xFFFE)
        self._pending: tuple[int, bytes] | None = None  # (seq, wire) of the unanswered command
        self._pending_is_hello = False
        self._nak_sent = False
        self._since_ack = 0
        self._idle_s = 0.0
        self._naks_in_silence = 0
        self._rounds = 0  # resend requests since the last good frame, while bytes came
        self._noise = False  # bytes but no good frame since the last resend request

    # -- sending -----------------------------------------------------------------------
    def _write(self, wire: bytes, frame: p.Frame) -> None:
        try:
            self.port.write(wire)
        except Exception as exc:  # serial.SerialException and OSError alike
            raise InstrumentError(f"{self.name}: write failed: {exc}") from None
        self.log.frame("tx", wire[:-1], "ok", frame)

    def _send(self, msg: p.Message, seq: int) -> bytes:
        wire = msg.frame(seq)
        self._write(wire, p.Frame(msg.TYPE, seq, msg.payload()))
        return wire

    def send_command(self, msg: p.Message) -> int:
        """Send a command; returns its sequence number (the ACK will echo it)."""
        seq = self._cmd_seq
        self._cmd_seq = self._cmd_seq % 0xFFFF + 1
        if isinstance(msg, p.Hello):
            self.expected = 0  # HELLO resets the device's sequence
            self._queue.clear()
        wire = self._send(msg, seq)
        self._pending = (seq, wire)
        self._pending_is_hello = isinstance(msg, p.Hello)
        return seq

    def _nak(self) -> None:
        self.log.sync()  # a NAK acknowledges what came before it
        self._send(p.Nak(self.expected), 0)
        self.stats.naks += 1

    def _ack(self) -> None:
        self.log.sync()
        self._send(p.Ack(self.expected), 0)
        self.stats.acks += 1
        self._since_ack = 0

    # -- receiving ---------------------------------------------------------------------
    def receive(self) -> p.Message:
        """The next device message in sequence (blocking, with recovery and timeouts)."""
        while not self._queue:
            self._pump()
        return self._queue.popleft()

    def _pump(self) -> None:
        try:
            waiting = self.port.in_waiting
            data = self.port.read(max(1, min(waiting, 4096)))
        except Exception as exc:
            raise InstrumentError(f"{self.name}: read failed: {exc}") from None
        self.log.received(data)
        if not data:
            self._on_silence()
            return
        self._idle_s = 0.0  # the line is alive, if perhaps noisy: a new silence begins
        self._naks_in_silence = 0
        self._noise = True
        for block, item in self.reader.feed(data):
            self._on_block(block, item)
        if self._since_ack >= max(1, self.ring // 4):
            self._ack()

    def _on_silence(self) -> None:
        self.stats.timeouts += 1
        self._idle_s += float(self.port.timeout or 0.05)
        if self._idle_s >= self.silent_after_s:
            if self._rounds or self._noise:  # garbled bytes came since the last good frame
                self._noisy(f"then the device was silent for {self.silent_after_s:g} s")
            before = f"; the line was noisy before: {self.stats.describe()}" if (
                self.stats.byte_error_rate > 1e-4) else ""
            raise InstrumentError(
                f"{self.name}: no response from the device for {self.silent_after_s:g} s "
                f"(is it connected and powered, is this the bench's port?){before}")
        if self._idle_s >= self.nak_after_s * (self._naks_in_silence + 1):
            self._naks_in_silence += 1
            if self._noise:
                self._rounds += 1
                self._noise = False
                if self._rounds >= self.max_rounds:
                    self._noisy("")
            self._nak_sent = False
            self._nak()

    def _noisy(self, then: str) -> None:
        raise InstrumentError(
            f"{self.name}: noisy line, not a silent device: {self._rounds} resend requests in "
            f"a row brought no intact frame{', ' + then if then else ''}; "
            f"{self.stats.describe()}; check the cable (length, shielding, ground), the "
            f"connectors and the baud rate")

    def _alive(self) -> None:
        self._idle_s = 0.0
        self._naks_in_silence = 0
        self._rounds = 0
        self._noise = False
        self._rounds = 0  # resend requests since the last good frame, while bytes came
        self._noise = False  # bytes but no good frame since the last resend request

    def _on_block(self, block: bytes, item: p.Frame | p.FrameError) -> None:
        self.stats.received += 1
        self.stats.received_bytes += len(block) + 1  # with the delimiter
        if isinstance(item, p.FrameError):
            self.stats.corrupt += 1
            self.log.frame("rx", block, item.reason)
            if not self._nak_sent:
                self._nak_sent = True
                self._nak()
            return
        frame = item
        if frame.type < 0x80:
            self.log.frame("rx", block, "echo", frame)
            raise InstrumentError(f"{self.name}: received a host frame back (type "
                                  f"0x{frame.type:02x}); this is a loopback, not the bench")
        try:
            msg = p.decode_message(frame)
        except p.FrameError as exc:
            self.stats.corrupt += 1
            self.log.frame("rx", block, exc.reason, frame)
            if not self._nak_sent:
                self._nak_sent = True
                self._nak()
            return
        if not p.is_sequenced(frame):
            self.log.frame("rx", block, "ok", frame)
            self._alive()
            self._on_unsequenced(msg)
            return
        diff = (frame.seq - self.expected) & 0xFFFF
        if diff == 0:
            self.log.frame("rx", block, "ok", frame)
            self.expected = (self.expected + 1) & 0xFFFF
            self.stats.frames += 1
            self._since_ack += 1
            self._nak_sent = False
            self._alive()
            if isinstance(msg, p.CommandAck) and self._pending and msg.cmd_seq == self._pending[0]:
                self._pending = None
            self._queue.append(msg)
        elif diff < 0x8000:
            self.stats.gaps += 1
            self.log.frame("rx", block, "gap", frame)
            if not self._nak_sent:
                self._nak_sent = True
                self._nak()
        else:
            self.stats.duplicates += 1
            self.log.frame("rx", block, "duplicate", frame)

    def _on_unsequenced(self, msg: p.Message) -> None:
        pending = self._pending
        if isinstance(msg, p.Sync):
            if pending is not None and msg.last_cmd_seq != pending[0] and (
                    not msg.busy or self._pending_is_hello):
                self.stats.command_resends += 1
                self._write(pending[1], p.decode_block(pending[1][:-1]))
            elif msg.next_seq != self.expected and not self._nak_sent:
                self._nak_sent = True
                self._nak()
        elif isinstance(msg, p.DeviceError):
            if self._pending_is_hello and pending is not None:
                # a device still in an older session: our HELLO has not arrived yet
                self.stats.command_resends += 1
                self._write(pending[1], p.decode_block(pending[1][:-1]))
                return
            raise InstrumentError(f"{self.name}: the device reports a link error: "
                                  f"{msg.describe()}; the run cannot continue without losing "
                                  f"data")

    def flush_ack(self) -> None:
        """Acknowledge everything received so far."""
        if self._since_ack:
            self._ack()
