"""`particlebot radio setup`: the real digi-xbee configures an emulated XBee; values read back."""

from __future__ import annotations

import logging
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
import serial
from digi.xbee.devices import Raw802Device
from digi.xbee.exception import OperationNotSupportedException

from particlebot.cli import main
from particlebot.fleet import Fleet, FleetKey, ParticleRecord, create_fleet, load_fleet
from particlebot.provision.xbee_setup import RadioPlan, RadioSetupError, Role, XBeeSetup
from particlebot.radio import NoResponseError
from tests.support.ptys import VanishingPty
from tests.support.xbee_emulator import XBeeEmulator

KEY = FleetKey.from_hex("000102030405060708090A0B0C0D0E0F")
GUARD_S = 0.15  # the emulator's guard time is 0.1 s; a real radio's 1 s


def plan(role: Role, node_id: str, channel: int = 0x0C) -> RadioPlan:
    return RadioPlan(role, node_id, pan_id=0x1A2B, channel=channel, key=KEY)


def setup(port: str, radio_plan: RadioPlan) -> object:
    return XBeeSetup(port, guard_s=GUARD_S, sync_timeout_s=1.0, say=lambda line: None).run(
        radio_plan
    )


@pytest.fixture
def emulators(tmp_path: Path) -> Iterator[list[XBeeEmulator]]:
    made: list[XBeeEmulator] = []
    yield made
    for emulator in made:
        emulator.close()


def command_mode_values(port: str, commands: list[str]) -> dict[str, str]:
    """Reads registers as a person at a terminal would: +++, then ATxx lines (plain pyserial)."""
    with serial.Serial(port, 9600, timeout=1.0) as link:
        time.sleep(GUARD_S)
        link.write(b"+++")
        assert link.read_until(b"\r") == b"OK\r"
        values = {}
        for command in commands:
            link.write(f"AT{command}\r".encode())
            values[command] = link.read_until(b"\r").decode().strip()
        link.write(b"ATCN\r")
        assert link.read_until(b"\r") == b"OK\r"
    return values


def test_a_factory_radio_ends_as_a_particle_s_transparent_radio_and_keeps_it_after_power_off(
    tmp_path: Path, emulators: list[XBeeEmulator], caplog: pytest.LogCaptureFixture
) -> None:
    emulator = XBeeEmulator(tmp_path / "ttyUSB0", api_mode=0, node_id=b" ")
    emulators.append(emulator)
    caplog.set_level(logging.DEBUG)
    result = setup(emulator.port, plan(Role.PARTICLE, "7"))
    assert result.address == "0013A20040A1B2C3"  # type: ignore[attr-defined]
    assert (result.found_mode, result.final_mode) == (0, 0)  # type: ignore[attr-defined]

    emulator.power_cycle()  # only what was written to non-volatile memory is left
    values = command_mode_values(
        emulator.port, ["AP", "ID", "CH", "MY", "DH", "DL", "NI", "EE", "BD", "KY"]
    )
    assert values == {
        "AP": "0",
        "ID": "1A2B",
        "CH": "C",
        "MY": "FFFE",
        "DH": "0",
        "DL": "FFFF",
        "NI": "7",
        "EE": "1",
        "BD": "3",
        "KY": "OK",  # write-only: acknowledged, not shown
    }
    assert emulator.saved_key == KEY.secret_bytes()
    # digi-xbee logs frames in hex at DEBUG level; the KY frame is kept out of the log.
    for form in (KEY.secret_hex(), " ".join(f"{b:02X}" for b in KEY.secret_bytes())):
        assert form not in caplog.text.upper()
    assert "4B 59" not in caplog.text  # no KY frame at all
    assert "41 50" in caplog.text  # while other frames are logged as usual


def test_a_base_radio_in_escaped_api_mode_with_no_node_id_is_configured_and_stays_api(
    tmp_path: Path, emulators: list[XBeeEmulator]
) -> None:
    emulator = XBeeEmulator(tmp_path / "ttyUSB0", api_mode=2, node_id=b"")
    emulators.append(emulator)
    result = setup(emulator.port, plan(Role.BASE, "BASE"))
    assert (result.found_mode, result.final_mode) == (2, 2)  # type: ignore[attr-defined]

    emulator.power_cycle()
    device = Raw802Device(emulator.port, 9600)
    device.set_sync_ops_timeout(1.0)
    try:
        device.open()
        read = {
            name: bytes(device.get_parameter(name))
            for name in ("AP", "ID", "CH", "MY", "DL", "NI", "EE", "BD")
        }
        with pytest.raises(OperationNotSupportedException, match="KY"):
            device.get_parameter("KY")  # write-only: the answer carries no value
    finally:
        device.close()
    assert read == {
        "AP": b"\x02",
        "ID": b"\x1a\x2b",
        "CH": b"\x0c",
        "MY": b"\xff\xfe",
        "DL": b"\xff\xff",
        "NI": b"BASE",
        "EE": b"\x01",
        "BD": b"\x03",
    }
    assert emulator.saved_key == KEY.secret_bytes()


def test_a_particle_radio_in_api_mode_is_switched_to_transparent(
    tmp_path: Path, emulators: list[XBeeEmulator]
) -> None:
    emulator = XBeeEmulator(tmp_path / "ttyUSB0", api_mode=1)
    emulators.append(emulator)
    setup(emulator.port, plan(Role.PARTICLE, "12"))
    assert emulator.saved[b"AP"] == b"\x00" and emulator.saved[b"NI"] == b"12"


def test_a_channel_the_radio_lacks_is_refused_by_name(
    tmp_path: Path, emulators: list[XBeeEmulator]
) -> None:
    pro = XBeeEmulator(tmp_path / "ttyUSB0", api_mode=1, channels=range(0x0C, 0x18))
    emulators.append(pro)
    with pytest.raises(RadioSetupError, match="refused channel 0x0B"):
        setup(pro.port, plan(Role.PARTICLE, "3", channel=0x0B))
    assert pro.saved[b"CH"] == b"\x0c"  # nothing half-written to its memory


def test_a_port_where_nothing_answers(tmp_path: Path) -> None:
    silent = VanishingPty(tmp_path / "ttyUSB0")
    try:
        with pytest.raises(NoResponseError, match="9600 baud"):
            XBeeSetup(str(silent.path), guard_s=GUARD_S, probe_timeout_s=0.2).run(
                plan(Role.BASE, "BASE")
            )
    finally:
        silent.close()


# ---- the command ---------------------------------------------------------------------------------


def test_the_command_records_the_radio_and_moves_it_between_particles(
    tmp_path: Path, emulators: list[XBeeEmulator], capsys: pytest.CaptureFixture[str]
) -> None:
    fleet_path = tmp_path / "fleet.toml"
    fleet = Fleet.new()
    fleet.record(ParticleRecord(4))
    create_fleet(fleet, fleet_path)
    emulator = XBeeEmulator(tmp_path / "ttyUSB0", api_mode=0)
    emulators.append(emulator)
    base = ["radio", "setup", "--port", emulator.port, "--fleet", str(fleet_path)]
    fast = ["--guard-time", str(GUARD_S)]

    assert main([*base, "--particle", "4", *fast]) == 0
    record = load_fleet(fleet_path).get(4)
    assert record is not None and record.radio_address == "0013A20040A1B2C3"
    assert record.radio_configured_at is not None

    assert main([*base, "--particle", "9", *fast]) == 0  # the radio moved to particle 9
    moved = load_fleet(fleet_path)
    assert moved.get(4).radio_address is None  # type: ignore[union-attr]
    assert moved.get(9).radio_address == "0013A20040A1B2C3"  # type: ignore[union-attr]
    out, err = capsys.readouterr()
    assert "it was particle 4's radio before" in out
    assert "has not been flashed into this fleet yet" in out
    assert emulator.saved_key == fleet.key.secret_bytes()
    assert fleet.key.secret_hex() not in (out + err).upper()


def test_the_command_without_a_fleet_or_with_a_bad_id_says_so_in_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["radio", "setup", "--port", "/dev/null", "--fleet", str(tmp_path / "fleet.toml")]
    assert main([*argv, "--base"]) == 2
    assert "fleet init" in capsys.readouterr().err
    create_fleet(Fleet.new(), tmp_path / "fleet.toml")
    assert main([*argv, "--particle", "0"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "1..253" in err


@pytest.mark.parametrize("guard", ["nan", "inf", "-1", "60"])
def test_a_guard_time_that_would_wait_for_ever_or_is_a_typo_is_refused_as_it_is_read(
    guard: str, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit) as ended:
        main(["radio", "setup", "--base", "--port", "/dev/null", "--guard-time", guard])
    assert ended.value.code == 2
    (line,) = capsys.readouterr().err.splitlines()
    assert f"--guard-time: must be a number 0..10, not '{guard}'" in line
