"""The fleet file (TOML, in the experiment folder): read, checked, and rewritten atomically as 0600.

The file holds the radios' AES key, so it is only ever written whole, through a private temporary
file renamed over the old one (a crash leaves either the old or the new file, never half of
one), with mode 0600, and refused when others can read it. Tools that change it (flash, radio
setup) hold an exclusive lock on its folder while they read, change and write it, so two of them
running at once cannot lose each other's records.
"""

from __future__ import annotations

import contextlib
import datetime as dt
import os
import stat
import tomllib
from collections.abc import Iterator, Mapping, MutableMapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import tomlkit
import tomlkit.exceptions
from tomlkit.items import Integer, Item, Trivia

from particlebot.errors import ParticlebotError
from particlebot.fileio import cannot_write, write_text
from particlebot.fleet.model import (
    BaseStationRecord,
    Fleet,
    FleetError,
    FleetKey,
    ParticleRecord,
    PhotocellLaw,
)

try:
    import fcntl
except ImportError:  # Windows: no advisory locks; one tool at a time
    fcntl = None  # type: ignore[assignment]

DEFAULT_FLEET_FILE = Path("fleet.toml")
FORMAT_VERSION = 1
PRIVATE_MODE = 0o600

_HEADER = """\
particlebot fleet file: the radio network of one experiment and every particle in it.
Written by `particlebot fleet init`, `particlebot flash`, `particlebot radio setup` and
`particlebot calibrate`; values may be edited by hand, and comments are kept. It holds the
radios' AES key: keep it private (mode 0600, which the tools insist on) and out of version
control."""

_PARTICLE_KEYS = (
    "board_serial",
    "radio_address",
    "definition_hash",
    "image_sha256",
    "flashed_at",
    "radio_configured_at",
    "note",
    "calibration",
)


class FleetFileError(ParticlebotError):
    """The fleet file is missing, unreadable, malformed or too open; the message says what to do."""


# ---- reading -------------------------------------------------------------------------------------


def load_fleet(path: Path) -> Fleet:
    """The fleet in path; FleetFileError (one line, with what to do) when it cannot be used."""
    try:
        info = path.stat()
    except FileNotFoundError:
        raise FleetFileError(
            f"no fleet file {path}: create one with `particlebot fleet init` (or name it with "
            "--fleet)"
        ) from None
    except OSError as exc:
        raise FleetFileError(f"cannot read {path}: {exc.strerror}") from None
    check_private(path, info.st_mode)
    try:
        document = tomllib.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise FleetFileError(f"cannot read {path}: {exc.strerror}") from None
    except UnicodeDecodeError:
        raise FleetFileError(f"{path} is not a text file") from None
    except tomllib.TOMLDecodeError as exc:
        raise FleetFileError(f"{path} is not valid TOML: {exc}") from None
    try:
        return _fleet_from(document)
    except (FleetError, TypeError, ValueError) as exc:
        raise FleetFileError(f"{path}: {exc}") from None


def check_private(path: Path, mode: int) -> None:
    if os.name == "nt":
        return
    if mode & (stat.S_IRWXG | stat.S_IRWXO):
        raise FleetFileError(
            f"{path} holds the radios' AES key but others may read it (mode "
            f"{stat.S_IMODE(mode):04o}): run `chmod 600 {path}`, and make a new key with "
            "`particlebot fleet init --new-key` if someone else may have read it"
        )


def _fleet_from(document: Mapping[str, Any]) -> Fleet:
    _only(document, ("version", "radio", "base_station", "photocells", "particles"), "the file")
    version = document.get("version", FORMAT_VERSION)
    if version != FORMAT_VERSION:
        raise FleetError(f"format version {version} is not {FORMAT_VERSION}; update particlebot")
    radio = _table(document, "radio", required=True)
    _only(radio, ("pan_id", "channel", "key"), "[radio]")
    fleet = Fleet(
        pan_id=_int(radio, "pan_id", "[radio]"),
        channel=_int(radio, "channel", "[radio]"),
        key=FleetKey.from_hex(_str(radio, "key", "[radio]")),
    )
    base = _table(document, "base_station", required=False)
    if base:
        _only(base, ("radio_address", "radio_configured_at"), "[base_station]")
        fleet.base_station = BaseStationRecord(
            radio_address=_str(base, "radio_address", "[base_station]"),
            radio_configured_at=_time(base, "radio_configured_at", "[base_station]"),
        )
    law = _table(document, "photocells", required=False)
    if law:
        _only(law, ("scale", "unit", "calibrated_at"), "[photocells]")
        scale = law.get("scale")
        if not isinstance(scale, int | float) or isinstance(scale, bool):
            raise FleetError("[photocells]: scale must be a number")
        fleet.photocells = PhotocellLaw(
            scale=float(scale),
            unit=_str(law, "unit", "[photocells]"),
            calibrated_at=_time(law, "calibrated_at", "[photocells]"),
        )
    for name, entry in _table(document, "particles", required=False).items():
        where = f"[particles.{name}]"
        if not isinstance(entry, dict):
            raise FleetError(f"{where} must be a table")
        try:
            particle_id = int(name)
        except ValueError:
            raise FleetError(f"{where}: particles are keyed by their id (1..253)") from None
        _only(entry, _PARTICLE_KEYS, where)
        calibration = entry.get("calibration", {})
        if not isinstance(calibration, dict) or not all(
            isinstance(v, int) and not isinstance(v, bool) for v in calibration.values()
        ):
            raise FleetError(f"{where}: calibration must be a table of integers")
        fleet.record(
            ParticleRecord(
                id=particle_id,
                board_serial=_str(entry, "board_serial", where, optional=True),
                radio_address=_str(entry, "radio_address", where, optional=True),
                definition_hash=_int(entry, "definition_hash", where, optional=True),
                image_sha256=_str(entry, "image_sha256", where, optional=True),
                flashed_at=_time(entry, "flashed_at", where),
                radio_configured_at=_time(entry, "radio_configured_at", where),
                note=_str(entry, "note", where, optional=True),
                calibration=dict(calibration),
            )
        )
    _check_addresses(fleet)
    return fleet


def _check_addresses(fleet: Fleet) -> None:
    """FleetError when two radios of the fleet share an address: frames for one would reach
    the other, and the roster could not tell them apart."""
    holders: dict[str, str] = {}
    if fleet.base_station is not None:
        holders[fleet.base_station.radio_address] = "[base_station]"
    for particle_id, particle in sorted(fleet.particles.items()):
        address = particle.radio_address
        if address is None:
            continue
        where = f"[particles.{particle_id}]"
        if address in holders:
            raise FleetError(f"{where}: radio_address {address} is {holders[address]}'s already")
        holders[address] = where


def _only(table: Mapping[str, Any], known: tuple[str, ...], where: str) -> None:
    unknown = sorted(set(table) - set(known))
    if unknown:
        raise FleetError(f"unknown key {unknown[0]!r} in {where} (known: {', '.join(known)})")


def _table(document: Mapping[str, Any], name: str, *, required: bool) -> dict[str, Any]:
    table = document.get(name)
    if table is None:
        if required:
            raise FleetError(f"[{name}] is missing")
        return {}
    if not isinstance(table, dict):
        raise FleetError(f"{name} must be a table")
    return table


def _int(table: Mapping[str, Any], name: str, where: str, *, optional: bool = False) -> Any:
    return _typed(table, name, where, int, "an integer", optional)


def _str(table: Mapping[str, Any], name: str, where: str, *, optional: bool = False) -> Any:
    return _typed(table, name, where, str, "a string", optional)


def _typed(
    table: Mapping[str, Any], name: str, where: str, kind: type, called: str, optional: bool
) -> Any:
    item = table.get(name)
    if item is None and optional:
        return None
    if not isinstance(item, kind) or isinstance(item, bool):
        raise FleetError(f"{where}: {name} must be {called}")
    return item


def _time(table: Mapping[str, Any], name: str, where: str) -> dt.datetime | None:
    item = table.get(name)
    if item is None:
        return None
    if not isinstance(item, dt.datetime) or item.tzinfo is None:
        raise FleetError(f"{where}: {name} must be a date and time with its UTC offset")
    return item


# ---- writing -------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Hex:
    """An integer written in hexadecimal with at least `digits` digits (TOML reads it as int)."""

    value: int
    digits: int


Value = str | int | float | bool | Hex | dt.datetime
Tableish = MutableMapping[str, Any]
"""A TOML document or table as tomlkit gives it (a mapping that remembers its layout)."""


def render(fleet: Fleet, previous: str | None = None) -> str:
    """The fleet as the text of a fleet file. With previous (the file's text as it is now), the
    file is changed in place: a value that did not change keeps its spelling, and comments, key
    order and blank lines a person wrote stay where they are."""
    document = tomlkit.parse(previous) if previous else _new_document()
    _merge(document, {"version": FORMAT_VERSION})
    radio: dict[str, Value | None] = {
        "pan_id": Hex(fleet.pan_id, 4),
        "channel": Hex(fleet.channel, 2),
        "key": fleet.key.secret_hex(),
    }
    _merge(_layout_table(document, "radio"), radio)
    base = fleet.base_station
    if base is None:
        document.pop("base_station", None)
    else:
        values: dict[str, Value | None] = {
            "radio_address": base.radio_address,
            "radio_configured_at": base.radio_configured_at,
        }
        _merge(_layout_table(document, "base_station"), values)
    law = fleet.photocells
    if law is None:
        document.pop("photocells", None)
    else:
        cells: dict[str, Value | None] = {
            "scale": law.scale,
            "unit": law.unit,
            "calibrated_at": law.calibrated_at,
        }
        _merge(_layout_table(document, "photocells"), cells)
    roster = [str(particle_id) for particle_id in fleet.roster_ids()]
    if not roster:
        document.pop("particles", None)
        return tomlkit.dumps(document)
    particles = _layout_table(document, "particles", super_table=True)
    for name in [name for name in particles if name not in roster]:
        del particles[name]
    for particle_id, name in zip(fleet.roster_ids(), roster, strict=True):
        particle = fleet.particles[particle_id]
        hashed = particle.definition_hash
        table = _layout_table(particles, name)
        _merge(
            table,
            {
                "board_serial": particle.board_serial,
                "radio_address": particle.radio_address,
                "definition_hash": None if hashed is None else Hex(hashed, 8),
                "image_sha256": particle.image_sha256,
                "flashed_at": particle.flashed_at,
                "radio_configured_at": particle.radio_configured_at,
                "note": particle.note,
            },
        )
        if particle.calibration:
            _merge(
                _layout_table(table, "calibration"), dict(particle.calibration), drop_others=True
            )
        else:
            table.pop("calibration", None)
    return tomlkit.dumps(document)


def _new_document() -> tomlkit.TOMLDocument:
    document = tomlkit.document()
    for line in _HEADER.splitlines():
        document.add(tomlkit.comment(line))
    document.add(tomlkit.nl())
    return document


def _layout_table(parent: Tableish, name: str, *, super_table: bool = False) -> Tableish:
    """parent's table name, added at the end when it is not there yet."""
    if name not in parent:
        parent[name] = tomlkit.table(is_super_table=super_table or None)
    table = parent[name]
    assert isinstance(table, MutableMapping)
    return table


def _merge(
    table: Tableish, values: Mapping[str, Value | None], *, drop_others: bool = False
) -> None:
    """Sets each value in table; None removes the key. A key whose value is unchanged is left
    alone, so that its spelling (decimal or hex, quotes) and comment stay as written. With
    drop_others, keys not in values go (a calibration table holds exactly what it holds)."""
    if drop_others:
        for name in [name for name in table if name not in values]:
            del table[name]
    for name, value in values.items():
        if value is None:
            table.pop(name, None)
            continue
        plain = value.value if isinstance(value, Hex) else value
        current = _unwrap(table.get(name))
        # bool is an int and 1 == 1.0: equal values of another type are written anew.
        if current == plain and type(current) is type(plain):
            continue
        if isinstance(value, Hex):
            if value.value < 0:
                raise ValueError("hexadecimal TOML integers cannot be negative")
            table[name] = Integer(value.value, Trivia(), f"0x{value.value:0{value.digits}X}")
        else:
            table[name] = value


def _unwrap(item: object) -> object:
    return item.unwrap() if isinstance(item, Item) else item


def save_fleet(fleet: Fleet, path: Path) -> None:
    """Writes the whole file atomically with mode 0600, keeping what a person wrote in it."""
    try:
        previous: str | None = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError):  # none yet, or one being replaced whole
        previous = None
    try:
        text = render(fleet, previous)
    except tomlkit.exceptions.TOMLKitError:  # not TOML: written afresh, as a new file is
        text = render(fleet)
    try:
        write_text(path, text, mode=PRIVATE_MODE)
    except OSError as exc:  # a file where the folder should be, read-only, /proc
        raise FleetFileError(str(cannot_write(path, exc))) from None


def create_fleet(fleet: Fleet, path: Path, *, replace: bool = False) -> None:
    """Writes a new fleet file; FleetFileError when one exists already (unless replace)."""
    with _locked(path):
        if path.exists() and not replace:
            raise FleetFileError(
                f"{path} exists already; `particlebot fleet show` lists it (--new-key makes a new "
                "key for it)"
            )
        save_fleet(fleet, path)


@contextlib.contextmanager
def updating_fleet(path: Path) -> Iterator[Fleet]:
    """Reads the fleet under an exclusive lock, lets the caller change it, and writes it back
    (only if the block ends without an exception)."""
    with _locked(path):
        fleet = load_fleet(path)
        yield fleet
        save_fleet(fleet, path)


@contextlib.contextmanager
def _locked(path: Path) -> Iterator[None]:
    # The folder is locked rather than the file, because the file is replaced by each write.
    if fcntl is None:
        yield
        return
    directory = path.parent if str(path.parent) else Path(".")
    try:
        fd = os.open(directory, os.O_RDONLY)
    except OSError as exc:
        raise FleetFileError(f"cannot open the folder of {path}: {exc.strerror}") from None
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        os.close(fd)  # releases the lock
