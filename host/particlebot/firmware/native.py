"""ctypes binding of the firmware logic built for the PC (firmware/lib/capi/particle_capi.h).

The virtual particles and the firmware-logic tests drive the very C++ that is flashed onto a
particle through this module. The library is looked up in this order: the PARTICLEBOT_NATIVE_LIB
environment variable, then the clone's build/native/libparticle.so or an installed wheel's own
(particlebot.resources knows which); in a clone a missing library is built once with `make native`.
"""

from __future__ import annotations

import ctypes
import logging
import os
import subprocess
import threading
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from particlebot import resources
from particlebot.closing import ClosedOnExit
from particlebot.errors import ParticlebotError
from particlebot.protocol.generated import (
    FRAME_OVERHEAD,
    MAX_PAYLOAD,
    Method,
    Param,
    ParamResult,
    Status,
)

SENSOR_COUNT = 6
EEPROM_SIZE = 1024
_STATUS_CAPACITY = 64
_TX_CHUNK = 4096
_MAX_FRAME = MAX_PAYLOAD + FRAME_OVERHEAD

_log = logging.getLogger(__name__)

ENV_VAR = resources.ENV_NATIVE_LIB


class NativeLibraryError(ParticlebotError, OSError):
    """The native firmware library is missing or cannot be loaded."""


_U8P = ctypes.POINTER(ctypes.c_uint8)
_U16P = ctypes.POINTER(ctypes.c_uint16)

_lock = threading.Lock()
_library: ctypes.CDLL | None = None


def _declare(lib: ctypes.CDLL) -> None:
    """Gives every C function its signature, so ctypes converts and checks arguments."""
    handle = ctypes.c_void_p
    signatures: dict[str, tuple[object, list[object]]] = {
        "pb_particle_new": (handle, [_U8P, ctypes.c_size_t, ctypes.c_uint8, ctypes.c_uint32]),
        "pb_particle_free": (None, [handle]),
        "pb_particle_set_adc": (None, [handle, _U16P]),
        "pb_particle_receive": (None, [handle, _U8P, ctypes.c_size_t]),
        "pb_particle_tick": (None, [handle, ctypes.c_uint32]),
        "pb_particles_tick": (
            None,
            [
                ctypes.POINTER(handle),
                ctypes.c_size_t,
                ctypes.c_uint32,
                ctypes.POINTER(ctypes.c_uint32),
                _U8P,
            ],
        ),
        "pb_particle_transmit": (ctypes.c_size_t, [handle, _U8P, ctypes.c_size_t]),
        "pb_inter_frame_gap_ms": (ctypes.c_uint8, []),
        "pb_particle_id": (ctypes.c_uint8, [handle]),
        "pb_particle_servo_pulse_us": (ctypes.c_uint16, [handle]),
        "pb_particle_radius_um": (ctypes.c_uint32, [handle]),
        "pb_particle_status_payload": (ctypes.c_size_t, [handle, _U8P, ctypes.c_size_t]),
        "pb_particle_eeprom": (ctypes.c_size_t, [handle, _U8P, ctypes.c_size_t]),
        "pb_definition_hash": (ctypes.c_uint32, []),
        "pb_calibrated_reading": (
            ctypes.c_uint16,
            [ctypes.c_uint16, ctypes.c_uint16, ctypes.c_uint16],
        ),
        "pb_estimate": (
            ctypes.c_uint8,
            [
                ctypes.c_uint8,
                ctypes.c_uint16,
                _U16P,
                ctypes.c_size_t,
                ctypes.c_int32,
                ctypes.c_int32,
                ctypes.c_int32,
                ctypes.c_int32,
                ctypes.c_int32,
            ],
        ),
        "pb_encode_frame": (
            ctypes.c_size_t,
            [
                ctypes.c_uint8,
                ctypes.c_uint8,
                ctypes.c_uint8,
                _U8P,
                ctypes.c_size_t,
                _U8P,
                ctypes.c_size_t,
            ],
        ),
        "pb_parse_stream": (
            ctypes.c_size_t,
            [_U8P, ctypes.c_size_t, _U8P, ctypes.c_size_t, _U16P],
        ),
    }
    for name, (restype, argtypes) in signatures.items():
        function = getattr(lib, name)
        function.restype = restype
        function.argtypes = argtypes


def _build_once(root: Path) -> None:
    # A warning, so that it shows without any logging set up: the build takes a while.
    _log.warning("building the native firmware library (make -C %s native)...", root)
    result = subprocess.run(
        ["make", "-C", str(root), "native"], capture_output=True, text=True, check=False
    )
    if result.returncode != 0:
        raise NativeLibraryError(
            f"`make native` failed (exit {result.returncode}):\n{result.stderr[-2000:]}"
        )


def library_path() -> Path:
    """Where the library is looked for (it may not exist yet)."""
    return resources.native_library()


def load_library() -> ctypes.CDLL:
    """The loaded library, built first with `make native` when missing in a source checkout."""
    global _library
    with _lock:
        if _library is not None:
            return _library
        path = library_path()
        root = resources.source_root()
        if not path.exists() and ENV_VAR not in os.environ and root is not None:
            _build_once(root)
        if not path.exists():
            if ENV_VAR in os.environ:
                advice = f"fix {ENV_VAR}"
            elif root is not None:
                advice = "run `make native`"
            else:
                advice = f"reinstall particlebot from a platform wheel, or set {ENV_VAR}"
            raise NativeLibraryError(f"native firmware library not found at {path}: {advice}")
        try:
            lib = ctypes.CDLL(str(path))
            _declare(lib)
        except (OSError, AttributeError) as exc:
            raise NativeLibraryError(
                f"cannot load {path} ({exc}): rebuild it with `make native`"
            ) from exc
        _library = lib
        return lib


def _bytes_arg(data: bytes | bytearray) -> ctypes.Array[ctypes.c_uint8]:
    return (ctypes.c_uint8 * len(data)).from_buffer_copy(bytes(data))


def _u16_array(values: Sequence[int]) -> ctypes.Array[ctypes.c_uint16]:
    for v in values:
        if not 0 <= v <= 0xFFFF:
            raise ValueError(f"{v} does not fit 16 bits")
    return (ctypes.c_uint16 * len(values))(*values)


class NativeParticle(ClosedOnExit):
    """One particle: the firmware's Particle class with a RAM EEPROM and a simulated ADC.

    Time is whatever the caller says: tick(now_ms) advances the logic to now_ms, drawing ADC
    samples from the values last given to set_adc() as the real main loop would (one conversion
    per 125 us). Bytes passed to receive() arrive at the time of the last tick.
    """

    def __init__(
        self, eeprom: bytes | None = None, reset_cause: int = 1, rng_seed: int = 1
    ) -> None:
        self._lib = load_library()
        image = _bytes_arg(eeprom) if eeprom else None
        length = len(eeprom) if eeprom else 0
        handle = self._lib.pb_particle_new(image, length, reset_cause, rng_seed & 0xFFFFFFFF)
        if not handle:
            raise MemoryError("pb_particle_new failed")
        self._handle: int | None = handle
        self._now_ms = 0
        self._frame = (ctypes.c_uint8 * _MAX_FRAME)()

    def _h(self) -> int:
        if self._handle is None:
            raise ValueError("the particle is closed")
        return self._handle

    def close(self) -> None:
        if self._handle is not None:
            self._lib.pb_particle_free(self._handle)
            self._handle = None

    def __del__(self) -> None:
        # Only when the interpreter is not tearing the module down already.
        if getattr(self, "_handle", None) is not None and _library is not None:
            self.close()

    def set_adc(self, values: Sequence[int]) -> None:
        """Raw readings (0..1023) of photocells A0..A5 from now on."""
        if len(values) != SENSOR_COUNT:
            raise ValueError(f"need {SENSOR_COUNT} ADC values, got {len(values)}")
        self._lib.pb_particle_set_adc(self._h(), _u16_array(values))

    def receive(self, data: bytes | bytearray) -> None:
        """Bytes arriving on the particle's Serial1."""
        if data:
            self._lib.pb_particle_receive(self._h(), _bytes_arg(data), len(data))

    def tick(self, now_ms: int) -> None:
        """Advance to now_ms (call at least every 5 ms of simulated time)."""
        self._now_ms = now_ms
        self._lib.pb_particle_tick(self._h(), now_ms & 0xFFFFFFFF)

    @property
    def now_ms(self) -> int:
        """The time of the last tick()."""
        return self._now_ms

    @property
    def inter_frame_gap_ms(self) -> int:
        """See inter_frame_gap_ms()."""
        return int(self._lib.pb_inter_frame_gap_ms())

    def transmit_frame(self) -> bytes:
        """The next frame queued for Serial1 (b"" when none), removed from the queue: what the
        firmware hands its serial port at once, before a silence of inter_frame_gap_ms()."""
        n = self._lib.pb_particle_transmit(self._h(), self._frame, _MAX_FRAME)
        return bytes(self._frame[:n]) if n else b""

    def transmit(self, limit: int = _TX_CHUNK) -> bytes:
        """Everything queued for Serial1 (at most limit bytes), removed from the queue."""
        out = bytearray()
        buffer = (ctypes.c_uint8 * min(limit, _TX_CHUNK))()
        while len(out) < limit:
            n = self._lib.pb_particle_transmit(
                self._h(), buffer, min(len(buffer), limit - len(out))
            )
            if n == 0:
                break
            out += bytes(buffer[:n])
        return bytes(out)

    @property
    def id(self) -> int:
        return int(self._lib.pb_particle_id(self._h()))

    @property
    def servo_pulse_us(self) -> int:
        return int(self._lib.pb_particle_servo_pulse_us(self._h()))

    @property
    def radius_um(self) -> int:
        return int(self._lib.pb_particle_radius_um(self._h()))

    def status_payload(self) -> bytes:
        """The STATUS payload the particle would send now."""
        buffer = (ctypes.c_uint8 * _STATUS_CAPACITY)()
        n = self._lib.pb_particle_status_payload(self._h(), buffer, len(buffer))
        return bytes(buffer[:n])

    def status(self) -> Status:
        """The STATUS the particle would send now, decoded."""
        return Status.decode_payload(self.status_payload())

    def eeprom(self) -> bytes:
        """A copy of the EEPROM image (EEPROM_SIZE bytes)."""
        buffer = (ctypes.c_uint8 * EEPROM_SIZE)()
        n = self._lib.pb_particle_eeprom(self._h(), buffer, len(buffer))
        return bytes(buffer[:n])


class NativeBatch:
    """Ticks many particles in one call (pb_particles_tick) and reads each one's radius and
    whether it has a frame to send: what a swarm needs every tick, without three calls per
    particle. The particles' own now_ms is not updated by it."""

    def __init__(self, particles: Sequence[NativeParticle]) -> None:
        self._lib = load_library()
        self.count = len(particles)
        self._handles = (ctypes.c_void_p * self.count)(*[p._h() for p in particles])
        self.radius_um = (ctypes.c_uint32 * self.count)()
        """Each particle's radius after the last tick()."""
        self.tx_waiting = (ctypes.c_uint8 * self.count)()
        """1 where a particle had a frame to send after the last tick()."""

    def tick(self, now_ms: int) -> None:
        self._lib.pb_particles_tick(
            self._handles, self.count, now_ms & 0xFFFFFFFF, self.radius_um, self.tx_waiting
        )


# ---- pure functions ------------------------------------------------------------------------------


def inter_frame_gap_ms() -> int:
    """The silence the firmware keeps on its serial port between two frames, so that its XBee
    sends each frame as an RF packet of its own."""
    return int(load_library().pb_inter_frame_gap_ms())


def calibrated_reading(raw: int, gamma_milli: int, gain_milli: int) -> int:
    """A photocell's raw reading (0..1023) as the firmware corrects it for the calibration
    parameters SENSOR_GAMMA_k = gamma_milli and SENSOR_GAIN_k = gain_milli (thousandths)."""
    return int(load_library().pb_calibrated_reading(raw, gamma_milli, gain_milli))


def definition_hash() -> int:
    """The protocol definition hash the library was built with."""
    return int(load_library().pb_definition_hash())


def estimate(
    method: Method | int,
    own: int,
    others: Sequence[int],
    *,
    ref_distance_mm: int = 280,
    ref_value: int = 980,
    diameter_mm: int = 155,
    count_tolerance: int = 10,
    groups: int = 0,
) -> int:
    """S_n from the firmware's estimator for own reading among others (defaults: the params')."""
    lib = load_library()
    array = _u16_array(list(others)) if others else None
    return int(
        lib.pb_estimate(
            int(method),
            own,
            array,
            len(others),
            ref_distance_mm,
            ref_value,
            diameter_mm,
            count_tolerance,
            groups,
        )
    )


def encode_frame(frame_type: int, sender: int, seq: int, payload: bytes) -> bytes:
    """The firmware encoder's frame; raises ValueError when the payload is too long."""
    lib = load_library()
    out = (ctypes.c_uint8 * (len(payload) + 8))()
    data = _bytes_arg(payload) if payload else None
    n = lib.pb_encode_frame(frame_type, sender, seq, data, len(payload), out, len(out))
    if n == 0:
        raise ValueError(f"payload of {len(payload)} bytes does not fit a frame")
    return bytes(out[:n])


@dataclass(frozen=True)
class ParsedFrame:
    """A frame the firmware's parser accepted."""

    type: int
    sender: int
    seq: int
    payload: bytes


@dataclass(frozen=True)
class ParseCounters:
    """The parser's counters, as STATUS reports them."""

    frames: int
    bad_crc: int
    bad_length: int
    skipped_bytes: int


def parse_stream(data: bytes | bytearray) -> tuple[list[ParsedFrame], ParseCounters]:
    """Runs the firmware's streaming parser over data: the frames it accepts and its counters."""
    lib = load_library()
    # Accepted frames never share bytes and each shrinks by its 4 bytes of sync and CRC here.
    capacity = max(len(data), 1)
    out = (ctypes.c_uint8 * capacity)()
    counters = (ctypes.c_uint16 * 4)()
    source = _bytes_arg(data) if data else None
    n = lib.pb_parse_stream(source, len(data), out, capacity, counters)
    raw = bytes(out[:n])
    frames: list[ParsedFrame] = []
    i = 0
    while i < len(raw):
        length = raw[i + 3]
        frames.append(ParsedFrame(raw[i], raw[i + 1], raw[i + 2], raw[i + 4 : i + 4 + length]))
        i += 4 + length
    return frames, ParseCounters(*counters)


# ---- firmware constants and the epoch plan, for the vectorised model of the firmware ------------

_MODEL_SIGNATURES: dict[str, tuple[object, list[object]]] = {
    "pb_settings_image": (
        ctypes.c_size_t,
        [
            ctypes.c_uint8,
            _U8P,
            ctypes.POINTER(ctypes.c_int32),
            ctypes.c_size_t,
            _U8P,
            ctypes.c_size_t,
            ctypes.POINTER(ctypes.c_size_t),
            _U8P,
        ],
    ),
    "pb_frame_timeout_ms": (ctypes.c_uint16, []),
    "pb_ping_slot_ms": (ctypes.c_uint16, []),
    "pb_ping_slots_unknown": (ctypes.c_uint8, []),
    "pb_servo_cal_points": (ctypes.c_uint8, []),
    "pb_servo_pulse_min_us": (ctypes.c_uint16, []),
    "pb_servo_pulse_max_us": (ctypes.c_uint16, []),
    "pb_servo_step_ms": (ctypes.c_uint16, []),
    "pb_adc_full_scale": (ctypes.c_uint16, []),
    "pb_s_n_max": (ctypes.c_uint8, []),
    "pb_plan_epoch": (
        None,
        [
            ctypes.c_uint8,
            ctypes.c_uint16,
            ctypes.c_uint8,
            ctypes.c_uint8,
            ctypes.c_uint32,
            ctypes.c_uint32,
            ctypes.c_uint8,
            ctypes.c_uint8,
            ctypes.POINTER(ctypes.c_uint32),
        ],
    ),
}


def _model_library() -> ctypes.CDLL:
    """The library with the model's functions declared (idempotent, so no lock is needed)."""
    lib = load_library()
    for name, (restype, argtypes) in _MODEL_SIGNATURES.items():
        function = getattr(lib, name)
        function.restype = restype
        function.argtypes = argtypes
    return lib


@dataclass(frozen=True)
class FirmwareConstants:
    """Values the firmware defines outside the protocol that a model or a simulation of it
    needs."""

    servo_step_ms: int  # one servo step; a cycle of cycle_steps steps lasts T
    adc_full_scale: int  # highest reading; a sensor reading it or 0 is left out as faulty
    s_n_max: int  # every estimator saturates S_n here
    frame_timeout_ms: int  # a partial frame this old is dropped by the particle's parser
    ping_slot_ms: int  # a broadcast request is answered in a random slot of this length...
    ping_slots_unknown: int  # ...one of this many while the particle knows no group size
    inter_frame_gap_ms: int  # silence on Serial1 after each frame (one RF packet per frame)
    servo_cal_points: int  # points of the servo table SERVO_CAL_0..
    servo_pulse_min_us: int  # the pulses a servo may be given
    servo_pulse_max_us: int


_constants: FirmwareConstants | None = None


def firmware_constants() -> FirmwareConstants:
    """The constants the library was built with (read once)."""
    global _constants
    if _constants is None:
        lib = _model_library()
        _constants = FirmwareConstants(
            servo_step_ms=int(lib.pb_servo_step_ms()),
            adc_full_scale=int(lib.pb_adc_full_scale()),
            s_n_max=int(lib.pb_s_n_max()),
            frame_timeout_ms=int(lib.pb_frame_timeout_ms()),
            ping_slot_ms=int(lib.pb_ping_slot_ms()),
            ping_slots_unknown=int(lib.pb_ping_slots_unknown()),
            inter_frame_gap_ms=int(lib.pb_inter_frame_gap_ms()),
            servo_cal_points=int(lib.pb_servo_cal_points()),
            servo_pulse_min_us=int(lib.pb_servo_pulse_min_us()),
            servo_pulse_max_us=int(lib.pb_servo_pulse_max_us()),
        )
    return _constants


def settings_image(particle_id: int, params: Mapping[Param, int] | None = None) -> bytes:
    """The EEPROM a particle with this id and these parameter values (the rest their defaults)
    boots from, written by the firmware's own settings code: EEPROM_SIZE bytes. ValueError names
    a value the firmware refuses (as SET_PARAM would) or an id outside 1..253."""
    lib = _model_library()
    items = list((params or {}).items())
    ids = (ctypes.c_uint8 * max(1, len(items)))(*[int(p) for p, _ in items])
    values = (ctypes.c_int32 * max(1, len(items)))(*[int(v) for _, v in items])
    out = (ctypes.c_uint8 * EEPROM_SIZE)()
    refused = ctypes.c_size_t(0)
    result = ctypes.c_uint8(0)
    n = lib.pb_settings_image(
        particle_id, ids, values, len(items), out, EEPROM_SIZE, refused, result
    )
    if n == 0:
        if refused.value >= len(items):
            raise ValueError(f"particle id {particle_id} is outside 1..253")
        param, value = items[refused.value]
        raise ValueError(
            f"{Param(param).name}={value} refused by the firmware: {ParamResult(result.value).name}"
        )
    return bytes(out[:n])


@dataclass(frozen=True)
class EpochPlan:
    """One epoch of a particle's schedule, in ms (see plan_epoch in coordination.h)."""

    first_cycle_ms: int  # after the common start
    pause_ms: int  # t_p between cycles
    epoch_ms: int  # from the round's start to the next round's


def plan_epoch(
    method: Method | int,
    *,
    cycle_steps: int,
    wave_size: int,
    wave_size_param: int,
    update_interval_ms: int,
    round_ms: int,
    s_n: int,
    group_size: int,
) -> EpochPlan:
    """The firmware's plan for a particle whose round gave s_n after hearing group_size
    particles (itself included); wave_size 0 is automatic, as in START."""
    lib = _model_library()
    out = (ctypes.c_uint32 * 3)()
    lib.pb_plan_epoch(
        int(method),
        cycle_steps,
        wave_size,
        wave_size_param,
        update_interval_ms,
        round_ms,
        s_n,
        group_size,
        out,
    )
    return EpochPlan(int(out[0]), int(out[1]), int(out[2]))
