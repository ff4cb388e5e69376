"""The fleet of one experiment: its radio network (PAN, channel, AES key) and its particles."""

from __future__ import annotations

import datetime as dt
import hashlib
import math
import re
import secrets
from dataclasses import dataclass, field

from particlebot.errors import ParticlebotError
from particlebot.protocol import BASE_STATION_ID, BROADCAST_ID, UNASSIGNED_ID

# Ids the protocol leaves to particles: everything but the base station's, the unassigned one
# and broadcast, which sit at the two ends of the byte.
assert BASE_STATION_ID < UNASSIGNED_ID < BROADCAST_ID
FIRST_ID = BASE_STATION_ID + 1
LAST_ID = UNASSIGNED_ID - 1

KEY_BYTES = 16
"""802.15.4 encrypts with AES-128: the XBee's KY is 16 bytes."""
CHANNELS = range(0x0B, 0x1B)
"""XBee Series 1 channels (CH); the XBee-PRO S1 only has 0x0C-0x17."""
DEFAULT_CHANNEL = 0x0C
"""A channel every Series 1 radio, PRO or not, has."""
PAN_IDS = range(0x0000, 0xFFFF)
"""ID: any 16-bit PAN but 0xFFFF (802.15.4's broadcast PAN)."""
FACTORY_PAN_ID = 0x3332
"""Every XBee leaves the factory on this PAN; a fleet avoids it, so as not to hear strangers."""


class FleetError(ParticlebotError, ValueError):
    """A value that cannot be in a fleet; the message says which and why."""


class FleetKey:
    """The radios' AES key. Never shown: repr() and str() hide it, so it cannot reach a log."""

    __slots__ = ("_key",)

    def __init__(self, key: bytes) -> None:
        if len(key) != KEY_BYTES:
            raise FleetError(
                f"the AES key must be {KEY_BYTES} bytes ({2 * KEY_BYTES} hex digits), "
                f"not {len(key)}"
            )
        self._key = bytes(key)

    @classmethod
    def generate(cls) -> FleetKey:
        return cls(secrets.token_bytes(KEY_BYTES))

    @classmethod
    def from_hex(cls, text: str) -> FleetKey:
        digits = text.strip().replace(" ", "").replace(":", "")
        if not re.fullmatch(r"[0-9A-Fa-f]*", digits) or len(digits) % 2:
            raise FleetError(
                f"the AES key must be {2 * KEY_BYTES} hex digits (0-9, A-F); "
                f"what was given is not hex"
            )
        return cls(bytes.fromhex(digits))

    def secret_bytes(self) -> bytes:
        """The key itself, for the radio and the fleet file only."""
        return self._key

    def secret_hex(self) -> str:
        return self._key.hex().upper()

    @property
    def fingerprint(self) -> str:
        """Eight hex digits of the key's SHA-256: tells two keys apart without revealing them."""
        return hashlib.sha256(self._key).hexdigest()[:8].upper()

    def __eq__(self, other: object) -> bool:
        return isinstance(other, FleetKey) and secrets.compare_digest(self._key, other._key)

    def __hash__(self) -> int:
        return hash(self._key)

    def __repr__(self) -> str:
        return f"FleetKey(<hidden, fingerprint {self.fingerprint}>)"

    __str__ = __repr__


def timestamp() -> dt.datetime:
    """Now, in UTC, to the second: how the fleet file dates what the tools did."""
    return dt.datetime.now(dt.UTC).replace(microsecond=0)


def normalize_address(address: str) -> str:
    """A 64-bit radio address as 16 upper-case hex digits (SH then SL)."""
    digits = address.strip().upper().removeprefix("0X").replace(":", "").replace(" ", "")
    if not re.fullmatch(r"[0-9A-F]{1,16}", digits):
        raise FleetError(f"'{address}' is not a 64-bit radio address (16 hex digits)")
    return digits.rjust(16, "0")


def check_id(particle_id: int) -> int:
    if not FIRST_ID <= particle_id <= LAST_ID:
        raise FleetError(f"particle ids are {FIRST_ID}..{LAST_ID}, not {particle_id}")
    return particle_id


@dataclass
class ParticleRecord:
    """What the tools know about one particle; None where nothing is known yet."""

    id: int
    board_serial: str | None = None
    """The USB serial number the board reported, when it reports one."""
    radio_address: str | None = None
    """The 64-bit address of the XBee on this particle."""
    definition_hash: int | None = None
    """Protocol definition hash of the firmware flashed (what its STATUS reports)."""
    image_sha256: str | None = None
    """SHA-256 of the flashed Intel HEX file."""
    flashed_at: dt.datetime | None = None
    radio_configured_at: dt.datetime | None = None
    note: str | None = None
    """Free text for people ("left wheel sticks"); the tools keep it."""
    calibration: dict[str, int] = field(default_factory=dict)
    """Calibration parameters in its EEPROM, by parameter name: the servo table as flashed or
    calibrated, the photocells' SENSOR_GAMMA_k and SENSOR_GAIN_k, REF_VALUE."""

    def __post_init__(self) -> None:
        check_id(self.id)
        if self.radio_address is not None:
            self.radio_address = normalize_address(self.radio_address)


PHOTOCELL_UNITS = {
    "m2": "x is r^2 in square metres, r from the lamp to the photocells",
    "1/lux": "x is 1 / the illuminance in lux",
}
"""What the light level x of a fleet's photocell law rho' = scale * x is measured in."""


@dataclass
class PhotocellLaw:
    """The law every calibrated photocell of the fleet follows after its SENSOR_GAMMA_k and
    SENSOR_GAIN_k: rho' = scale * x (rho' the corrected resistance over the load's), so that
    eq. 14 holds across the fleet. Particles calibrated later join it."""

    scale: float
    unit: str = "m2"
    calibrated_at: dt.datetime | None = None

    def __post_init__(self) -> None:
        if not (math.isfinite(self.scale) and self.scale > 0):
            raise FleetError(f"the photocell scale must be a number above 0, not {self.scale}")
        if self.unit not in PHOTOCELL_UNITS:
            raise FleetError(
                f"the photocell unit must be {' or '.join(map(repr, PHOTOCELL_UNITS))}, "
                f"not {self.unit!r}"
            )


@dataclass
class BaseStationRecord:
    radio_address: str
    radio_configured_at: dt.datetime | None = None

    def __post_init__(self) -> None:
        self.radio_address = normalize_address(self.radio_address)


@dataclass
class Fleet:
    """The radio network and the roster. The console and the tools share this one model."""

    pan_id: int
    channel: int
    key: FleetKey
    base_station: BaseStationRecord | None = None
    particles: dict[int, ParticleRecord] = field(default_factory=dict)
    photocells: PhotocellLaw | None = None
    """Set by `particlebot calibrate sensors`."""

    def __post_init__(self) -> None:
        if self.pan_id not in PAN_IDS:
            raise FleetError(f"PAN id 0x{self.pan_id:X} is outside 0x0000-0xFFFE")
        if self.channel not in CHANNELS:
            raise FleetError(
                f"channel 0x{self.channel:X} is not an XBee Series 1 channel "
                f"(0x{CHANNELS.start:X}-0x{CHANNELS.stop - 1:X}; XBee-PRO: 0x0C-0x17)"
            )

    @classmethod
    def new(cls, *, pan_id: int | None = None, channel: int = DEFAULT_CHANNEL) -> Fleet:
        """A fleet with a fresh random key and, unless given, a random PAN id."""
        if pan_id is None:
            pan_id = FACTORY_PAN_ID
            while pan_id == FACTORY_PAN_ID:
                pan_id = 1 + secrets.randbelow(PAN_IDS.stop - 2)
        return cls(pan_id=pan_id, channel=channel, key=FleetKey.generate())

    # ---- the roster --------------------------------------------------------------------------

    def roster_ids(self) -> list[int]:
        return sorted(self.particles)

    def get(self, particle_id: int) -> ParticleRecord | None:
        return self.particles.get(particle_id)

    def by_radio_address(self, address: str) -> ParticleRecord | None:
        wanted = normalize_address(address)
        for particle in self.particles.values():
            if particle.radio_address == wanted:
                return particle
        return None

    def next_free_id(self) -> int:
        for candidate in range(FIRST_ID, LAST_ID + 1):
            if candidate not in self.particles:
                return candidate
        raise FleetError(f"the fleet is full: every id {FIRST_ID}..{LAST_ID} is taken")

    def record(self, particle: ParticleRecord) -> None:
        """Adds the particle, or replaces the record of the same id."""
        self.particles[particle.id] = particle

    def forget(self, particle_id: int) -> ParticleRecord | None:
        return self.particles.pop(particle_id, None)
