"""The particle's firmware logic, run on the PC through the native library (see native.py)."""

from particlebot.firmware.native import (
    EEPROM_SIZE,
    SENSOR_COUNT,
    NativeLibraryError,
    NativeParticle,
    ParseCounters,
    ParsedFrame,
    definition_hash,
    encode_frame,
    estimate,
    load_library,
    parse_stream,
)

__all__ = [
    "EEPROM_SIZE",
    "SENSOR_COUNT",
    "NativeLibraryError",
    "NativeParticle",
    "ParseCounters",
    "ParsedFrame",
    "definition_hash",
    "encode_frame",
    "estimate",
    "load_library",
    "parse_stream",
]
