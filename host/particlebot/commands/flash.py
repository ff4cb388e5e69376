"""`particlebot flash`: firmware onto Fio v3 boards over USB, each given an id the fleet records."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING

from particlebot import resources
from particlebot.commands._common import fail
from particlebot.errors import ParticlebotError
from particlebot.fleet import FleetError, FleetFileError, check_id, load_fleet
from particlebot.options import NON_NEGATIVE, Bounds, float_arg, int_arg
from particlebot.protocol import DEFINITION_HASH

if TYPE_CHECKING:
    from particlebot.provision.boards import BoardPort, UsbBus
    from particlebot.provision.flashing import Flasher, FlashPlan, Timing, Uploader
    from particlebot.provision.image import FirmwareImage

# What `make firmware` builds in a clone, or the image an installed wheel carries.
DEFAULT_IMAGE = resources.firmware_image()


class UsageError(ParticlebotError, ValueError):
    """Options that do not go together."""


INTERRUPTED = (
    "interrupted; a board interrupted while uploading may hold part of the image: flash it again"
)
PLUG_IN_HINT = (
    "plug in a Fio v3 (if its firmware has no USB serial, press its reset button after plugging "
    "it in: the bootloader then waits 8 s)"
)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--firmware",
        type=Path,
        default=DEFAULT_IMAGE,
        help=f"Intel HEX image (default: {DEFAULT_IMAGE})",
    )
    parser.add_argument("--fleet", type=Path, default=Path("fleet.toml"), help="fleet file")
    parser.add_argument(
        "--id",
        type=int,
        help="give the particle this id (default: it keeps "
        "the id it has, or gets the fleet's next free one)",
    )
    parser.add_argument(
        "--renumber",
        action="store_true",
        help="give boards that already have an id the next free one",
    )
    parser.add_argument(
        "--force",
        action="store_true",
        help="with --id: even if the fleet has that id (a replacement board)",
    )
    parser.add_argument(
        "--many",
        action="store_true",
        help="flash boards one after another as they are plugged in (Ctrl-C ends)",
    )
    parser.add_argument(
        "--count",
        type=int_arg(Bounds(minimum=1)),
        help="with --many: stop after this many boards",
    )
    parser.add_argument(
        "--port",
        help="the board's serial port, running or in its bootloader "
        "(a port that is not a Fio v3's is taken to be a bootloader)",
    )
    parser.add_argument(
        "--wait",
        type=float_arg(NON_NEGATIVE),
        default=30.0,
        help="seconds to wait for a board to appear (default 30)",
    )
    parser.add_argument(
        "--no-check",
        action="store_true",
        help="skip running the image in the emulator before flashing",
    )


def run(
    args: argparse.Namespace,
    *,
    usb: UsbBus | None = None,
    uploader: Uploader | None = None,
    timing: Timing | None = None,
) -> int:
    """The command; usb, uploader and timing stand in for the system's in tests."""
    # Imported here, so that building the parser for another command stays quick.
    from particlebot.firmware import NativeLibraryError, load_library
    from particlebot.provision.avrdude import Avrdude, AvrdudeError
    from particlebot.provision.boards import SystemUsb
    from particlebot.provision.flashing import Flasher
    from particlebot.provision.image import ImageError
    from particlebot.sim.particles.emulated.boot import BootError

    try:
        plan = _plan(args)
        uploader = uploader or Avrdude()
        load_library()  # ids are given through the firmware logic: check it loads before a board
    except (
        UsageError,
        ImageError,
        FleetFileError,
        FleetError,
        AvrdudeError,
        BootError,
        NativeLibraryError,
    ) as exc:
        return fail(str(exc))
    usb = usb or SystemUsb()
    flasher = Flasher(usb, uploader, plan, timing=timing)
    if args.many:
        return _flash_many(flasher, args.count)
    try:
        board = _one_board(flasher, usb, args)
        if isinstance(board, str):
            return fail(board)
        outcome = flasher.flash(board)
    except KeyboardInterrupt:
        return fail(INTERRUPTED)
    print(outcome.line())
    return 0 if outcome.ok else 1


def _plan(args: argparse.Namespace) -> FlashPlan:
    from particlebot.provision.flashing import FlashPlan
    from particlebot.provision.image import FirmwareImage

    if args.many and args.port:
        raise UsageError("--port names one board; --many finds each board on USB")
    if args.many and args.id is not None:
        raise UsageError("--id gives one board its id; --many numbers boards from the fleet")
    if args.count is not None and not args.many:
        raise UsageError("--count goes with --many")
    fleet = load_fleet(args.fleet)
    if args.id is not None:
        check_id(args.id)
        if fleet.get(args.id) is not None and not args.force:
            raise FleetError(
                f"id {args.id} is taken in {args.fleet}; re-flashing that particle keeps its id "
                "without --id, and --force gives the id to this board anyway"
            )
    image = FirmwareImage.load(args.firmware)
    definition_hash = None if args.no_check else _check_image(image)
    return FlashPlan(image, args.fleet, definition_hash, args.id, args.renumber)


def _check_image(image: FirmwareImage) -> int | None:
    """Runs the image in the emulator: a particle firmware answers PING with its definition hash."""
    from particlebot.sim.particles.emulated.boot import (
        BootError,
        EmulatorMissingError,
        boot_and_ping,
    )

    try:
        report = boot_and_ping(image.flash)
    except EmulatorMissingError as exc:
        print(f"{image.path}: {image.size:,} B; its definition hash is not recorded ({exc})")
        return None
    except BootError as exc:
        raise BootError(f"{image.path}: {exc} (--no-check flashes it anyway)") from None
    found = report.status.definition_hash
    note = (
        ""
        if found == DEFINITION_HASH
        else (f"; NOT this host's 0x{DEFINITION_HASH:08X}: the console will flag these particles")
    )
    print(f"{image.path}: {image.size:,} B, protocol definition 0x{found:08X}{note}")
    return found


def _one_board(flasher: Flasher, usb: UsbBus, args: argparse.Namespace) -> BoardPort | str:
    """The board to flash, or why there is none."""
    from particlebot.provision.boards import BoardMode, BoardPort

    if args.port:
        for listed in usb.boards():
            if listed.device == args.port:
                return listed
        return BoardPort(args.port, BoardMode.BOOTLOADER)
    boards = usb.boards()
    if len(boards) > 1:
        names = ", ".join(f"{b.device} ({b.mode.value})" for b in boards)
        return f"{len(boards)} Fio v3 boards found ({names}): name one with --port, or use --many"
    if not boards and args.wait > 0:
        print(f"Waiting up to {args.wait:.0f} s for a board: {PLUG_IN_HINT}")
    found = flasher.wait_for_board(args.wait)
    if found is None:
        return (
            "no Fio v3 found on USB (1B4F:F101 running, 1B4F:F100 bootloader): "
            f"{PLUG_IN_HINT}, or name its port with --port"
        )
    return found


def _flash_many(flasher: Flasher, count: int | None) -> int:
    from particlebot.provision.flashing import summary

    print(f"Flashing one board after another: {PLUG_IN_HINT}. Ctrl-C when done.")
    try:
        flasher.flash_many(count=count)
    except KeyboardInterrupt:
        if flasher.busy:
            print(INTERRUPTED)
    print(summary(flasher.outcomes))
    return 0 if all(o.ok for o in flasher.outcomes) else 1
