"""The simulated instrument: the real firmware core driving a simulated plant, in simulated time.

The firmware's portable core (``firmware/src``) is built for the host with its host hardware
layer (``firmware/hal/host``) as ``firmware/build/libspicethermal_fw.so`` and loaded with
ctypes. The core records its hardware calls (heater DAC and PWM, power cut, ADC triggers, hot
plate) as timed operations; :class:`SimulatedDevice` applies them to the
:class:`~spicethermal.bench.plant.Plant`, answers ADC triggers with codes from the
:class:`~spicethermal.bench.plant.Frontend`, and jumps the clock from one event (timer wake-up,
ADC trigger) to the next, so an hour of bench time runs in seconds. Same seed, same bytes.

The host sees only the serial byte stream (:mod:`.protocol_sim` wraps this as a pyserial port).

>>> dev = SimulatedDevice("actuator", seed=1)
>>> from spicethermal.bench import protocol as p
>>> dev.write(p.Hello().frame(5))
>>> [type(p.decode_message(f)).__name__ for _, f in p.FrameReader().feed(dev.pump())]
['CommandAck', 'Info']
"""

from __future__ import annotations

import ctypes
import math
import subprocess
import threading
from collections.abc import Iterable
from functools import lru_cache
from pathlib import Path

import numpy as np

from ..core.errors import InstrumentError
from .array_devices import ArrayGeometry
from .array_plant import ArrayPlant
from .devices import SAMPLE_WINDOW, artefacts, shown_as, simulated_effects
from .devices import preset as get_preset
from .plant import Frontend, Plant

FIRMWARE_DIR = Path(__file__).resolve().parents[2] / "firmware"
LIBRARY = FIRMWARE_DIR / "build" / "libspicethermal_fw.so"

OP_DAC, OP_PWM, OP_CUT, OP_RELEASE, OP_ADC_AT, OP_ADC_AFTER_CUT, OP_ADC_ON_PHASE, OP_FIXTURE = (
    range(1, 9))
OP_HEATER, OP_TSP = 9, 10  # array boards: the heater and the TSP diode selected
#: Array board: multiplexer settling plus one conversion, per port of a scan (us).
SCAN_US = 20
CAP_IDEAL_HOLD = 0x0001
_WRAP = 1 << 32


class _Conv(ctypes.Structure):
    _fields_ = [("num", ctypes.c_int32), ("off", ctypes.c_int32), ("den", ctypes.c_int32)]


class _Board(ctypes.Structure):
    _fields_ = [("ch", _Conv * 5), ("i_full_ua", ctypes.c_uint32), ("dac_max", ctypes.c_uint16),
                ("vd_nominal_uv", ctypes.c_uint32), ("fixture_min_mc", ctypes.c_int32),
                ("fixture_max_mc", ctypes.c_int32), ("caps", ctypes.c_uint16),
                ("adc_bits", ctypes.c_uint8), ("name", ctypes.c_char * 16),
                ("i_sense_ua", ctypes.c_uint32), ("ports", ctypes.c_uint8),
                ("scan_us", ctypes.c_uint16)]


class _Op(ctypes.Structure):
    _fields_ = [("op", ctypes.c_uint32), ("a", ctypes.c_uint32), ("b", ctypes.c_uint32),
                ("t_us", ctypes.c_uint32)]


class _State(ctypes.Structure):
    _fields_ = [("now_us", ctypes.c_uint32), ("board", _Board), ("wake_us", ctypes.c_uint32),
                ("wake_set", ctypes.c_uint32), ("n_ops", ctypes.c_uint32),
                ("ops_lost", ctypes.c_uint32), ("ops", _Op * 64), ("tx_len", ctypes.c_uint32),
                ("tx", ctypes.c_uint8 * 16384)]


_BUILD_LOCK = threading.Lock()


@lru_cache(maxsize=1)
def firmware_library() -> ctypes.CDLL:
    """The host build of the firmware core, built with ``make -C firmware host`` when needed."""
    with _BUILD_LOCK:
        if not (FIRMWARE_DIR / "Makefile").exists():
            raise InstrumentError(f"simulated bench: firmware sources not found in {FIRMWARE_DIR}")
        try:
            subprocess.run(["make", "-s", "-C", str(FIRMWARE_DIR), "host"], check=True,
                           capture_output=True, text=True, timeout=120)
        except FileNotFoundError:
            raise InstrumentError("simulated bench: 'make' (and gcc) are needed to build the "
                                  "firmware core") from None
        except subprocess.CalledProcessError as exc:
            last = (exc.stderr or exc.stdout or "").strip().splitlines()[-1:] or ["?"]
            raise InstrumentError(f"simulated bench: building the firmware failed: {last[0]}"
                                  ) from None
        lib = ctypes.CDLL(str(LIBRARY))
    lib.hh_new.restype = ctypes.c_void_p
    lib.hh_free.argtypes = [ctypes.c_void_p]
    lib.hh_init.argtypes = [ctypes.c_void_p]
    lib.hh_rx.argtypes = [ctypes.c_void_p, ctypes.c_char_p, ctypes.c_uint32]
    lib.hh_adc.argtypes = [ctypes.c_void_p, ctypes.POINTER(ctypes.c_uint16)]
    lib.hh_poll.argtypes = [ctypes.c_void_p]
    lib.hh_busy.argtypes = [ctypes.c_void_p]
    lib.hh_busy.restype = ctypes.c_uint32
    lib.hh_blocked.argtypes = [ctypes.c_void_p]
    lib.hh_blocked.restype = ctypes.c_uint32
    lib.hh_set_version.argtypes = [ctypes.c_uint8] * 3
    lib.built_version = tuple((ctypes.c_uint8 * 3).in_dll(lib, "st_fw_version"))
    return lib


def default_effects() -> tuple[str, ...]:
    """The effects of a URL without ``effects=``: what the paper's bench shows, every artefact
    of the front end (:func:`~spicethermal.bench.devices.shown_as`)."""
    return tuple(shown_as().values())


def parse_effects(text: str | None) -> tuple[str, ...]:
    """Effect names from a URL's ``effects=a,b`` (None: :func:`default_effects`; ``none``: no
    effect), each one the simulated bench can switch on
    (:func:`~spicethermal.bench.devices.simulated_effects`)."""
    if text is None:
        return default_effects()
    names = tuple(x.strip() for x in text.split(",") if x.strip())
    if names in ((), ("none",)):
        return ()
    known = simulated_effects()
    for name in names:
        if name not in known:
            raise InstrumentError(f"effects: unknown effect {name!r}; the simulated bench knows "
                                  f"{', '.join(known)}")
    return names


class SimulatedDevice:
    """The firmware core on a simulated plant (see the module docstring).

    Parameters
    ----------
    device : preset name, ``actuator`` or ``mur880e``.
    seed : seed of the noise generator.
    noise_k : TSP noise, kelvin (standard deviation).
    effects : enabled effect names (default: the bench's artefacts, :func:`default_effects`).
    firmware_version : report this version in INFO instead of the real one (tests).
    array : the array of the ``array`` device (default :class:`ArrayGeometry`, a 2 x 4 cell).
    """

    def __init__(self, device: str = "actuator", *, seed: int = 0, noise_k: float = 0.03,
                 effects: Iterable[str] | None = None,
                 firmware_version: tuple[int, int, int] | None = None,
                 array: ArrayGeometry | None = None) -> None:
        self.preset = get_preset(device)
        self.effects = tuple(default_effects() if effects is None else effects)
        self.rng = np.random.default_rng(seed)
        if device == "array":
            self.plant: Plant = ArrayPlant(self.preset, array or ArrayGeometry())
        elif array is not None:
            raise InstrumentError(f"sim://{device}: rows, cols, pitch and coupling are options "
                                  f"of sim://array")
        else:
            self.plant = Plant(self.preset, self.effects)
        on = artefacts(self.effects)
        self.frontend = Frontend(self.preset, on, noise_k, self.rng)
        self.ideal_hold = SAMPLE_WINDOW not in on  # an ideal track-and-hold: no sample window
        self._lib = firmware_library()
        self._version = firmware_version or self._lib.built_version
        self._dev = self._lib.hh_new()
        if not self._dev:
            raise InstrumentError("simulated bench: out of memory")
        self._state = _State.from_address(self._dev)
        self._set_board()
        self._lib.hh_init(self._dev)
        # clock and hardware state
        self.t = 0.0
        self.pwm: tuple[float, float, float] | None = None   # (t0, period, on) seconds
        self.current_a = 0.0
        self.cut_at: float | None = None
        self.last_cut: float | None = None
        self.adc_at: float | None = None
        self.adc_kind = 0
        self.wake: float | None = None

    # -- setup -------------------------------------------------------------------------
    def _set_board(self) -> None:
        b, bd = self.preset.board, self._state.board
        for i, (num, off, den) in enumerate(b.conversions()):
            bd.ch[i].num, bd.ch[i].off, bd.ch[i].den = num, off, den
        bd.i_full_ua = round(b.i_full_a * 1e6)
        bd.dac_max = b.dac_max
        bd.vd_nominal_uv = round(b.vd_nominal_v * 1e6)
        bd.fixture_min_mc = round(b.fixture_min_c * 1e3)
        bd.fixture_max_mc = round(b.fixture_max_c * 1e3)
        bd.caps = CAP_IDEAL_HOLD if self.ideal_hold else 0
        bd.adc_bits = 10
        bd.name = b.name.encode("ascii")[:15]
        bd.i_sense_ua = round(self.preset.diode.i_bias_a * 1e6)
        if isinstance(self.plant, ArrayPlant):
            bd.ports = self.plant.n_ports
            bd.scan_us = SCAN_US

    def close(self) -> None:
        if self._dev:
            self._lib.hh_free(self._dev)
            self._dev = None

    def __del__(self) -> None:  # pragma: no cover - best effort
        try:
            self.close()
        except Exception:
            pass

    # -- clock -------------------------------------------------------------------------
    @property
    def now_us(self) -> int:
        return round(self.t * 1e6)

    def _unwrap(self, t_u32: int) -> float:
        now = self.now_us
        delta = (t_u32 - now + (1 << 31)) % _WRAP - (1 << 31)
        return (now + delta) * 1e-6

    # -- host side ---------------------------------------------------------------------
    def write(self, data: bytes) -> None:
        """Bytes from the host arrive at the UART."""
        if not data:
            return
        self._lib.hh_set_version(*self._version)
        self._state.now_us = self.now_us % _WRAP
        self._lib.hh_rx(self._dev, bytes(data), len(data))
        self._apply_ops()
        self._poll()

    def pump(self, max_events: int = 100000) -> bytes:
        """Run the device until it has transmitted something or waits for the host."""
        events = 0
        while self._state.tx_len == 0 and events < max_events:
            if self._lib.hh_blocked(self._dev):
                break  # the host must acknowledge first; its reads take no simulated time
            if self.adc_at is not None and (self.wake is None or self.adc_at <= self.wake
                                            or self.wake <= self.t):  # a busy-poll: go on
                self._convert()
            elif self.wake is not None:
                self.advance_to(self.wake)
            else:
                break  # idle: waiting for the host
            self._poll()
            events += 1
        n = self._state.tx_len
        out = ctypes.string_at(ctypes.addressof(self._state.tx), n)
        self._state.tx_len = 0
        return out

    @property
    def busy(self) -> bool:
        return bool(self._lib.hh_busy(self._dev))

    # -- firmware calls ----------------------------------------------------------------
    def _poll(self) -> None:
        self._state.now_us = self.now_us % _WRAP
        self._lib.hh_poll(self._dev)
        self._apply_ops()
        self.wake = self._unwrap(self._state.wake_us) if self._state.wake_set else None

    def _apply_ops(self) -> None:
        s = self._state
        if s.ops_lost:
            raise InstrumentError("simulated bench: the firmware issued too many hardware calls")
        b = self.preset.board
        for k in range(s.n_ops):
            o = s.ops[k]
            if o.op == OP_DAC:
                self.current_a = o.a / b.dac_max * b.i_full_a
            elif o.op == OP_PWM:
                self.pwm = None if o.a == 0 or o.b == 0 else (self.t, o.a * 1e-9, o.b * 1e-9)
                self.cut_at = None
                self.plant.drive_changed()
            elif o.op == OP_CUT:
                self.cut_at = self._cut_time(bool(o.a))
                if self.pwm is not None:
                    self.last_cut = self.cut_at
                self.plant.drive_changed()
            elif o.op == OP_RELEASE:
                self.cut_at = None
                self.plant.drive_changed()
            elif o.op == OP_ADC_AT:
                self.adc_at, self.adc_kind = self._unwrap(o.a), OP_ADC_AT
            elif o.op == OP_ADC_AFTER_CUT:
                base = self.cut_at if self.cut_at is not None else self.t
                self.adc_at, self.adc_kind = base + o.a * 1e-6, OP_ADC_AFTER_CUT
            elif o.op == OP_ADC_ON_PHASE:
                self.adc_at, self.adc_kind = self._on_phase_middle(), OP_ADC_ON_PHASE
            elif o.op in (OP_HEATER, OP_TSP) and isinstance(self.plant, ArrayPlant):
                self.advance_to(self.t)
                if o.op == OP_HEATER:
                    self.plant.heater = min(o.a, self.plant.n_ports - 1)
                    self.plant.drive_changed()
                else:
                    self.plant.tsp_port = min(o.a, self.plant.n_ports - 1)
            elif o.op == OP_FIXTURE:
                self.advance_to(self.t)
                if o.a == 0:
                    self.plant.set_fixture(None)
                else:
                    self.plant.set_fixture(b.fixture_min_c + o.a / b.dac_max * (
                        b.fixture_max_c - b.fixture_min_c))
        s.n_ops = 0

    def _period_index(self, t: float) -> tuple[int, float]:
        t0, period, _ = self.pwm  # type: ignore[misc]
        k = math.floor((t - t0) / period + 1e-9)
        return k, t0 + k * period

    def _cut_time(self, at_on_end: bool) -> float:
        if not at_on_end or self.pwm is None or self.pwm[2] >= self.pwm[1]:
            return self.t
        _, period, on = self.pwm
        k, start = self._period_index(self.t)
        end = start + on
        return end if end >= self.t - 1e-12 else end + period

    def _on_phase_middle(self) -> float:
        if self.pwm is None or self.pwm[2] >= self.pwm[1]:
            return self.t + 1e-6
        _, period, on = self.pwm
        _, start = self._period_index(self.t)
        mid = start + on / 2
        return mid if mid >= self.t else mid + period

    def _heater_on(self, t: float) -> bool:
        if self.pwm is None or (self.cut_at is not None and t >= self.cut_at - 1e-12):
            return False
        _, period, on = self.pwm
        if on >= period:
            return True
        _, start = self._period_index(t)
        return t - start < on

    def _power(self) -> float:
        return self.current_a * self.frontend.v_diode(self.current_a, self.plant.tj_c)

    # -- plant -------------------------------------------------------------------------
    def advance_to(self, t_end: float) -> None:
        """Integrate the plant from the current time to ``t_end`` under the heater drive."""
        plant = self.plant
        while self.t < t_end:
            eps = 4 * math.ulp(max(self.t, t_end))
            if t_end - self.t <= eps:
                self.t = plant.t_s = t_end
                break
            chunk = plant.max_chunk_s
            if self.pwm is not None and self.pwm[2] < self.pwm[1]:
                chunk = max(chunk, 2 * self.pwm[1])  # whole periods, judged at their ends
            limit = min(t_end, self.t + chunk)
            track = True
            off = self.pwm is None or (self.cut_at is not None and self.cut_at <= self.t + eps)
            if off:
                seg_end, power = limit, 0.0
            else:
                if self.cut_at is not None:
                    limit = min(limit, self.cut_at)
                _, period, on = self.pwm  # type: ignore[misc]
                if on >= period:
                    seg_end, power = limit, self._power()
                else:
                    tol = eps + 1e-9 * period
                    k, start = self._period_index(self.t)
                    if self.t - start >= period - tol:  # at the next period's start
                        k, start = k + 1, start + period
                    phase = max(0.0, self.t - start)
                    n = math.floor((limit - start) / period + 1e-9)
                    if phase <= tol and n >= 1:
                        plant.step_periods(n, period, on, self._power())
                        self.t = plant.t_s = max(self.t, start + n * period)
                        continue
                    track = False
                    if phase < on - tol:
                        seg_end, power = min(limit, start + on), self._power()
                    else:
                        seg_end, power = min(limit, start + period), 0.0
            if seg_end <= self.t:  # pragma: no cover - guards float corner cases
                seg_end = min(t_end, self.t + max(eps, 1e-12))
            plant.step(seg_end - self.t, power, track)
            self.t = plant.t_s = seg_end

    def _convert(self) -> None:
        """Run the armed ADC conversion and hand the codes to the firmware."""
        t_adc = max(self.adc_at, self.t)  # type: ignore[type-var]
        kind = self.adc_kind
        self.adc_at = None
        held = None
        if kind == OP_ADC_AFTER_CUT and self.ideal_hold and self.cut_at is not None:
            self.advance_to(max(self.cut_at, self.t))
            held = self.plant.sensed_c
        self.advance_to(t_adc)
        plant = self.plant
        on = self._heater_on(self.t)
        since = None if self.last_cut is None else self.t - self.last_cut
        tj = plant.tj_c
        codes = self.frontend.codes(
            tj_c=tj, tj_tsp_c=plant.sensed_c if held is None else held,
            ambient_c=plant.ambient_c(),
            tref_c=plant.tref_c,
            taux_c=tj if plant.fixture_c is not None else plant.ambient_c(),
            heater_on=on, current_a=self.current_a,
            since_cut_s=None if held is not None else since)
        arr = (ctypes.c_uint16 * 5)(*codes)
        self._state.now_us = self.now_us % _WRAP
        self._lib.hh_adc(self._dev, arr)
