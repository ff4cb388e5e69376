"""`particlebot radio setup`: an XBee (base station's or a particle's) configured for the fleet."""

from __future__ import annotations

import argparse
from pathlib import Path

from particlebot.commands._common import fail
from particlebot.fleet import (
    BaseStationRecord,
    FleetError,
    FleetFileError,
    ParticleRecord,
    check_id,
    load_fleet,
    timestamp,
    updating_fleet,
)
from particlebot.options import Bounds, float_arg

GUARD_TIME = Bounds(minimum=0, maximum=10)
"""Seconds of silence around +++: a Series 1 radio's GT is at most 0xCE4 ms (3.3 s), so more is a
typo; NaN or infinity would wait for ever."""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    actions = parser.add_subparsers(dest="radio_action", metavar="ACTION", required=True)
    setup = actions.add_parser(
        "setup",
        help="configure an XBee Series 1 for the fleet (through an XBee Explorer)",
        description="Sets PAN, channel, MY=FFFE, DL=FFFF, 9600 baud, NI, AES (EE=1, KY = the "
        "fleet's key), reads every value back, writes them to the radio's memory and records "
        "its 64-bit address in the fleet file. The radio must be at 9600 baud (the factory "
        "setting); it may be in transparent or API mode.",
    )
    who = setup.add_mutually_exclusive_group(required=True)
    who.add_argument("--base", action="store_true", help="the base station's radio (API mode)")
    who.add_argument(
        "--particle", type=int, metavar="ID", help="the radio of particle ID (transparent mode)"
    )
    setup.add_argument("--port", required=True, help="the radio's serial port, e.g. /dev/ttyUSB0")
    setup.add_argument("--fleet", type=Path, default=Path("fleet.toml"), help="fleet file")
    setup.add_argument(
        "--guard-time",
        type=float_arg(GUARD_TIME),
        default=1.1,
        help="seconds of silence around +++ (the radio's GT, 1 s from the factory, plus margin)",
    )


def run(args: argparse.Namespace) -> int:
    # digi-xbee is imported here, so that building the parser for another command stays quick.
    from particlebot.provision.xbee_setup import BASE_NODE_ID, RadioPlan, Role, XBeeSetup
    from particlebot.radio import RadioError

    try:
        fleet = load_fleet(args.fleet)
        if args.particle is not None:
            check_id(args.particle)
    except (FleetFileError, FleetError) as exc:
        return fail(str(exc))
    role = Role.BASE if args.base else Role.PARTICLE
    node_id = BASE_NODE_ID if args.base else str(args.particle)
    plan = RadioPlan(role, node_id, fleet.pan_id, fleet.channel, fleet.key)
    who = "the base station" if args.base else f"particle {args.particle}"
    print(f"Setting up the XBee on {args.port} for {who}...")
    try:
        result = XBeeSetup(args.port, guard_s=args.guard_time).run(plan)
    except RadioError as exc:
        return fail(str(exc))
    print("Set, read back and saved: " + ", ".join(result.checked))
    try:
        moved_from = _record(args, result.address)
    except (FleetFileError, FleetError) as exc:
        return fail(f"the radio is set up, but recording it failed: {exc}")
    print(f"Radio {result.address} recorded for {who} in {args.fleet}{moved_from}")
    if args.particle is not None and fleet.get(args.particle) is None:
        print(
            f"Note: particle {args.particle} has not been flashed into this fleet yet "
            f"(particlebot flash --id {args.particle} gives a board that id)"
        )
    return 0


def _record(args: argparse.Namespace, address: str) -> str:
    """Writes the radio's address into the fleet; says where it was recorded before, if anywhere."""
    now = timestamp()
    with updating_fleet(args.fleet) as fleet:
        previous = fleet.by_radio_address(address)
        note = ""
        if previous is not None and previous.id != args.particle:
            previous.radio_address = None
            note = f" (it was particle {previous.id}'s radio before)"
        if args.base:
            fleet.base_station = BaseStationRecord(address, now)
            return note
        if fleet.base_station is not None and fleet.base_station.radio_address == address:
            fleet.base_station = None
            note = " (it was the base station's radio before)"
        record = fleet.get(args.particle) or ParticleRecord(args.particle)
        record.radio_address = address
        record.radio_configured_at = now
        fleet.record(record)
        return note
