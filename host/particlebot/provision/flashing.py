"""Flashing particles: reset a board into its bootloader, upload, give it an id, record it.

The state machine for one board: a running port is touched at 1200 baud and the tool waits for
the same board's bootloader port; a bootloader port is uploaded to at once. The upload reads the
board's EEPROM, decides its id (the one asked for, the one it already has, or the fleet's next
free one), writes flash and id in the same bootloader session, and the fleet file records the
particle. Many boards are flashed one after another as a person plugs them in; a board that
fails is reported and skipped, and the run goes on.
"""

from __future__ import annotations

import datetime as dt
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Protocol

from particlebot.fleet import (
    Fleet,
    FleetError,
    FleetFileError,
    ParticleRecord,
    timestamp,
    updating_fleet,
)
from particlebot.provision import identity
from particlebot.provision.avrdude import AvrdudeError, EepromEditor, UploadReport
from particlebot.provision.boards import BoardError, BoardMode, BoardPort, UsbBus
from particlebot.provision.image import FirmwareImage

UPLOAD_FAILED_NOTE = "upload failed"
"""How the note of an id reserved for a board whose upload failed begins."""


class Uploader(Protocol):
    """Writes an image to a board in its bootloader (provision.avrdude.Avrdude)."""

    def upload(self, port: str, hex_file: Path, edit_eeprom: EepromEditor) -> UploadReport: ...


@dataclass(frozen=True)
class FlashOutcome:
    """What happened to one board."""

    port: str
    particle_id: int | None = None
    id_source: str = ""
    """"new" (next free in the fleet), "kept" (the id it had) or "given" (--id)."""
    report: UploadReport | None = None
    error: str | None = None
    seconds: float = 0.0

    @property
    def ok(self) -> bool:
        return self.error is None

    def line(self) -> str:
        if not self.ok:
            return f"FAILED {self.port}: {self.error}"
        assert self.report is not None
        eeprom = "id written" if self.report.eeprom_bytes_written else "EEPROM unchanged"
        return (
            f"particle {self.particle_id} ({self.id_source} id) on {self.port}: "
            f"{self.report.flash_bytes_verified:,} B flashed and verified, {eeprom}, "
            f"{self.seconds:.1f} s"
        )


@dataclass
class FlashPlan:
    """What every board of a run gets."""

    image: FirmwareImage
    fleet_path: Path
    definition_hash: int | None
    """The image's protocol definition hash, when the emulator could read it."""
    requested_id: int | None = None
    renumber: bool = False
    """Give a board that already has an id the next free one instead."""


@dataclass
class Timing:
    bootloader_timeout_s: float = 10.0
    """How long a touched board may take to show its bootloader port."""
    poll_s: float = 0.2
    settle_s: float = 2.0
    """After an upload the board leaves its bootloader (0.5 s) and, if its new firmware has USB,
    comes back as a running port (about a second later): until then, whatever shows up where it
    is plugged in is that board."""
    replug_gap_s: float = 0.3
    """A flashed board counts as unplugged once its place has been empty this long."""
    remind_s: float = 15.0
    """How long to wait before reminding the person to unplug a flashed board."""
    clock: Callable[[], float] = time.monotonic
    sleep: Callable[[float], None] = time.sleep
    now: Callable[[], dt.datetime] = timestamp


class Flasher:
    def __init__(
        self,
        usb: UsbBus,
        uploader: Uploader,
        plan: FlashPlan,
        *,
        timing: Timing | None = None,
        say: Callable[[str], None] = print,
    ) -> None:
        self.usb = usb
        self.uploader = uploader
        self.plan = plan
        self.timing = timing or Timing()
        self.say = say
        self.outcomes: list[FlashOutcome] = []
        """Every board flash_many() dealt with, also when it was interrupted."""
        self.busy = False
        """A board is being flashed right now."""

    # ---- one board ---------------------------------------------------------------------------

    def flash(self, board: BoardPort) -> FlashOutcome:
        started = self.timing.clock()
        self.busy = True
        try:
            target = board
            if board.mode is BoardMode.RUNNING:
                target = self.reset_into_bootloader(board)
            return self._upload(board, target, started)
        except (
            BoardError,
            AvrdudeError,
            identity.IdentityError,
            FleetError,
            FleetFileError,
        ) as exc:
            return FlashOutcome(board.device, error=str(exc), seconds=self._since(started))
        finally:
            self.busy = False

    def reset_into_bootloader(self, board: BoardPort) -> BoardPort:
        """Touches a running board and waits for its bootloader port."""
        timing = self.timing
        already = {b.device for b in self.usb.boards() if b.mode is BoardMode.BOOTLOADER}
        self.usb.touch(board.device)
        deadline = timing.clock() + timing.bootloader_timeout_s
        while True:
            for candidate in self.usb.boards():
                if candidate.mode is not BoardMode.BOOTLOADER:
                    continue
                same_place = board.location is not None and candidate.location == board.location
                if same_place or (board.location is None and candidate.device not in already):
                    return candidate
            if timing.clock() >= deadline:
                raise BoardError(
                    f"no bootloader appeared within {timing.bootloader_timeout_s:.0f} s of the "
                    "1200-baud reset: press the board's reset button (or unplug and replug it) "
                    "and try again"
                )
            timing.sleep(timing.poll_s)

    def _upload(self, board: BoardPort, target: BoardPort, started: float) -> FlashOutcome:
        plan = self.plan
        failure: AvrdudeError | KeyboardInterrupt | None = None
        with updating_fleet(plan.fleet_path) as fleet:
            chosen: dict[str, int | str] = {}

            def edit(before: bytes) -> bytes:
                current = identity.id_in(before)
                particle_id, source = choose_id(fleet, current, plan)
                chosen.update(id=particle_id, source=source)
                if particle_id == current:
                    return before
                chosen["written"] = particle_id
                return identity.with_id(before, particle_id)

            try:
                report = self.uploader.upload(target.device, plan.image.path, edit)
            except (AvrdudeError, KeyboardInterrupt) as exc:
                # avrdude writes the EEPROM before the flash: a board whose flash then failed (or
                # was interrupted) may hold its new id already. The id stays reserved, so that
                # the next board does not get it too.
                failure = exc
                reserved = chosen.get("written")
                if isinstance(reserved, int) and fleet.get(reserved) is None:
                    why = str(exc) or "interrupted"
                    note = (
                        f"{UPLOAD_FAILED_NOTE} ({why}); the board may hold this id: flash it again"
                    )
                    fleet.record(
                        ParticleRecord(reserved, board_serial=board.serial_number, note=note)
                    )
            else:
                particle_id = int(chosen["id"])
                record = fleet.get(particle_id) or ParticleRecord(particle_id)
                record.board_serial = (
                    board.serial_number or target.serial_number or record.board_serial
                )
                record.definition_hash = plan.definition_hash
                record.image_sha256 = plan.image.sha256
                record.flashed_at = self.timing.now()
                record.calibration = identity.calibration(report.eeprom_after)
                if record.note and record.note.startswith(UPLOAD_FAILED_NOTE):
                    record.note = None
                fleet.record(record)
        if failure is not None:
            raise failure
        return FlashOutcome(
            target.device,
            particle_id=particle_id,
            id_source=str(chosen["source"]),
            report=report,
            seconds=self._since(started),
        )

    def _since(self, started: float) -> float:
        return self.timing.clock() - started

    # ---- one after another -------------------------------------------------------------------

    def wait_for_board(self, timeout_s: float) -> BoardPort | None:
        """The first board present within timeout_s; None if none came."""
        deadline = self.timing.clock() + timeout_s
        while True:
            boards = self.usb.boards()
            if boards:
                return boards[0]
            if self.timing.clock() >= deadline:
                return None
            self.timing.sleep(self.timing.poll_s)

    def flash_many(
        self, *, count: int | None = None, idle_timeout_s: float | None = None
    ) -> list[FlashOutcome]:
        """Flashes each board that appears, once, until count boards were done or none came for
        idle_timeout_s (None: until interrupted).

        Boards carry nothing that tells them apart over USB, so a board just flashed is told
        from the next one by where it is plugged in: its place counts as taken until it has been
        empty for a moment (after the settle time), i.e. until the person unplugged it. A
        bootloader port there after the settle time is always taken as a board to flash (someone
        pressed reset)."""
        timing = self.timing
        outcomes = self.outcomes
        first = len(outcomes)
        taken: dict[str, _Taken] = {}
        idle_since = reminded = timing.clock()
        while count is None or len(outcomes) - first < count:
            now = timing.clock()
            boards = self.usb.boards()
            present = {b.socket for b in boards}
            for socket, mark in list(taken.items()):
                if socket in present:
                    mark.last_present = now
                elif mark.settled(now, timing) and now - mark.last_present >= timing.replug_gap_s:
                    del taken[socket]
            fresh = [
                b for b in boards if b.socket not in taken or _reset_by_hand(b, taken, now, timing)
            ]
            if not fresh:
                if idle_timeout_s is not None and now - idle_since >= idle_timeout_s:
                    break
                if taken and now - reminded >= timing.remind_s:
                    self.say("Waiting for the next board: unplug the one just flashed first.")
                    reminded = now
                timing.sleep(timing.poll_s)
                continue
            board = fresh[0]
            self.say(f"[{len(outcomes) + 1}] {board.device} ({board.mode.value})...")
            outcome = self.flash(board)
            finished = timing.clock()
            # Without USB locations the bootloader's port has a name of its own: mark it too.
            for socket in {board.socket, outcome.port}:
                taken[socket] = _Taken(finished, finished)
            outcomes.append(outcome)
            self.say(f"[{len(outcomes)}] {outcome.line()}")
            idle_since = reminded = timing.clock()
        return outcomes[first:]


@dataclass
class _Taken:
    """The place of a board that was flashed."""

    finished_at: float
    last_present: float

    def settled(self, now: float, timing: Timing) -> bool:
        return now - self.finished_at >= timing.settle_s


def _reset_by_hand(board: BoardPort, taken: dict[str, _Taken], now: float, timing: Timing) -> bool:
    return board.mode is BoardMode.BOOTLOADER and taken[board.socket].settled(now, timing)


def choose_id(fleet: Fleet, current: int, plan: FlashPlan) -> tuple[int, str]:
    """The id a board gets: the one asked for, else the one it has, else the next free one."""
    if plan.requested_id is not None:
        return plan.requested_id, "given"
    if identity.is_assigned(current) and not plan.renumber:
        return current, "kept"
    return fleet.next_free_id(), "new"


def summary(outcomes: list[FlashOutcome]) -> str:
    done = [o for o in outcomes if o.ok]
    failed = [o for o in outcomes if not o.ok]
    ids = ", ".join(str(o.particle_id) for o in done) or "none"
    text = f"{len(done)} particle(s) flashed (ids {ids})"
    if failed:
        text += f"; {len(failed)} failed: " + "; ".join(f"{o.port} ({o.error})" for o in failed)
    return text
