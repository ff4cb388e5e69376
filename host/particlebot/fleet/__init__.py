"""The fleet file: the radio network and the roster of one experiment, shared by every tool."""

from particlebot.fleet.model import (
    CHANNELS,
    DEFAULT_CHANNEL,
    FIRST_ID,
    KEY_BYTES,
    LAST_ID,
    BaseStationRecord,
    Fleet,
    FleetError,
    FleetKey,
    ParticleRecord,
    check_id,
    normalize_address,
    timestamp,
)
from particlebot.fleet.store import (
    DEFAULT_FLEET_FILE,
    FleetFileError,
    create_fleet,
    load_fleet,
    render,
    save_fleet,
    updating_fleet,
)

__all__ = [
    "CHANNELS",
    "DEFAULT_CHANNEL",
    "DEFAULT_FLEET_FILE",
    "FIRST_ID",
    "KEY_BYTES",
    "LAST_ID",
    "BaseStationRecord",
    "Fleet",
    "FleetError",
    "FleetFileError",
    "FleetKey",
    "ParticleRecord",
    "check_id",
    "create_fleet",
    "load_fleet",
    "normalize_address",
    "render",
    "save_fleet",
    "timestamp",
    "updating_fleet",
]
