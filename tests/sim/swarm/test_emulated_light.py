"""How an emulated swarm is set up: the EEPROM preset and the light each particle sees."""

from __future__ import annotations

import struct

import pytest

from particlebot.firmware.native import NativeParticle
from particlebot.protocol import (
    BASE_STATION_ID,
    UNASSIGNED_ID,
    Param,
    SetId,
    SetParam,
    crc16,
    encode_frame,
)
from particlebot.sim import eeprom_image, light_to_millivolts

CRC_AT = 7 + 4 * 64  # settings block: header, 64 int32 slots, then its CRC
RESETS_AT = 5


def test_eeprom_preset_is_the_block_the_firmware_logic_itself_writes():
    # The firmware logic (built for the PC) given the same id and parameter over the radio.
    with NativeParticle(eeprom=None, reset_cause=1) as particle:
        particle.tick(0)
        particle.receive(encode_frame(SetId(target=UNASSIGNED_ID, new_id=42), BASE_STATION_ID, 0))
        particle.receive(
            encode_frame(SetParam(target=42, param=Param.ROUND_MS, value=1500), BASE_STATION_ID, 1)
        )
        particle.tick(1)
        stored = particle.eeprom()[: CRC_AT + 2]
    ours = bytearray(eeprom_image(42, {Param.ROUND_MS: 1500}))
    # Only the reset bookkeeping differs: it booted once, the preset has never booted.
    ours[RESETS_AT : RESETS_AT + 2] = stored[RESETS_AT : RESETS_AT + 2]
    ours[CRC_AT:] = struct.pack("<H", crc16(bytes(ours[:CRC_AT])))
    assert bytes(ours) == stored


def test_eeprom_preset_refuses_values_outside_a_parameters_range():
    with pytest.raises(ValueError):
        eeprom_image(1, {Param.ROUND_MS: 10})


def test_light_readings_become_the_divider_voltage_at_3v3():
    assert light_to_millivolts(0) == 0
    assert light_to_millivolts(1023) == 3300
    assert light_to_millivolts(980) == round(980 * 3300 / 1023)
    assert light_to_millivolts(2000) == 3300
