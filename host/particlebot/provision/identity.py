"""A particle's id and calibration in its EEPROM image, read and changed by the firmware logic.

The EEPROM layout belongs to the firmware (firmware/lib/settings). Rather than copying it into
Python, the image read from a board is loaded into the firmware logic built for the PC
(particlebot.firmware.NativeParticle), which is then sent the same SET_ID and GET_PARAM
messages the console sends over the radio; the image it leaves behind is what goes back onto
the board. Every other setting the board held survives, and a blank or corrupt image comes out
as the firmware's defaults, exactly as the particle itself would rebuild it.

One side effect: loading an image counts as a boot, so the particle's reset counter goes up by
one (with cause 0, which is also what a particle reads after Caterina starts it).
"""

from __future__ import annotations

from particlebot.errors import ParticlebotError
from particlebot.firmware import NativeParticle
from particlebot.protocol import (
    BASE_STATION_ID,
    UNASSIGNED_ID,
    GetParam,
    Message,
    Param,
    ParamResult,
    ParamValue,
    SetId,
    StreamDecoder,
    encode_frame,
)

CALIBRATION_PREFIX = "SERVO_CAL_"
"""Parameters that calibrate one particle's body (the servo table) rather than configure a run."""
# The bootloader's MCUSR is cleared before the firmware starts: a flashed particle reads 0.
_RESET_CAUSE = 0
_REPLY_WAIT_MS = 50


class IdentityError(ParticlebotError, ValueError):
    """The firmware logic refused the change (an id outside 1..253)."""


def id_in(eeprom: bytes) -> int:
    """The id a particle with this EEPROM reports (UNASSIGNED_ID for a blank or corrupt one)."""
    with NativeParticle(eeprom, reset_cause=_RESET_CAUSE) as particle:
        return particle.id


def with_id(eeprom: bytes, new_id: int) -> bytes:
    """The EEPROM image after the particle is told SET_ID new_id; its other settings unchanged."""
    with NativeParticle(eeprom, reset_cause=_RESET_CAUSE) as particle:
        particle.receive(encode_frame(SetId(target=particle.id, new_id=new_id), BASE_STATION_ID, 1))
        particle.tick(_REPLY_WAIT_MS)
        if particle.id != new_id:
            raise IdentityError(f"the firmware refused id {new_id} (ids are 1..253)")
        image = particle.eeprom()
    return image + eeprom[len(image) :]


def calibration(eeprom: bytes) -> dict[str, int]:
    """The calibration parameters this EEPROM holds, by name, as GET_PARAM reports them."""
    values: dict[str, int] = {}
    with NativeParticle(eeprom, reset_cause=_RESET_CAUSE) as particle:
        own_id = particle.id
        decoder = StreamDecoder()
        now = 0
        for seq, param in enumerate(p for p in Param if p.name.startswith(CALIBRATION_PREFIX)):
            particle.receive(
                encode_frame(GetParam(target=own_id, param=param), BASE_STATION_ID, seq)
            )
            now += _REPLY_WAIT_MS
            particle.tick(now)
            for frame in decoder.feed(particle.transmit()):
                reply: Message | None = frame.message
                if (
                    isinstance(reply, ParamValue)
                    and reply.param == param
                    and reply.result == ParamResult.OK
                ):
                    values[param.name] = reply.value
    return values


def is_assigned(particle_id: int) -> bool:
    return particle_id != UNASSIGNED_ID
