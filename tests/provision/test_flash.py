"""`particlebot flash`: the reset/upload state machine; the real avrdude on emulated bootloaders."""

from __future__ import annotations

import argparse
import io
import shutil
import stat
import sys
from collections.abc import Callable, Iterator
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest
import serial

from particlebot.cli import build_parser, main
from particlebot.commands import flash as flash_command
from particlebot.fleet import Fleet, ParticleRecord, create_fleet, load_fleet
from particlebot.provision import identity
from particlebot.provision.avrdude import Avrdude, AvrdudeError, parse_dump, write_commands
from particlebot.provision.boards import (
    FIO_BOOTLOADER_PID,
    FIO_RUNNING_PID,
    FIO_VID,
    BoardError,
    BoardMode,
    BoardPort,
    SystemUsb,
    UsbBus,
)
from particlebot.provision.flashing import Flasher, FlashPlan, Timing, summary
from particlebot.provision.image import FirmwareImage, ImageError, parse_intel_hex
from tests.support.caterina_emulator import CaterinaEmulator
from tests.support.usb_bench import BenchBoard, FakeClock, UsbBench

needs_avrdude = pytest.mark.skipif(
    shutil.which("avrdude") is None, reason="avrdude is not installed (`make system-deps`)"
)
BLANK_EEPROM = b"\xff" * 1024


def intel_hex(data: bytes) -> str:
    """data as Intel HEX records from address 0, 16 bytes per record."""
    lines = []
    for address in range(0, len(data), 16):
        chunk = data[address : address + 16]
        record = bytes([len(chunk), address >> 8, address & 0xFF, 0]) + chunk
        lines.append(f":{record.hex().upper()}{(-sum(record)) & 0xFF:02X}")
    return "\n".join([*lines, ":00000001FF"]) + "\n"


@pytest.fixture
def image(tmp_path: Path) -> FirmwareImage:
    # Any bytes do for the bootloader; 700 of them make six pages and a part page.
    path = tmp_path / "image.hex"
    path.write_text(intel_hex(bytes(range(256)) * 2 + bytes(188)))
    return FirmwareImage.load(path)


@pytest.fixture
def fleet_path(tmp_path: Path) -> Path:
    path = tmp_path / "fleet.toml"
    create_fleet(Fleet.new(), path)
    return path


def make_flasher(
    bench: UsbBench, image: FirmwareImage, fleet_path: Path, **plan: object
) -> Flasher:
    clock = bench.clock
    timing = Timing(bootloader_timeout_s=5.0, poll_s=0.05, clock=clock, sleep=clock.sleep)
    flash_plan = FlashPlan(image, fleet_path, 0x1234ABCD, **plan)  # type: ignore[arg-type]
    return Flasher(bench, Avrdude(), flash_plan, timing=timing, say=bench.report)


BenchFactory = Callable[..., UsbBench]


@pytest.fixture
def bench_factory(tmp_path: Path) -> Iterator[BenchFactory]:
    """Benches on a fake clock: the tool's waits cost nothing, and the person takes 3 s to
    swap boards (longer than the tool's settle time, as a person's hands are)."""
    benches: list[UsbBench] = []

    def make(boards: list[BenchBoard], **options: Any) -> UsbBench:
        bench = UsbBench(tmp_path, boards, swap_s=3.0, **options)
        benches.append(bench)
        return bench

    yield make
    for bench in benches:
        bench.close()


# ---- one board ----


@needs_avrdude
def test_a_running_board_is_touched_then_flashed_in_its_bootloader_and_numbered(
    bench_factory: BenchFactory, image: FirmwareImage, fleet_path: Path
) -> None:
    bench = bench_factory([BenchBoard("a", serial_number="SN-A")])
    (running,) = bench.boards()
    assert running.mode is BoardMode.RUNNING
    flasher = make_flasher(bench, image, fleet_path)
    outcome = flasher.flash(running)
    assert outcome.ok, outcome.error
    board = bench.current
    assert board is not None and board.emulator is not None
    assert bench.touched == [running.device]
    assert board.emulator.application() == image.flash.rstrip(b"\xff")
    assert outcome.report is not None and outcome.report.flash_bytes_verified == image.size
    assert (outcome.particle_id, outcome.id_source) == (1, "new")
    assert identity.id_in(bytes(board.emulator.eeprom)) == 1
    record = load_fleet(fleet_path).get(1)
    assert record is not None
    assert record.board_serial == "SN-A"
    assert record.image_sha256 == image.sha256
    assert record.definition_hash == 0x1234ABCD
    assert record.calibration == identity.calibration(bytes(board.emulator.eeprom))
    assert record.calibration  # the servo table
    assert record.flashed_at is not None


@needs_avrdude
def test_a_board_already_in_its_bootloader_is_not_touched(
    bench_factory: BenchFactory, image: FirmwareImage, fleet_path: Path
) -> None:
    bench = bench_factory([BenchBoard("a", starts_in_bootloader=True)])
    (port,) = bench.boards()
    outcome = make_flasher(bench, image, fleet_path).flash(port)
    assert outcome.ok, outcome.error
    assert bench.touched == []


@needs_avrdude
def test_a_reflashed_particle_keeps_its_id_and_settings_unless_renumbered(
    bench_factory: BenchFactory, image: FirmwareImage, fleet_path: Path
) -> None:
    numbered = identity.with_id(BLANK_EEPROM, 5)
    bench = bench_factory(
        [BenchBoard("five", eeprom=numbered), BenchBoard("five-again", eeprom=numbered)]
    )
    flasher = make_flasher(bench, image, fleet_path)
    (first,) = bench.boards()
    outcome = flasher.flash(first)
    assert (outcome.particle_id, outcome.id_source) == (5, "kept")
    assert outcome.report is not None and outcome.report.eeprom_bytes_written == 0
    bench.report(outcome.line())
    flasher.timing.sleep(3.0)

    flasher.plan.renumber = True
    (second,) = bench.boards()
    outcome = flasher.flash(second)
    assert (outcome.particle_id, outcome.id_source) == (1, "new")
    assert load_fleet(fleet_path).roster_ids() == [1, 5]


@needs_avrdude
def test_a_refused_id_ends_the_session_before_any_flash_is_written(
    bench_factory: BenchFactory,
    image: FirmwareImage,
    fleet_path: Path,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    def refuse(eeprom: bytes, new_id: int) -> bytes:
        raise identity.IdentityError(f"the firmware refused id {new_id}")

    monkeypatch.setattr(identity, "with_id", refuse)
    bench = bench_factory([BenchBoard("a", starts_in_bootloader=True)])
    (port,) = bench.boards()
    outcome = make_flasher(bench, image, fleet_path).flash(port)
    assert not outcome.ok and "refused id 1" in (outcome.error or "")
    emulator = bench.current.emulator if bench.current else None
    assert emulator is not None
    assert emulator.log.flash_pages_written == 0
    assert not emulator.exited.is_set()  # left waiting in its bootloader, not half-flashed
    assert load_fleet(fleet_path).roster_ids() == []


# ---- one board after another ----


@pytest.mark.slow
@needs_avrdude
def test_many_boards_go_on_past_a_board_that_never_resets_and_one_that_fails_to_verify(
    bench_factory: BenchFactory, image: FirmwareImage, fleet_path: Path
) -> None:
    bench = bench_factory(
        [
            BenchBoard("good-1"),
            BenchBoard("no-bootloader", answers_touch=False),
            BenchBoard("bad-flash", corrupt_flash=True),
            BenchBoard("good-2", usb_firmware=False),
        ]
    )
    flasher = make_flasher(bench, image, fleet_path)
    outcomes = flasher.flash_many(count=4, idle_timeout_s=60)

    assert [o.ok for o in outcomes] == [True, False, False, True]
    assert [o.particle_id for o in outcomes] == [1, None, None, 3]
    assert "no bootloader appeared" in (outcomes[1].error or "")
    assert "verification mismatch" in (outcomes[2].error or "")
    # The board whose flash failed to verify had its id written already (avrdude writes the
    # EEPROM first): id 2 stays reserved for it, so that no other board gets it too.
    bad_board = bench.finished[2].emulator
    assert bad_board is not None and identity.id_in(bytes(bad_board.eeprom)) == 2
    fleet = load_fleet(fleet_path)
    assert fleet.roster_ids() == [1, 2, 3]
    reserved = fleet.get(2)
    assert reserved is not None and reserved.flashed_at is None
    assert (reserved.note or "").startswith("upload failed (verification mismatch")
    # The first board came back running its new firmware and was not flashed a second time.
    first = bench.finished[0]
    assert first.emulator is not None and first.emulator.log.commands.count("E") == 1
    text = summary(outcomes)
    assert text.startswith("2 particle(s) flashed (ids 1, 3); 2 failed:")
    assert "tty-no-bootloader-run" in text and "tty-bad-flash-run" in text


@pytest.mark.slow
@needs_avrdude
def test_many_boards_without_usb_locations_are_told_apart_by_their_ports(
    bench_factory: BenchFactory, image: FirmwareImage, fleet_path: Path
) -> None:
    bench = bench_factory([BenchBoard("a"), BenchBoard("b")], location=None)
    outcomes = make_flasher(bench, image, fleet_path).flash_many(count=2, idle_timeout_s=60)
    assert [o.particle_id for o in outcomes] == [1, 2]


class PersonAtTheBench(io.StringIO):
    """stdout, as the person at the bench reads it: a board whose line is printed is unplugged."""

    def __init__(self, bench: UsbBench) -> None:
        super().__init__()
        self.bench = bench

    def write(self, text: str) -> int:
        self.bench.report(text)
        return super().write(text)


@needs_avrdude
def test_the_command_prints_a_line_per_board_and_a_summary_and_names_the_failed_one(
    bench_factory: BenchFactory,
    image: FirmwareImage,
    fleet_path: Path,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    bench = bench_factory(
        [BenchBoard("a"), BenchBoard("no-bootloader", answers_touch=False), BenchBoard("b")]
    )
    out = PersonAtTheBench(bench)
    monkeypatch.setattr(sys, "stdout", out)
    argv = ["flash", "--many", "--count", "3", "--fleet", str(fleet_path)]
    args = build_parser().parse_args([*argv, "--firmware", str(image.path), "--no-check"])
    clock = bench.clock
    timing = Timing(bootloader_timeout_s=5.0, poll_s=0.05, clock=clock, sleep=clock.sleep)
    assert flash_command.run(args, usb=bench, timing=timing) == 1  # one board failed

    lines = out.getvalue().splitlines()
    where = bench.directory
    no_bootloader = (
        "no bootloader appeared within 5 s of the 1200-baud reset: press the board's reset "
        "button (or unplug and replug it) and try again"
    )
    assert lines[0].startswith("Flashing one board after another: plug in a Fio v3")
    assert lines[1] == f"[1] {where}/tty-a-run (running)..."
    flashed = f"{image.size:,} B flashed and verified, id written"
    assert lines[2].startswith(f"[1] particle 1 (new id) on {where}/tty-a-boot: {flashed}")
    assert lines[3] == f"[2] {where}/tty-no-bootloader-run (running)..."
    assert lines[4] == f"[2] FAILED {where}/tty-no-bootloader-run: {no_bootloader}"
    assert lines[5] == f"[3] {where}/tty-b-run (running)..."
    assert lines[6].startswith(f"[3] particle 2 (new id) on {where}/tty-b-boot: {flashed}")
    assert lines[7] == (
        f"2 particle(s) flashed (ids 1, 2); 1 failed: {where}/tty-no-bootloader-run "
        f"({no_bootloader})"
    )
    assert len(lines) == 8
    assert load_fleet(fleet_path).roster_ids() == [1, 2]


def test_flash_many_stops_waiting_when_no_board_comes(
    bench_factory: BenchFactory, image: FirmwareImage, fleet_path: Path
) -> None:
    bench = bench_factory([])
    flasher = make_flasher(bench, image, fleet_path)
    assert flasher.flash_many(idle_timeout_s=2.0) == []
    assert flasher.timing.clock() >= 2.0


# ---- USB through pyserial ----


def test_the_system_bus_lists_only_fio_boards(monkeypatch: pytest.MonkeyPatch) -> None:
    def port(device: str, vid: int | None, pid: int | None) -> SimpleNamespace:
        return SimpleNamespace(
            device=device, vid=vid, pid=pid, serial_number=None, location="1-2:1.0"
        )

    ports = [
        port("/dev/ttyACM1", FIO_VID, FIO_BOOTLOADER_PID),
        port("/dev/ttyUSB0", 0x0403, 0x6015),  # an XBee Explorer
        port("/dev/ttyACM0", FIO_VID, FIO_RUNNING_PID),
        port("/dev/ttyS0", None, None),
    ]
    monkeypatch.setattr("serial.tools.list_ports.comports", lambda: ports)
    found = SystemUsb().boards()
    assert [(b.device, b.mode) for b in found] == [
        ("/dev/ttyACM0", BoardMode.RUNNING),
        ("/dev/ttyACM1", BoardMode.BOOTLOADER),
    ]


def test_the_touch_opens_at_1200_baud_drops_dtr_and_closes() -> None:
    opened: list[tuple[str, int]] = []
    port = SimpleNamespace(dtr=True, closed=False)

    def opener(device: str, baud: int) -> SimpleNamespace:
        opened.append((device, baud))
        port.close = lambda: setattr(port, "closed", True)
        return port

    SystemUsb(open_port=opener).touch("/dev/ttyACM0")
    assert opened == [("/dev/ttyACM0", 1200)]
    assert port.dtr is False and port.closed


def test_a_port_without_permission_gets_the_dialout_advice() -> None:
    def opener(device: str, baud: int) -> None:
        raise serial.SerialException(13, "could not open port: Permission denied")

    with pytest.raises(BoardError, match="dialout"):
        SystemUsb(open_port=opener).touch("/dev/ttyACM0")  # type: ignore[arg-type]


# ---- avrdude's terminal output ----


def test_a_dump_with_repeated_lines_left_out_is_filled_in() -> None:
    text = (
        "0000  50 42 01 17 07 01 00 ff  ff ff ff ff ff ff ff ff  |PB..............|\n"
        "0010  ff ff ff ff ff ff ff ff  ff ff ff ff ff ff ff ff  |................|\n"
        "*\n"
        "0030  01 02 03 04 05 06 07 08  09 0a 0b 0c 0d 0e 0f 10  |................|\n"
    )
    data = parse_dump(text, 64)
    assert data[:4] == b"PB\x01\x17" and data[16:48] == b"\xff" * 32 and data[48] == 1


def test_a_short_dump_is_an_error_not_a_short_eeprom() -> None:
    with pytest.raises(AvrdudeError, match="16 of 64"):
        parse_dump("0000  " + "00 " * 16 + "\n", 64)


def test_only_changed_bytes_are_written_back() -> None:
    before = bytes(100)
    after = bytearray(before)
    after[4] = 7
    after[10:80] = b"\x01" * 70
    lines = write_commands(before, bytes(after))
    assert lines[0] == "write eeprom 0x0004 0x07"
    assert [line.split()[2] for line in lines[1:]] == ["0x000a", "0x002a", "0x004a"]


# ---- bad input: one line and a non-zero exit ----


class StaticUsb:
    """Boards that are just there; a touch is noted and does nothing."""

    def __init__(self, ports: list[BoardPort]) -> None:
        self.ports = ports
        self.touched: list[str] = []

    def boards(self) -> list[BoardPort]:
        return list(self.ports)

    def touch(self, device: str) -> None:
        self.touched.append(device)


def run_cli(
    argv: list[str], capsys: pytest.CaptureFixture[str], usb: UsbBus | None = None
) -> tuple[int, str, str]:
    args: argparse.Namespace = build_parser().parse_args(["flash", *argv])
    clock = FakeClock()
    timing = Timing(poll_s=0.05, clock=clock, sleep=clock.sleep)
    code = flash_command.run(args, usb=usb or StaticUsb([]), timing=timing)
    out, err = capsys.readouterr()
    return code, out, err


def assert_one_line(code: int, err: str, *fragments: str) -> None:
    assert code != 0
    assert err.count("\n") == 1 and err.startswith("particlebot: "), err
    assert "Traceback" not in err
    for fragment in fragments:
        assert fragment in err, err


@pytest.fixture
def hex_file(image: FirmwareImage) -> str:
    return str(image.path)


def test_no_board_on_usb(
    capsys: pytest.CaptureFixture[str], fleet_path: Path, hex_file: str
) -> None:
    argv = ["--fleet", str(fleet_path), "--firmware", hex_file, "--no-check", "--wait", "1"]
    code, out, err = run_cli(argv, capsys)
    assert_one_line(code, err, "no Fio v3 found", "--port")
    assert "Waiting up to 1 s" in out


def test_avrdude_missing(
    capsys: pytest.CaptureFixture[str],
    fleet_path: Path,
    hex_file: str,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr("particlebot.provision.avrdude.shutil.which", lambda name: None)
    argv = ["--fleet", str(fleet_path), "--firmware", hex_file, "--no-check"]
    code, _, err = run_cli(argv, capsys)
    assert_one_line(code, err, "avrdude is not installed")


@pytest.mark.parametrize(
    ("content", "complaint"),
    [
        (None, "no firmware image"),
        (b"\x7fELF\x01\x02\xff\xfe", "binary data"),
        (b":0400000001020304F1\n", "bad checksum"),
        (b":0400000001020304F2\n", "end-of-file record"),
        (b"hello\n", "expected ':'"),
    ],
)
def test_an_unusable_image(
    capsys: pytest.CaptureFixture[str],
    fleet_path: Path,
    tmp_path: Path,
    content: bytes | None,
    complaint: str,
) -> None:
    path = tmp_path / "bad.hex"
    if content is not None:
        path.write_bytes(content)
    code, _, err = run_cli(["--fleet", str(fleet_path), "--firmware", str(path)], capsys)
    assert_one_line(code, err, complaint)


def test_an_image_larger_than_the_bootloader_leaves(tmp_path: Path) -> None:
    path = tmp_path / "big.hex"
    path.write_text(intel_hex(bytes(28_673)))
    with pytest.raises(ImageError, match="28,673 B of flash; the bootloader leaves 28,672 B"):
        FirmwareImage.load(path)
    assert len(parse_intel_hex(intel_hex(bytes(28_672)))) == 28_672


def test_an_unreadable_or_open_fleet_file(
    capsys: pytest.CaptureFixture[str], fleet_path: Path, hex_file: str
) -> None:
    fleet_path.chmod(0o644)
    code, _, err = run_cli(["--fleet", str(fleet_path), "--firmware", hex_file], capsys)
    assert_one_line(code, err, "chmod 600")
    fleet_path.chmod(0o600)
    fleet_path.write_text("[radio]\npan_id = \n")
    code, _, err = run_cli(["--fleet", str(fleet_path), "--firmware", hex_file], capsys)
    assert_one_line(code, err, "not valid TOML")


def test_an_id_already_taken_or_out_of_range(
    capsys: pytest.CaptureFixture[str], fleet_path: Path, hex_file: str
) -> None:
    fleet = load_fleet(fleet_path)
    fleet.record(ParticleRecord(3))
    fleet_path.unlink()
    create_fleet(fleet, fleet_path)
    base = ["--fleet", str(fleet_path), "--firmware", hex_file, "--no-check"]
    code, _, err = run_cli([*base, "--id", "3"], capsys)
    assert_one_line(code, err, "id 3 is taken", "--force")
    code, _, err = run_cli([*base, "--id", "254"], capsys)
    assert_one_line(code, err, "1..253")


def test_options_that_do_not_go_together(
    capsys: pytest.CaptureFixture[str], fleet_path: Path, hex_file: str
) -> None:
    base = ["--fleet", str(fleet_path), "--firmware", hex_file, "--no-check"]
    assert_one_line(*run_cli([*base, "--many", "--port", "/dev/x"], capsys)[::2], "--many")
    assert_one_line(*run_cli([*base, "--many", "--id", "4"], capsys)[::2], "--many")
    assert_one_line(*run_cli([*base, "--count", "2"], capsys)[::2], "--count")


@pytest.mark.parametrize(
    ("argv", "complaint"),
    [
        (["--wait", "nan"], "--wait: must be a number >= 0, not 'nan'"),  # would wait for ever
        (["--wait", "inf"], "--wait: must be a number >= 0, not 'inf'"),
        (["--many", "--count", "0"], "--count: must be a whole number >= 1, not '0'"),
    ],
)
def test_numbers_that_cannot_be_waited_for_or_counted_are_refused_as_they_are_read(
    argv: list[str], complaint: str, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit) as ended:
        main(["flash", *argv])
    assert ended.value.code == 2
    assert_one_line(2, capsys.readouterr().err, f"particlebot: flash: argument {complaint}")


def test_several_boards_without_port_or_many_are_not_guessed_between(
    capsys: pytest.CaptureFixture[str], fleet_path: Path, hex_file: str
) -> None:
    usb = StaticUsb(
        [BoardPort("/dev/ttyACM0", BoardMode.RUNNING), BoardPort("/dev/ttyACM1", BoardMode.RUNNING)]
    )
    argv = ["--fleet", str(fleet_path), "--firmware", hex_file, "--no-check"]
    code, _, err = run_cli(argv, capsys, usb=usb)
    assert_one_line(code, err, "2 Fio v3 boards found", "--port")
    assert usb.touched == []


@needs_avrdude
def test_the_command_flashes_a_board_named_by_port_and_prints_one_line(
    capsys: pytest.CaptureFixture[str],
    fleet_path: Path,
    hex_file: str,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # Without the simavr harness the image is flashed all the same, its hash left unrecorded.
    monkeypatch.setenv("PARTICLEBOT_SIM_HARNESS", str(tmp_path / "no-harness"))
    emulator = CaterinaEmulator(tmp_path / "ttyACM7")
    try:
        argv = ["--fleet", str(fleet_path), "--firmware", hex_file, "--port", emulator.port]
        code, out, err = run_cli(argv, capsys)
    finally:
        emulator.close()
    assert code == 0, err
    first, second = out.splitlines()
    assert "its definition hash is not recorded" in first
    assert "fix PARTICLEBOT_SIM_HARNESS" in first
    assert second.startswith("particle 1 (new id) on ") and "flashed and verified" in second
    assert stat.S_IMODE(fleet_path.stat().st_mode) == 0o600
    record = load_fleet(fleet_path).get(1)
    assert record is not None and record.definition_hash is None
