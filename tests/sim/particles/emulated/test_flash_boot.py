"""`particlebot flash` end to end: real avrdude, emulated Caterina, the result booted in simavr.

The real avrdude uploads the real image to an emulated Caterina, and what the bootloader then
holds boots in simavr with the id the tool gave it."""

from __future__ import annotations

import hashlib
import shutil
from pathlib import Path

import pytest

from particlebot.cli import main
from particlebot.firmware import NativeParticle
from particlebot.fleet import Fleet, ParticleRecord, create_fleet, load_fleet
from particlebot.protocol import BASE_STATION_ID, DEFINITION_HASH, Param, SetParam, encode_frame
from particlebot.provision import identity
from particlebot.sim.particles.emulated.boot import boot_and_ping
from particlebot.sim.particles.emulated.harness import default_elf
from tests.support.caterina_emulator import CaterinaEmulator

pytestmark = [
    pytest.mark.usefixtures("built_images"),
    pytest.mark.skipif(shutil.which("avrdude") is None, reason="avrdude is not installed"),
]


def flash_through_the_command(
    tmp_path: Path, fleet: Fleet, eeprom: bytes | None, capsys: pytest.CaptureFixture[str]
) -> tuple[CaterinaEmulator, str]:
    fleet_path = tmp_path / "fleet.toml"
    create_fleet(fleet, fleet_path)
    emulator = CaterinaEmulator(tmp_path / "ttyACM0", eeprom=eeprom)
    try:
        code = main(["flash", "--port", emulator.port, "--fleet", str(fleet_path)])
    finally:
        emulator.close()
    out, err = capsys.readouterr()
    assert code == 0, err
    return emulator, out


def test_a_new_board_boots_the_flashed_image_with_the_next_free_id(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    fleet = Fleet.new()
    fleet.record(ParticleRecord(1))
    emulator, out = flash_through_the_command(tmp_path, fleet, None, capsys)
    assert f"protocol definition 0x{DEFINITION_HASH:08X}" in out
    assert "particle 2 (new id)" in out

    booted = boot_and_ping(emulator.application(), eeprom=bytes(emulator.eeprom))
    assert booted.particle_id == 2
    assert booted.status.definition_hash == DEFINITION_HASH

    record = load_fleet(tmp_path / "fleet.toml").get(2)
    assert record is not None
    assert record.definition_hash == DEFINITION_HASH
    hex_file = default_elf().with_suffix(".hex")
    assert record.image_sha256 == hashlib.sha256(hex_file.read_bytes()).hexdigest()


def test_a_reflashed_particle_boots_with_its_id_and_its_own_calibration(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # A particle numbered 6 whose servo was calibrated over the radio, as the console does it.
    with NativeParticle(identity.with_id(b"\xff" * 1024, 6)) as particle:
        tweak = SetParam(target=6, param=Param.SERVO_CAL_3, value=1300)
        particle.receive(encode_frame(tweak, BASE_STATION_ID, 1))
        particle.tick(50)
        eeprom = particle.eeprom()

    emulator, out = flash_through_the_command(tmp_path, Fleet.new(), eeprom, capsys)
    assert "particle 6 (kept id)" in out and "EEPROM unchanged" in out

    booted = boot_and_ping(emulator.application(), eeprom=bytes(emulator.eeprom))
    assert booted.particle_id == 6
    record = load_fleet(tmp_path / "fleet.toml").get(6)
    assert record is not None and record.calibration["SERVO_CAL_3"] == 1300


def test_an_image_that_does_not_answer_as_a_particle_is_refused_before_any_board(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    not_a_particle = tmp_path / "blink.hex"
    # A loop at address 0 (rjmp .-2): it runs, and never says a word on Serial1.
    not_a_particle.write_text(":02000000FFCF30\n:00000001FF\n")
    fleet_path = tmp_path / "fleet.toml"
    create_fleet(Fleet.new(), fleet_path)
    emulator = CaterinaEmulator(tmp_path / "ttyACM0")
    try:
        argv = ["flash", "--port", emulator.port, "--fleet", str(fleet_path)]
        code = main([*argv, "--firmware", str(not_a_particle)])
    finally:
        emulator.close()
    err = capsys.readouterr().err
    assert code == 2
    assert err.count("\n") == 1 and "does not behave like a particle firmware" in err
    assert "--no-check" in err
    assert emulator.log.commands == []
