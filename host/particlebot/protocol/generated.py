"""Radio protocol of the particles: constants, enums and message classes.

Generated from shared/protocol.toml by tools/gen_protocol.py; do not edit.
"""

import enum
import struct
from dataclasses import dataclass
from typing import Any, ClassVar, NamedTuple, Self, TypeAlias

from particlebot.errors import ParticlebotError

GENERATOR_VERSION = 2
DEFINITION_HASH = 0xF1AAC96B
"""CRC-32 of the definition's layout; every STATUS frame carries the firmware's."""
SYNC = bytes((0xA5, 0x5A))
MAX_PAYLOAD = 48
FRAME_OVERHEAD = 8
"""Sync (2), LEN, TYPE, SENDER, SEQ and CRC (2) around the payload."""
BASE_STATION_ID = 0
BROADCAST_ID = 255
UNASSIGNED_ID = 254
"""Reported by a particle whose EEPROM holds no id yet."""


class PayloadError(ParticlebotError, ValueError):
    """A payload has the wrong size for its message, or a field value does not fit."""


class State(enum.IntEnum):
    """What a particle is doing; reported in STATUS."""

    IDLE = 0
    """Contracted and waiting for START."""
    ESTIMATING = 1
    """Measuring light and exchanging intensities to estimate S_n."""
    WAITING = 2
    """Waiting out the initial delay t_I = (S_n - 1) * T / 2 after the common start."""
    CYCLING = 3
    """Running one expansion-contraction cycle of period T."""
    PAUSED = 4
    """Resting t_p between cycles."""
    STOPPING = 5
    """Moving smoothly back to the contracted state after STOP."""
    DONE = 6
    """Phototaxis finished: the measured intensity stopped increasing."""
    IDENTIFYING = 7
    """Wiggling so a person can see which particle this is."""
    HOLDING = 8
    """Holding the servo at the pulse a SERVO_HOLD asked for (servo calibration), until its time
    runs out, STOP, START or IDENTIFY.
    """


class Method(enum.IntEnum):
    """Position-estimation method of SI section S4."""

    DIRECT = 0
    """(A) eqs. 14-16 from a reference distance and intensity; no communication."""
    LINEAR = 1
    """(B) eqs. 17-18 from the group's V_max and V_min."""
    NONLINEAR = 2
    """(C) eqs. 29-30 from the group's V_max and V_min."""
    COUNTING = 3
    """(D) Algorithm 4: count distinct stronger intensity levels."""


class Param(enum.IntEnum):
    """Parameters settable with SET_PARAM and persisted in EEPROM."""

    CYCLE_STEPS = 1
    """Servo steps of 20 ms per expansion-contraction cycle (75, 150, 300 in the paper)."""
    WAVE_SIZE = 2
    """N of eq. 3 used when START leaves it automatic and no group is known; pause t_p = (N - 1) * T
    / 2.
    """
    UPDATE_INTERVAL_S = 3
    """Seconds between re-estimations of S_n (the paper used 120-300)."""
    METHOD = 4
    """Default estimation method when START does not name one (enum method)."""
    REF_DISTANCE_MM = 5
    """Method A: r_x, distance of the reference point to the lamp."""
    REF_VALUE = 6
    """Method A: V_x, intensity reading at the reference point."""
    DIAMETER_MM = 7
    """D, the contracted particle diameter used to turn distance into S_n."""
    COUNT_TOLERANCE = 8
    """Method D: readings closer than this count as one level (the paper used 10)."""
    BROADCAST_REPEATS = 9
    """Intensity broadcasts per particle per estimation round (the paper used 5)."""
    GROUPS = 10
    """Methods B and C: N_w, number of groups; 0 means one group per row of particles toward the
    lamp (the rows method A counts between the group's strongest and weakest readings).
    """
    ROUND_MS = 11
    """Length of one estimation round; every particle's common start follows it."""
    STATUS_PERIOD_MS = 12
    """Interval between STATUS frames (each is jittered so particles do not collide)."""
    RADIUS_MIN_UM = 13
    """Contracted radius R_min in micrometres."""
    RADIUS_MAX_UM = 14
    """Fully expanded radius in micrometres (R_min + Delta R)."""
    SENSOR_GAMMA_0 = 16
    """Photocell A0's gamma (eq. 7) in thousandths; 1000 means gamma = 1, the law eq. 14 assumes."""
    SENSOR_GAMMA_1 = 17
    """Photocell A1's gamma (eq. 7) in thousandths."""
    SENSOR_GAMMA_2 = 18
    """Photocell A2's gamma (eq. 7) in thousandths."""
    SENSOR_GAMMA_3 = 19
    """Photocell A3's gamma (eq. 7) in thousandths."""
    SENSOR_GAMMA_4 = 20
    """Photocell A4's gamma (eq. 7) in thousandths."""
    SENSOR_GAMMA_5 = 21
    """Photocell A5's gamma (eq. 7) in thousandths."""
    SENSOR_GAIN_0 = 22
    """Photocell A0's gain in thousandths: the factor on its gamma-corrected resistance ratio; 1000
    leaves it.
    """
    SENSOR_GAIN_1 = 23
    """Photocell A1's gain in thousandths."""
    SENSOR_GAIN_2 = 24
    """Photocell A2's gain in thousandths."""
    SENSOR_GAIN_3 = 25
    """Photocell A3's gain in thousandths."""
    SENSOR_GAIN_4 = 26
    """Photocell A4's gain in thousandths."""
    SENSOR_GAIN_5 = 27
    """Photocell A5's gain in thousandths."""
    SERVO_CAL_0 = 32
    """Servo pulse (us) at calibration point 0 of 9 (R_min)."""
    SERVO_CAL_1 = 33
    """Servo pulse (us) at calibration point 1 of 9."""
    SERVO_CAL_2 = 34
    """Servo pulse (us) at calibration point 2 of 9."""
    SERVO_CAL_3 = 35
    """Servo pulse (us) at calibration point 3 of 9."""
    SERVO_CAL_4 = 36
    """Servo pulse (us) at calibration point 4 of 9."""
    SERVO_CAL_5 = 37
    """Servo pulse (us) at calibration point 5 of 9."""
    SERVO_CAL_6 = 38
    """Servo pulse (us) at calibration point 6 of 9."""
    SERVO_CAL_7 = 39
    """Servo pulse (us) at calibration point 7 of 9."""
    SERVO_CAL_8 = 40
    """Servo pulse (us) at calibration point 8 of 9 (fully expanded)."""


class ParamResult(enum.IntEnum):
    """Outcome of SET_PARAM / GET_PARAM, reported in PARAM_VALUE."""

    OK = 0
    """Applied (SET) or read (GET)."""
    UNKNOWN_PARAM = 1
    """No parameter has that number."""
    OUT_OF_RANGE = 2
    """Value outside the parameter's min..max."""
    BUSY = 3
    """Refused while running; STOP first."""
    SERVO_TABLE_NOT_MONOTONIC = 4
    """Inside min..max, but the nine SERVO_CAL pulses would no longer rise (or fall) from point 0 to
    point 8: change the neighbouring points first.
    """
    RADIUS_MIN_NOT_BELOW_MAX = 5
    """Inside min..max, but RADIUS_MIN_UM would no longer be below RADIUS_MAX_UM."""


class MessageType(enum.IntEnum):
    """The TYPE byte of a frame."""

    START = 0x01
    STOP = 0x02
    SET_PARAM = 0x03
    GET_PARAM = 0x04
    PING = 0x05
    IDENTIFY = 0x06
    SET_ID = 0x07
    SERVO_HOLD = 0x08
    STATUS = 0x20
    INTENSITY = 0x21
    PARAM_VALUE = 0x22


class ParamSpec(NamedTuple):
    """Default, accepted range and meaning of one parameter."""

    default: int
    min: int
    max: int
    description: str


PARAM_SPECS: dict[Param, ParamSpec] = {
    Param.CYCLE_STEPS: ParamSpec(
        150,
        10,
        3000,
        "Servo steps of 20 ms per expansion-contraction cycle (75, 150, 300 in the paper).",
    ),
    Param.WAVE_SIZE: ParamSpec(
        5,
        1,
        64,
        "N of eq. 3 used when START leaves it automatic and no group is known; pause t_p = (N - "
        "1) * T / 2.",
    ),
    Param.UPDATE_INTERVAL_S: ParamSpec(
        180,
        10,
        3600,
        "Seconds between re-estimations of S_n (the paper used 120-300).",
    ),
    Param.METHOD: ParamSpec(
        3,
        0,
        3,
        "Default estimation method when START does not name one (enum method).",
    ),
    Param.REF_DISTANCE_MM: ParamSpec(
        280,
        10,
        10000,
        "Method A: r_x, distance of the reference point to the lamp.",
    ),
    Param.REF_VALUE: ParamSpec(
        980,
        1,
        1022,
        "Method A: V_x, intensity reading at the reference point.",
    ),
    Param.DIAMETER_MM: ParamSpec(
        155,
        10,
        1000,
        "D, the contracted particle diameter used to turn distance into S_n.",
    ),
    Param.COUNT_TOLERANCE: ParamSpec(
        10,
        0,
        200,
        "Method D: readings closer than this count as one level (the paper used 10).",
    ),
    Param.BROADCAST_REPEATS: ParamSpec(
        5,
        1,
        20,
        "Intensity broadcasts per particle per estimation round (the paper used 5).",
    ),
    Param.GROUPS: ParamSpec(
        0,
        0,
        64,
        "Methods B and C: N_w, number of groups; 0 means one group per row of particles toward "
        "the lamp (the rows method A counts between the group's strongest and weakest readings).",
    ),
    Param.ROUND_MS: ParamSpec(
        3000,
        200,
        60000,
        "Length of one estimation round; every particle's common start follows it.",
    ),
    Param.STATUS_PERIOD_MS: ParamSpec(
        2000,
        200,
        60000,
        "Interval between STATUS frames (each is jittered so particles do not collide).",
    ),
    Param.RADIUS_MIN_UM: ParamSpec(
        77500,
        50000,
        150000,
        "Contracted radius R_min in micrometres.",
    ),
    Param.RADIUS_MAX_UM: ParamSpec(
        117500,
        50000,
        150000,
        "Fully expanded radius in micrometres (R_min + Delta R).",
    ),
    Param.SENSOR_GAMMA_0: ParamSpec(
        1000,
        250,
        4000,
        "Photocell A0's gamma (eq. 7) in thousandths; 1000 means gamma = 1, the law eq. 14 "
        "assumes.",
    ),
    Param.SENSOR_GAMMA_1: ParamSpec(
        1000,
        250,
        4000,
        "Photocell A1's gamma (eq. 7) in thousandths.",
    ),
    Param.SENSOR_GAMMA_2: ParamSpec(
        1000,
        250,
        4000,
        "Photocell A2's gamma (eq. 7) in thousandths.",
    ),
    Param.SENSOR_GAMMA_3: ParamSpec(
        1000,
        250,
        4000,
        "Photocell A3's gamma (eq. 7) in thousandths.",
    ),
    Param.SENSOR_GAMMA_4: ParamSpec(
        1000,
        250,
        4000,
        "Photocell A4's gamma (eq. 7) in thousandths.",
    ),
    Param.SENSOR_GAMMA_5: ParamSpec(
        1000,
        250,
        4000,
        "Photocell A5's gamma (eq. 7) in thousandths.",
    ),
    Param.SENSOR_GAIN_0: ParamSpec(
        1000,
        100,
        10000,
        "Photocell A0's gain in thousandths: the factor on its gamma-corrected resistance ratio; "
        "1000 leaves it.",
    ),
    Param.SENSOR_GAIN_1: ParamSpec(
        1000,
        100,
        10000,
        "Photocell A1's gain in thousandths.",
    ),
    Param.SENSOR_GAIN_2: ParamSpec(
        1000,
        100,
        10000,
        "Photocell A2's gain in thousandths.",
    ),
    Param.SENSOR_GAIN_3: ParamSpec(
        1000,
        100,
        10000,
        "Photocell A3's gain in thousandths.",
    ),
    Param.SENSOR_GAIN_4: ParamSpec(
        1000,
        100,
        10000,
        "Photocell A4's gain in thousandths.",
    ),
    Param.SENSOR_GAIN_5: ParamSpec(
        1000,
        100,
        10000,
        "Photocell A5's gain in thousandths.",
    ),
    Param.SERVO_CAL_0: ParamSpec(
        1000,
        500,
        2500,
        "Servo pulse (us) at calibration point 0 of 9 (R_min).",
    ),
    Param.SERVO_CAL_1: ParamSpec(
        1100,
        500,
        2500,
        "Servo pulse (us) at calibration point 1 of 9.",
    ),
    Param.SERVO_CAL_2: ParamSpec(
        1195,
        500,
        2500,
        "Servo pulse (us) at calibration point 2 of 9.",
    ),
    Param.SERVO_CAL_3: ParamSpec(
        1285,
        500,
        2500,
        "Servo pulse (us) at calibration point 3 of 9.",
    ),
    Param.SERVO_CAL_4: ParamSpec(
        1370,
        500,
        2500,
        "Servo pulse (us) at calibration point 4 of 9.",
    ),
    Param.SERVO_CAL_5: ParamSpec(
        1455,
        500,
        2500,
        "Servo pulse (us) at calibration point 5 of 9.",
    ),
    Param.SERVO_CAL_6: ParamSpec(
        1545,
        500,
        2500,
        "Servo pulse (us) at calibration point 6 of 9.",
    ),
    Param.SERVO_CAL_7: ParamSpec(
        1640,
        500,
        2500,
        "Servo pulse (us) at calibration point 7 of 9.",
    ),
    Param.SERVO_CAL_8: ParamSpec(
        1750,
        500,
        2500,
        "Servo pulse (us) at calibration point 8 of 9 (fully expanded).",
    ),
}


def _pack(layout: struct.Struct, *values: int) -> bytes:
    try:
        return layout.pack(*values)
    except struct.error as error:
        raise PayloadError(str(error)) from None


def _unpack(name: str, layout: struct.Struct, data: bytes) -> tuple[int, ...]:
    if len(data) != layout.size:
        raise PayloadError(f"{name} payload is {len(data)} bytes, not {layout.size}")
    return layout.unpack(data)


def _array(name: str, values: tuple[int, ...], count: int) -> tuple[int, ...]:
    if len(values) != count:
        raise PayloadError(f"{name} needs {count} values, got {len(values)}")
    return values


class Message:
    """Base of every message: a frozen dataclass with a fixed little-endian layout."""

    __slots__ = ()
    # Declared so type checkers accept messages in dataclasses.fields() and asdict().
    __dataclass_fields__: ClassVar[dict[str, Any]]
    MESSAGE_TYPE: ClassVar[MessageType]
    PAYLOAD_SIZE: ClassVar[int]
    SENT_BY: ClassVar[str]
    """Who sends it: "base" or "particle"."""

    def encode_payload(self) -> bytes:
        """The payload bytes; PayloadError when a field does not fit its type."""
        raise NotImplementedError

    @classmethod
    def decode_payload(cls, data: bytes) -> Self:
        """The message a payload holds; PayloadError unless it has PAYLOAD_SIZE bytes."""
        raise NotImplementedError


@dataclass(frozen=True, slots=True)
class Start(Message):
    """START: Begin coordinated locomotion. START itself is the common start: each particle runs one
    estimation round of ROUND_MS, then waits t_I and cycles. A repeated START with the same run_id
    is ignored, so the console may resend it.
    """

    MESSAGE_TYPE: ClassVar[MessageType] = MessageType.START
    PAYLOAD_SIZE: ClassVar[int] = 8
    SENT_BY: ClassVar[str] = "base"
    _LAYOUT: ClassVar[struct.Struct] = struct.Struct("<BBHBHB")

    run_id: int
    """Distinguishes runs; a particle ignores a START of the run it is already in."""
    method: int
    """Estimation method. (Method)"""
    cycle_steps: int
    """Steps of 20 ms per cycle, so T = cycle_steps * 20 ms; 0 keeps the stored CYCLE_STEPS."""
    wave_size: int
    """N of eq. 3; 0 means automatic (particles heard, else WAVE_SIZE)."""
    update_interval_s: int
    """Seconds between re-estimations; 0 keeps the stored UPDATE_INTERVAL_S."""
    phototaxis: int
    """1: Algorithm 3, stop by itself when the intensity stops increasing; 0: run until STOP."""

    def encode_payload(self) -> bytes:
        return _pack(
            self._LAYOUT,
            self.run_id,
            self.method,
            self.cycle_steps,
            self.wave_size,
            self.update_interval_s,
            self.phototaxis,
        )

    @classmethod
    def decode_payload(cls, data: bytes) -> Self:
        values = _unpack("Start", cls._LAYOUT, data)
        return cls(
            run_id=values[0],
            method=values[1],
            cycle_steps=values[2],
            wave_size=values[3],
            update_interval_s=values[4],
            phototaxis=values[5],
        )


@dataclass(frozen=True, slots=True)
class Stop(Message):
    """STOP: Stop at once: within one servo step the particle starts moving smoothly to the
    contracted state and reports STOPPING, then IDLE.
    """

    MESSAGE_TYPE: ClassVar[MessageType] = MessageType.STOP
    PAYLOAD_SIZE: ClassVar[int] = 0
    SENT_BY: ClassVar[str] = "base"
    _LAYOUT: ClassVar[struct.Struct] = struct.Struct("<")

    def encode_payload(self) -> bytes:
        return _pack(self._LAYOUT)

    @classmethod
    def decode_payload(cls, data: bytes) -> Self:
        _unpack("Stop", cls._LAYOUT, data)
        return cls()


@dataclass(frozen=True, slots=True)
class SetParam(Message):
    """SET_PARAM: Set one parameter and persist it in EEPROM. Answered by PARAM_VALUE."""

    MESSAGE_TYPE: ClassVar[MessageType] = MessageType.SET_PARAM
    PAYLOAD_SIZE: ClassVar[int] = 6
    SENT_BY: ClassVar[str] = "base"
    _LAYOUT: ClassVar[struct.Struct] = struct.Struct("<BBi")

    target: int
    """Particle id, or broadcast_id for all."""
    param: int
    """Which parameter. (Param)"""
    value: int
    """New value."""

    def encode_payload(self) -> bytes:
        return _pack(self._LAYOUT, self.target, self.param, self.value)

    @classmethod
    def decode_payload(cls, data: bytes) -> Self:
        values = _unpack("SetParam", cls._LAYOUT, data)
        return cls(target=values[0], param=values[1], value=values[2])


@dataclass(frozen=True, slots=True)
class GetParam(Message):
    """GET_PARAM: Read one parameter. Answered by PARAM_VALUE."""

    MESSAGE_TYPE: ClassVar[MessageType] = MessageType.GET_PARAM
    PAYLOAD_SIZE: ClassVar[int] = 2
    SENT_BY: ClassVar[str] = "base"
    _LAYOUT: ClassVar[struct.Struct] = struct.Struct("<BB")

    target: int
    """Particle id, or broadcast_id for all."""
    param: int
    """Which parameter. (Param)"""

    def encode_payload(self) -> bytes:
        return _pack(self._LAYOUT, self.target, self.param)

    @classmethod
    def decode_payload(cls, data: bytes) -> Self:
        values = _unpack("GetParam", cls._LAYOUT, data)
        return cls(target=values[0], param=values[1])


@dataclass(frozen=True, slots=True)
class Ping(Message):
    """PING: Ask for a STATUS frame now."""

    MESSAGE_TYPE: ClassVar[MessageType] = MessageType.PING
    PAYLOAD_SIZE: ClassVar[int] = 1
    SENT_BY: ClassVar[str] = "base"
    _LAYOUT: ClassVar[struct.Struct] = struct.Struct("<B")

    target: int
    """Particle id, or broadcast_id for all."""

    def encode_payload(self) -> bytes:
        return _pack(self._LAYOUT, self.target)

    @classmethod
    def decode_payload(cls, data: bytes) -> Self:
        values = _unpack("Ping", cls._LAYOUT, data)
        return cls(target=values[0])


@dataclass(frozen=True, slots=True)
class Identify(Message):
    """IDENTIFY: Make an idle particle wiggle three times so a person can find it; it answers with
    STATUS.
    """

    MESSAGE_TYPE: ClassVar[MessageType] = MessageType.IDENTIFY
    PAYLOAD_SIZE: ClassVar[int] = 1
    SENT_BY: ClassVar[str] = "base"
    _LAYOUT: ClassVar[struct.Struct] = struct.Struct("<B")

    target: int
    """Particle id, or broadcast_id for all."""

    def encode_payload(self) -> bytes:
        return _pack(self._LAYOUT, self.target)

    @classmethod
    def decode_payload(cls, data: bytes) -> Self:
        values = _unpack("Identify", cls._LAYOUT, data)
        return cls(target=values[0])


@dataclass(frozen=True, slots=True)
class SetId(Message):
    """SET_ID: Give one particle a new id, stored in EEPROM; it answers with STATUS from the new
    id.
    """

    MESSAGE_TYPE: ClassVar[MessageType] = MessageType.SET_ID
    PAYLOAD_SIZE: ClassVar[int] = 2
    SENT_BY: ClassVar[str] = "base"
    _LAYOUT: ClassVar[struct.Struct] = struct.Struct("<BB")

    target: int
    """Current id of the particle to rename (never broadcast_id)."""
    new_id: int
    """New id, 1..253."""

    def encode_payload(self) -> bytes:
        return _pack(self._LAYOUT, self.target, self.new_id)

    @classmethod
    def decode_payload(cls, data: bytes) -> Self:
        values = _unpack("SetId", cls._LAYOUT, data)
        return cls(target=values[0], new_id=values[1])


@dataclass(frozen=True, slots=True)
class ServoHold(Message):
    """SERVO_HOLD: Servo calibration: make one resting particle (IDLE or DONE) hold its servo at
    pulse_us for hold_s seconds, so a person can measure the radius that pulse gives. It answers at
    once with STATUS: state HOLDING and servo_pulse_us = pulse_us when the hold took effect, its
    unchanged state otherwise (running, or a pulse outside 500..2500 us). A new SERVO_HOLD moves the
    pulse and restarts the time; hold_s = 0, STOP, START or IDENTIFY end the hold, and the servo
    goes straight back to the pulse of the contracted radius. Never persisted.
    """

    MESSAGE_TYPE: ClassVar[MessageType] = MessageType.SERVO_HOLD
    PAYLOAD_SIZE: ClassVar[int] = 4
    SENT_BY: ClassVar[str] = "base"
    _LAYOUT: ClassVar[struct.Struct] = struct.Struct("<BHB")

    target: int
    """Id of the particle to hold (a broadcast is ignored)."""
    pulse_us: int
    """Servo pulse to hold, microseconds (500..2500)."""
    hold_s: int
    """Seconds to hold, at most 60 (larger values hold 60) so that a forgotten hold cannot overheat
    the servo; resend to hold longer. 0 ends a hold.
    """

    def encode_payload(self) -> bytes:
        return _pack(self._LAYOUT, self.target, self.pulse_us, self.hold_s)

    @classmethod
    def decode_payload(cls, data: bytes) -> Self:
        values = _unpack("ServoHold", cls._LAYOUT, data)
        return cls(target=values[0], pulse_us=values[1], hold_s=values[2])


@dataclass(frozen=True, slots=True)
class Status(Message):
    """STATUS: Periodic report of a particle's state, every STATUS_PERIOD_MS and on PING."""

    MESSAGE_TYPE: ClassVar[MessageType] = MessageType.STATUS
    PAYLOAD_SIZE: ClassVar[int] = 46
    SENT_BY: ClassVar[str] = "particle"
    _LAYOUT: ClassVar[struct.Struct] = struct.Struct("<BBBBBBH6HHIIIHHHHBBH")

    state: int
    """What the particle is doing. (State)"""
    method: int
    """Estimation method of the current or last run. (Method)"""
    run_id: int
    """run_id of the current or last START."""
    s_n: int
    """Actuation sequence index S_n (1 = nearest the light); 0 before the first estimate."""
    group_size: int
    """Particles heard in the last estimation round, itself included."""
    sensor_faults: int
    """Bit k set: sensor k is stuck at 0 or 1023 and left out of the intensity."""
    intensity: int
    """Mean of the healthy sensors' 50-sample averages after each one's calibration (SENSOR_GAMMA_k,
    SENSOR_GAIN_k) (0..1023).
    """
    sensors: tuple[int, ...]
    """Each sensor's 50-sample average as read, before calibration (0..1023), A0..A5."""
    cycle_phase: int
    """Position within the current expansion-contraction cycle in 1/1000 of T; 0 outside a cycle."""
    radius_um: int
    """Radius the motion commands now, micrometres (while HOLDING, the motion's contracted radius:
    the servo then gets servo_pulse_us directly).
    """
    uptime_ms: int
    """Milliseconds since reset (wraps after 49 days)."""
    definition_hash: int
    """Hash of this protocol definition the firmware was built from."""
    rx_frames: int
    """Frames received intact (saturates at 65535)."""
    rx_bad_crc: int
    """Frames dropped for a CRC mismatch."""
    rx_bad_length: int
    """Frames dropped for a length over max_payload or a truncated body."""
    rx_skipped_bytes: int
    """Bytes skipped while resynchronising on the sync marker."""
    resets: int
    """Resets counted in EEPROM (power-on, watchdog, ...), saturating."""
    last_reset_cause: int
    """MCUSR at the last reset: bit 0 power-on, 1 external, 2 brown-out, 3 watchdog."""
    servo_pulse_us: int
    """Servo pulse going out now, microseconds (through the SERVO_CAL table, or the one a SERVO_HOLD
    set).
    """

    def encode_payload(self) -> bytes:
        return _pack(
            self._LAYOUT,
            self.state,
            self.method,
            self.run_id,
            self.s_n,
            self.group_size,
            self.sensor_faults,
            self.intensity,
            *_array("sensors", self.sensors, 6),
            self.cycle_phase,
            self.radius_um,
            self.uptime_ms,
            self.definition_hash,
            self.rx_frames,
            self.rx_bad_crc,
            self.rx_bad_length,
            self.rx_skipped_bytes,
            self.resets,
            self.last_reset_cause,
            self.servo_pulse_us,
        )

    @classmethod
    def decode_payload(cls, data: bytes) -> Self:
        values = _unpack("Status", cls._LAYOUT, data)
        return cls(
            state=values[0],
            method=values[1],
            run_id=values[2],
            s_n=values[3],
            group_size=values[4],
            sensor_faults=values[5],
            intensity=values[6],
            sensors=values[7:13],
            cycle_phase=values[13],
            radius_um=values[14],
            uptime_ms=values[15],
            definition_hash=values[16],
            rx_frames=values[17],
            rx_bad_crc=values[18],
            rx_bad_length=values[19],
            rx_skipped_bytes=values[20],
            resets=values[21],
            last_reset_cause=values[22],
            servo_pulse_us=values[23],
        )


@dataclass(frozen=True, slots=True)
class Intensity(Message):
    """INTENSITY: A particle's light reading, broadcast BROADCAST_REPEATS times per estimation round
    for methods B-D.
    """

    MESSAGE_TYPE: ClassVar[MessageType] = MessageType.INTENSITY
    PAYLOAD_SIZE: ClassVar[int] = 6
    SENT_BY: ClassVar[str] = "particle"
    _LAYOUT: ClassVar[struct.Struct] = struct.Struct("<BHBH")

    run_id: int
    """run_id of the START this round belongs to."""
    round: int
    """Estimation round number within the run, 0 first."""
    repeat: int
    """Which of the BROADCAST_REPEATS copies this is, 0 first."""
    intensity: int
    """The sender's intensity for this round (0..1023)."""

    def encode_payload(self) -> bytes:
        return _pack(self._LAYOUT, self.run_id, self.round, self.repeat, self.intensity)

    @classmethod
    def decode_payload(cls, data: bytes) -> Self:
        values = _unpack("Intensity", cls._LAYOUT, data)
        return cls(run_id=values[0], round=values[1], repeat=values[2], intensity=values[3])


@dataclass(frozen=True, slots=True)
class ParamValue(Message):
    """PARAM_VALUE: Answer to SET_PARAM or GET_PARAM."""

    MESSAGE_TYPE: ClassVar[MessageType] = MessageType.PARAM_VALUE
    PAYLOAD_SIZE: ClassVar[int] = 6
    SENT_BY: ClassVar[str] = "particle"
    _LAYOUT: ClassVar[struct.Struct] = struct.Struct("<BBi")

    param: int
    """Which parameter. (Param)"""
    result: int
    """Outcome. (ParamResult)"""
    value: int
    """The value now in force (unchanged on failure)."""

    def encode_payload(self) -> bytes:
        return _pack(self._LAYOUT, self.param, self.result, self.value)

    @classmethod
    def decode_payload(cls, data: bytes) -> Self:
        values = _unpack("ParamValue", cls._LAYOUT, data)
        return cls(param=values[0], result=values[1], value=values[2])


AnyMessage: TypeAlias = (
    Start
    | Stop
    | SetParam
    | GetParam
    | Ping
    | Identify
    | SetId
    | ServoHold
    | Status
    | Intensity
    | ParamValue
)

MESSAGES: dict[int, type[Message]] = {
    MessageType.START: Start,
    MessageType.STOP: Stop,
    MessageType.SET_PARAM: SetParam,
    MessageType.GET_PARAM: GetParam,
    MessageType.PING: Ping,
    MessageType.IDENTIFY: Identify,
    MessageType.SET_ID: SetId,
    MessageType.SERVO_HOLD: ServoHold,
    MessageType.STATUS: Status,
    MessageType.INTENSITY: Intensity,
    MessageType.PARAM_VALUE: ParamValue,
}
"""Message class of each known TYPE byte."""
