"""`particlebot fleet`: create the fleet file (network and key) and list who is in the fleet."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from particlebot.commands._common import fail
from particlebot.fleet import (
    DEFAULT_CHANNEL,
    Fleet,
    FleetError,
    FleetFileError,
    FleetKey,
    create_fleet,
    load_fleet,
    updating_fleet,
)


def integer(text: str) -> int:
    """Decimal or 0x-hex, as PAN ids and channels are written."""
    return int(text, 0)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    actions = parser.add_subparsers(dest="fleet_action", metavar="ACTION", required=True)
    init = actions.add_parser(
        "init",
        help="create the fleet file: PAN, channel and a new AES key",
        description="Creates the fleet file with a random PAN id (not the factory 0x3332), "
        "channel 0x0C and a random 128-bit AES key, mode 0600. The key is never printed.",
    )
    init.add_argument("--fleet", type=Path, default=Path("fleet.toml"), help="fleet file")
    init.add_argument("--pan", type=integer, help="PAN id, e.g. 0x1A2B (default: random)")
    init.add_argument(
        "--channel", type=integer, default=DEFAULT_CHANNEL, help="channel 0x0B-0x1A (default 0x0C)"
    )
    init.add_argument(
        "--key-file",
        help="read the key (32 hex digits) from this file, - for stdin, instead of making one "
        "(a key on the command line would end up in the shell's history)",
    )
    init.add_argument(
        "--new-key",
        action="store_true",
        help="give an existing fleet file a new key (every radio then needs `radio setup` again)",
    )
    show = actions.add_parser("show", help="the fleet's network and particles (never the key)")
    show.add_argument("--fleet", type=Path, default=Path("fleet.toml"), help="fleet file")


def run(args: argparse.Namespace) -> int:
    try:
        if args.fleet_action == "show":
            print(describe(load_fleet(args.fleet), args.fleet))
            return 0
        key = _read_key(args.key_file) if args.key_file else FleetKey.generate()
        if args.new_key:
            with updating_fleet(args.fleet) as fleet:
                fleet.key = key
            print(
                f"{args.fleet}: new key (fingerprint {key.fingerprint}); run `particlebot radio "
                "setup` for the base station and every particle"
            )
            return 0
        fleet = Fleet.new(pan_id=args.pan, channel=args.channel)
        fleet.key = key
        create_fleet(fleet, args.fleet)
    except (FleetFileError, FleetError) as exc:
        return fail(str(exc))
    print(
        f"Created {args.fleet} (mode 0600): PAN 0x{fleet.pan_id:04X}, channel "
        f"0x{fleet.channel:02X}, AES key fingerprint {fleet.key.fingerprint}"
    )
    return 0


def _read_key(source: str) -> FleetKey:
    try:
        text = sys.stdin.read() if source == "-" else Path(source).read_text(encoding="ascii")
    except OSError as exc:
        raise FleetError(f"cannot read the key from {source}: {exc.strerror}") from None
    except UnicodeDecodeError:
        raise FleetError(f"{source} does not hold a key written as hex digits") from None
    return FleetKey.from_hex(text)


def describe(fleet: Fleet, path: Path) -> str:
    lines = [
        f"{path}: PAN 0x{fleet.pan_id:04X}, channel 0x{fleet.channel:02X}, "
        f"AES key fingerprint {fleet.key.fingerprint}",
        "base station radio: "
        + (fleet.base_station.radio_address if fleet.base_station else "not set up"),
        f"{len(fleet.particles)} particle(s)",
    ]
    if fleet.particles:
        lines.append(f"{'id':>4}  {'radio':16}  {'definition':10}  {'flashed':20}  note")
    for particle_id in fleet.roster_ids():
        p = fleet.particles[particle_id]
        definition = "-" if p.definition_hash is None else f"0x{p.definition_hash:08X}"
        flashed = "-" if p.flashed_at is None else p.flashed_at.strftime("%Y-%m-%d %H:%M UTC")
        lines.append(
            f"{particle_id:>4}  {p.radio_address or '-':16}  {definition:10}  {flashed:20}  "
            f"{p.note or ''}".rstrip()
        )
    return "\n".join(lines)
