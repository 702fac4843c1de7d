"""pyserial URL handler ``sim://``: the simulated bench behind an ordinary serial port.

With ``spicethermal.bench`` in ``serial.protocol_handler_packages`` (the client adds it),
``serial.serial_for_url("sim://actuator?seed=3")`` returns this module's :class:`Serial`, and
the client talks to the firmware core on a simulated plant exactly as to the real bench.

URL: ``sim://DEVICE[?key=value&...]`` with DEVICE ``actuator`` or ``mur880e`` and

* ``seed`` (int, 0): seeds the plant noise and the link faults;
* ``noise`` (K, 0.03): TSP reading noise;
* ``effects`` (comma list, default ``electrical-transient,sample-window,tsp-nonlinearity``):
  the enabled effects of the catalogue (:mod:`spicethermal.effects`), ``none`` for an ideal
  bench. The list replaces the default. A measurement effect switches on the front end's
  hardware artefact that shows as it (:data:`~spicethermal.bench.devices.ARTEFACTS`, mapped in
  ``spicethermal/data/sim_bench.json``): without ``sample-window`` the bench holds the TSP at
  the start of each sample window (an ideal track-and-hold, INFO caps bit 0) and the bundle
  records ``sample_window_s = 0``; without ``electrical-transient`` the cut-off is clean;
  without ``tsp-nonlinearity`` the diode is linear in T. Any device effect of the registry is
  simulated through its plugin, with the device's parameters from that file
  (``temperature-coefficient``, ``phase-change``) or else the plugin's defaults;
* ``faults`` (per byte, 0): link fault rate in both directions; each fault is a flipped bit,
  a dropped byte or a duplicated byte, in equal shares;
* ``stall`` (reads, 0): with probability ``faults`` per read, the link holds the device's
  output back for this many reads (a stalled USB adapter), then delivers it;
* ``mute`` (0/1): a silent device (nothing ever comes back);
* ``firmware`` (X.Y.Z): the version the device reports (to test version checks).

A read never waits in wall-clock time: when the simulated device has nothing to say it returns
what it has (possibly nothing) at once, which the client counts as one timeout period.
"""

from __future__ import annotations

from urllib.parse import parse_qs, urlparse

import numpy as np
from serial import SerialBase, SerialException

from ..core.errors import InstrumentError
from .simulator import SimulatedDevice, parse_effects

KEYS = ("seed", "noise", "effects", "faults", "stall", "mute", "firmware")


class LinkFaults:
    """Byte-level faults on one direction of the link, at ``rate`` per byte.

    >>> f = LinkFaults(0.0, np.random.default_rng(0))
    >>> f(b"abc")
    b'abc'
    """

    def __init__(self, rate: float, rng: np.random.Generator) -> None:
        self.rate = rate
        self.rng = rng
        self.count = 0

    def __call__(self, data: bytes) -> bytes:
        if not self.rate or not data:
            return data
        hits = np.flatnonzero(self.rng.random(len(data)) < self.rate)
        if hits.size == 0:
            return data
        out = bytearray()
        prev = 0
        for i in hits:
            out += data[prev:i]
            kind = self.rng.integers(3)
            b = data[i]
            if kind == 0:
                out.append(b ^ (1 << int(self.rng.integers(8))))
            elif kind == 2:
                out += bytes((b, b))
            prev = i + 1
            self.count += 1
        out += data[prev:]
        return bytes(out)


def _parse(url: str) -> dict:
    parts = urlparse(url)
    if parts.scheme != "sim":
        raise SerialException(f"{url}: expected a sim://DEVICE URL")
    opts = {k: v[-1] for k, v in parse_qs(parts.query, keep_blank_values=True).items()}
    for key in opts:
        if key not in KEYS:
            raise SerialException(f"{url}: unknown option {key!r}; known: {', '.join(KEYS)}")
    try:
        version = None
        if "firmware" in opts:
            version = tuple(int(x) for x in opts["firmware"].split("."))
            if len(version) != 3 or not all(0 <= x < 256 for x in version):
                raise ValueError(opts["firmware"])
        return {
            "device": parts.netloc or parts.path.lstrip("/"),
            "seed": int(opts.get("seed", 0)),
            "noise_k": float(opts.get("noise", 0.03)),
            "effects": parse_effects(opts.get("effects")),
            "faults": float(opts.get("faults", 0.0)),
            "stall": int(opts.get("stall", 0)),
            "mute": opts.get("mute", "0") not in ("", "0", "false"),
            "firmware_version": version,
        }
    except ValueError as exc:
        raise SerialException(f"{url}: bad option value ({exc})") from None


class Serial(SerialBase):
    """A pyserial port whose far end is a :class:`~.simulator.SimulatedDevice`."""

    def open(self) -> None:
        if self._port is None:
            raise SerialException("Port must be configured before it can be used.")
        if self.is_open:
            raise SerialException("Port is already open.")
        opts = _parse(self.portstr)
        try:
            self.device = SimulatedDevice(
                opts["device"], seed=opts["seed"], noise_k=opts["noise_k"],
                effects=opts["effects"], firmware_version=opts["firmware_version"])
        except InstrumentError as exc:
            raise SerialException(str(exc)) from None
        rng = np.random.default_rng([opts["seed"], 0xB0B])
        self.to_device = LinkFaults(opts["faults"], rng)
        self.to_host = LinkFaults(opts["faults"], rng)
        self._stall_rate = opts["faults"] if opts["stall"] else 0.0
        self._stall_len = opts["stall"]
        self._stall_left = 0
        self._rng = rng
        self._mute = opts["mute"]
        self._rx = bytearray()
        self._held = bytearray()
        self.stalls = 0
        self.is_open = True

    def from_url(self, url: str) -> str:
        _parse(url)
        return url

    def _reconfigure_port(self, force_update: bool = False) -> None:
        pass

    def close(self) -> None:
        if self.is_open and getattr(self, "device", None) is not None:
            self.device.close()
        self.is_open = False

    def _fill(self) -> None:
        if self._mute:
            return
        if self._stall_left:
            self._stall_left -= 1
            return
        if self._stall_rate and self._rng.random() < self._stall_rate:
            self._stall_left = self._stall_len
            self.stalls += 1
            self._held += self.to_host(self.device.pump())
            return
        if self._held:
            self._rx += self._held
            self._held.clear()
        self._rx += self.to_host(self.device.pump())

    @property
    def in_waiting(self) -> int:
        if not self.is_open:
            raise SerialException("port not open")
        if not self._rx:
            self._fill()
        return len(self._rx)

    def read(self, size: int = 1) -> bytes:
        if not self.is_open:
            raise SerialException("port not open")
        if not self._rx:
            self._fill()
        out = bytes(self._rx[:size])
        del self._rx[:size]
        return out

    def write(self, data: bytes) -> int:
        if not self.is_open:
            raise SerialException("port not open")
        data = bytes(data)
        if not self._mute:
            self.device.write(self.to_device(data))
        return len(data)

    def reset_input_buffer(self) -> None:
        self._rx.clear()

    def reset_output_buffer(self) -> None:
        pass

    def flush(self) -> None:
        pass
