"""The bench client: talks to the firmware over any pyserial URL.

Layers, bottom up:

* :class:`~spicethermal.bench.link.RawLog` — every byte read from the port is appended to
  ``raw_frames.bin`` *before* it is processed, and fsynced before the host acknowledges it;
  every frame, both directions, gets a line in ``frames.jsonl`` with what the link made of it
  (ok, crc, gap...).
* :class:`~spicethermal.bench.link.Link` — the host side of the protocol
  (firmware/PROTOCOL.md §4, module :mod:`spicethermal.bench.link`): in-order, exactly-once
  delivery of device frames with cumulative ACKs, NAK/resend on a bad frame or a gap, command
  resend when SYNC shows the device never got it, timeouts and a silent-device error.
* :class:`BenchClient` — handshake (protocol and firmware version) and the procedures (the
  four of the paper, the forward voltage of protocol 3 and an array board's coupling of
  protocol 4), each returning the samples it received, checked complete (DONE count,
  contiguous indices).

Whole runs that write bundles are in :mod:`spicethermal.bench.session`.

>>> # a simulated bench, quickly: just the handshake
>>> with BenchClient("sim://actuator?seed=1") as bench:
...     bench.info.name, bench.info.firmware
('actuator', '1.3.0')
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from ..core.errors import DataFormatError, InstrumentError
from . import protocol as p
from .link import Link, RawLog

SUPPORTED_FIRMWARE_MAJOR = 1
ACTIONS = ("calibrate", "rth", "cooling", "pwm")
#: Procedures of array boards only, never part of a whole run.
ARRAY_ACTIONS = ("coupling",)
#: The first protocol version with the FORWARD procedure and the sense current in INFO.
FORWARD_PROTOCOL = 3
#: The first protocol version with the COUPLING procedure (array boards, ports in INFO's caps).
COUPLING_PROTOCOL = 4


# --------------------------------------------------------------------------- progress
class Progress:
    """A one-line progress bar on stderr (quiet unless enabled and stderr is a terminal)."""

    def __init__(self, enabled: bool, total: float) -> None:
        self.enabled = enabled and sys.stderr.isatty()
        self.total = max(total, 1e-9)
        self.done = 0.0
        self.label = ""

    def show(self, label: str | None = None, extra: float = 0.0) -> None:
        if label is not None:
            self.label = label
        if not self.enabled:
            return
        frac = min(1.0, (self.done + extra) / self.total)
        bar = "#" * int(30 * frac)
        sys.stderr.write(f"\r[{bar:<30}] {100 * frac:5.1f}% {self.label[:40]:<40}")
        sys.stderr.flush()

    def advance(self, amount: float) -> None:
        self.done += amount
        self.show()

    def close(self) -> None:
        if self.enabled:
            sys.stderr.write("\n")
            sys.stderr.flush()


# --------------------------------------------------------------------------- client
def open_port(url: str, timeout_s: float = 0.05):
    """Open any pyserial URL (``sim://`` included) with an InstrumentError when it fails."""
    import serial

    if "spicethermal.bench" not in serial.protocol_handler_packages:
        serial.protocol_handler_packages.append("spicethermal.bench")
    try:
        port = serial.serial_for_url(url, baudrate=115200, timeout=timeout_s,
                                     write_timeout=2.0)
    except (serial.SerialException, ValueError, OSError) as exc:
        raise InstrumentError(f"cannot open port {url}: {exc}") from None
    try:
        port.reset_input_buffer()
    except Exception:  # pragma: no cover - ports without buffers
        pass
    return port


@dataclass
class Run:
    """Samples of one procedure, complete and in order."""

    proc: int
    samples: list[p.Sample] = field(default_factory=list)

    def of_kind(self, kind: int) -> list[p.Sample]:
        return [s for s in self.samples if s.kind == kind]


class BenchClient:
    """A connection to the bench: handshake on open, procedures as methods.

    Parameters
    ----------
    url : any pyserial URL: ``/dev/ttyUSB0``, ``socket://host:port``, ``sim://actuator?...``.
    raw_dir : directory for the raw log (None: no raw log).
    progress : show progress on stderr.
    nak_after_s, silent_after_s : link timeouts (see :class:`Link`).
    """

    def __init__(self, url: str, raw_dir: Path | None = None, *, progress: bool = False,
                 nak_after_s: float = 0.5, silent_after_s: float = 5.0) -> None:
        self.url = url
        self.port = None
        self.log = RawLog(raw_dir)
        self.progress = Progress(progress, 1.0)
        self.on_status: Callable[[p.Status], None] | None = None
        try:
            self.port = open_port(url)
            self.link = Link(self.port, self.log, nak_after_s=nak_after_s,
                             silent_after_s=silent_after_s, name=url)
            self.info = self.handshake()
        except BaseException:
            self.close()
            raise

    def __enter__(self) -> BenchClient:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        try:
            if self.port is not None and self.port.is_open:
                self.port.close()
        finally:
            self.log.close()

    # -- protocol --------------------------------------------------------------------------
    def command(self, msg: p.Message) -> p.CommandAck:
        """Send a command and wait for its ACK; InstrumentError unless the status is ok."""
        seq = self.link.send_command(msg)
        while True:
            reply = self.link.receive()
            if isinstance(reply, p.CommandAck) and reply.cmd_seq == seq:
                if reply.status != 0:
                    raise InstrumentError(
                        f"{self.url}: the device refused {type(msg).__name__.lower()}: "
                        f"{p.ACK_STATUS.get(reply.status, reply.status)}")
                return reply

    def handshake(self) -> p.Info:
        """HELLO, then check the device's protocol and firmware version."""
        self.command(p.Hello(p.PROTOCOL_VERSION))
        info = self.link.receive()
        if not isinstance(info, p.Info):
            raise InstrumentError(f"{self.url}: expected INFO after HELLO, got "
                                  f"{type(info).__name__}")
        if info.proto not in p.PROTOCOLS:
            raise InstrumentError(f"{self.url}: the device speaks protocol version {info.proto}, "
                                  f"this client speaks {' and '.join(map(str, p.PROTOCOLS))}; "
                                  f"update one of them")
        if info.fw_major != SUPPORTED_FIRMWARE_MAJOR:
            raise InstrumentError(f"{self.url}: wrong firmware version {info.firmware} (board "
                                  f"{info.name!r}); this client needs firmware "
                                  f"{SUPPORTED_FIRMWARE_MAJOR}.x")
        self.link.ring = info.ring
        return info

    def _collect(self, msg: p.Message, proc: int) -> Run:
        self.command(msg)
        run = Run(proc)
        while True:
            m = self.link.receive()
            if isinstance(m, p.Sample):
                _check_range(m, self.url)
                if m.proc != proc:
                    raise InstrumentError(f"{self.url}: sample of procedure {m.proc} during "
                                          f"{p.PROC_NAMES[proc]}")
                if run.samples and m.index != run.samples[-1].index + 1:
                    raise InstrumentError(f"{self.url}: sample index jumped from "
                                          f"{run.samples[-1].index} to {m.index}: data lost")
                run.samples.append(m)
            elif isinstance(m, p.Status):
                if self.on_status is not None:
                    self.on_status(m)
            elif isinstance(m, p.Done):
                self.link.flush_ack()
                self.log.sync()  # the samples become a data set only once they are on disk
                if m.status != 0:
                    raise InstrumentError(f"{self.url}: {p.PROC_NAMES[proc]} failed: "
                                          f"{p.DONE_STATUS.get(m.status, m.status)}")
                first = run.samples[0].index if run.samples else m.first_index
                if m.n_samples != len(run.samples) or (run.samples and first != m.first_index):
                    raise InstrumentError(
                        f"{self.url}: {p.PROC_NAMES[proc]}: the device sent {m.n_samples} "
                        f"samples from index {m.first_index}, {len(run.samples)} arrived "
                        f"from index {first}")
                return run

    def abort(self) -> None:
        """Stop any procedure and switch the heater off (best effort)."""
        self.command(p.Abort())

    # -- procedures ------------------------------------------------------------------------
    def check_limits(self, settles_s: Sequence[float] = (), t_last_s: float | None = None
                     ) -> None:
        """Settle times within the limit the device reports in INFO, a cooling curve's last
        sample within the protocol's; a :class:`DataFormatError` naming the limit."""
        for settle_s in settles_s:
            if _ms(settle_s) > self.info.settle_max_ms:
                raise DataFormatError(f"settle time {settle_s:g} s is above the limit of "
                                      f"{self.info.settle_max_ms / 1e3:g} s that the device "
                                      f"reports")
        if t_last_s is not None and _ms(t_last_s) > p.CURVE_MAX_MS:
            raise DataFormatError(f"cooling curve: last sample at {t_last_s:g} s is above the "
                                  f"device's limit of {p.CURVE_MAX_MS / 1e3:g} s after the cut")

    def _settle_ms(self, settle_s: float) -> int:
        self.check_limits([settle_s])
        return _ms(settle_s)

    def calibrate(self, setpoint_c: float, settle_s: float, n: int, interval_s: float) -> Run:
        return self._collect(p.Calibrate(round(setpoint_c * 1e3), self._settle_ms(settle_s),
                                         _u16(n, "n"),
                                         _u16(round(interval_s * 1e3), "interval_ms")),
                             p.PROC_CAL)

    def rth(self, power_w: float, settle_s: float, window_s: float, n: int) -> Run:
        return self._collect(p.Rth(_uw(power_w), self._settle_ms(settle_s), _us16(window_s),
                                   _u16(n, "n")),
                             p.PROC_RTH)

    def cooling(self, power_w: float, settle_s: float, window_s: float, n: int,
                t_first_s: float, t_last_s: float, per_decade: int) -> Run:
        self.check_limits(t_last_s=t_last_s)
        return self._collect(p.Cooling(_uw(power_w), self._settle_ms(settle_s), _us16(window_s),
                                       _u16(n, "n"), round(t_first_s * 1e6), _ms(t_last_s),
                                       int(per_decade)), p.PROC_COOLING)

    def forward(self, setpoint_c: float, settle_s: float, pulse_s: float, n: int,
                interval_s: float, currents_a: Sequence[float]) -> Run:
        """Forward voltage on the fixture at ``setpoint_c``: ``n`` pulses of ``pulse_s`` at each
        current (protocol 3; firmware 1.2)."""
        if self.info.proto < FORWARD_PROTOCOL:
            raise InstrumentError(f"{self.url}: firmware {self.info.firmware} (protocol "
                                  f"{self.info.proto}) has no forward-voltage procedure; "
                                  f"update it to 1.2")
        if not 1 <= len(currents_a) <= p.FORWARD_MAX:
            raise DataFormatError(f"forward: give 1 to {p.FORWARD_MAX} currents")
        currents = tuple(round(i * 1e6) for i in currents_a)
        if any(not 0 < i < 2 ** 32 for i in currents):
            raise DataFormatError(f"forward: currents {tuple(currents_a)} must lie in (0, 4294) A")
        return self._collect(p.Forward(round(setpoint_c * 1e3), self._settle_ms(settle_s),
                                       _us16(pulse_s), _u16(n, "n"),
                                       _u16(round(interval_s * 1e3), "interval_ms"), currents),
                             p.PROC_FORWARD)

    def coupling(self, heater: int, power_w: float, settle_s: float, window_s: float, n: int,
                 t_first_s: float, t_last_s: float, per_decade: int) -> Run:
        """Heat ``heater`` and read every port of an array board (INFO caps: its ports;
        protocol 4, firmware 1.3)."""
        if self.info.proto < COUPLING_PROTOCOL:
            raise InstrumentError(f"{self.url}: firmware {self.info.firmware} (protocol "
                                  f"{self.info.proto}) has no coupling procedure; update it "
                                  f"to 1.3")
        ports = self.info.ports
        if ports < 2:
            raise InstrumentError(f"{self.url}: board {self.info.name!r} (firmware "
                                  f"{self.info.firmware}) is not an array board: it reports no "
                                  f"heaters to couple")
        if not 0 <= heater < ports:
            raise DataFormatError(f"coupling: heater {heater} outside the board's ports "
                                  f"0..{ports - 1}")
        self.check_limits(t_last_s=t_last_s)
        return self._collect(p.Coupling(heater, ports, _uw(power_w), self._settle_ms(settle_s),
                                        _us16(window_s), _u16(n, "n"), round(t_first_s * 1e6),
                                        _ms(t_last_s), int(per_decade)), p.PROC_COUPLING)

    def pwm(self, power_w: float, freq_hz: float, duty: float, settle_s: float,
            window_s: float, n: int, interval_s: float) -> Run:
        return self._collect(p.Pwm(_uw(power_w), round(freq_hz * 1e3), round(duty * 1e6),
                                   self._settle_ms(settle_s), _us16(window_s), _u16(n, "n"),
                                   _u16(round(interval_s * 1e3), "interval_ms")), p.PROC_PWM)


ADC_MAX_CODE = 1023


def _check_range(s: p.Sample, url: str) -> None:
    """A TSP reading at the end of the ADC range is clipped, hence wrong: stop, don't record.

    Curve points within the first millisecond are exempt: the electrical transient after the
    cut may drive the amplifier out of range there, and those points are masked anyway; so are
    readings while the heating current flows (the TSP amplifier saturates, by design)."""
    if s.kind in (p.KIND_POWER, p.KIND_FORWARD) or (s.kind == p.KIND_CURVE and s.t_us < 1000):
        return
    if s.code_tsp in (0, ADC_MAX_CODE):
        where = "above" if s.code_tsp == ADC_MAX_CODE else "below"
        raise InstrumentError(
            f"{url}: TSP reading out of the amplifier's range ({where} it; ADC code "
            f"{s.code_tsp}) during {p.PROC_NAMES.get(s.proc, 'a procedure')}: the junction is "
            f"too far from the reference diode's temperature; lower the power or the "
            f"calibration temperature")


def _uw(power_w: float) -> int:
    if not 0 < power_w < 4000:
        raise DataFormatError(f"power_w = {power_w!r}: must lie in (0, 4000) W")
    return round(power_w * 1e6)


def _ms(t_s: float) -> int:
    if not 0 <= t_s < 4e6:
        raise DataFormatError(f"time {t_s!r} s out of range")
    return round(t_s * 1e3)


def _us16(t_s: float) -> int:
    return _u16(round(t_s * 1e6), "window_us")


def _u16(v: int, name: str) -> int:
    if not 0 <= v <= 0xFFFF:
        raise DataFormatError(f"{name} = {v!r}: must fit in 16 bits")
    return int(v)
