"""The fleet file: round trip, roster lookups, privacy (0600, atomic, hidden key), bad files."""

from __future__ import annotations

import datetime as dt
import os
import stat
import threading
import tomllib
from dataclasses import replace
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from particlebot.cli import main
from particlebot.fleet import (
    FIRST_ID,
    LAST_ID,
    BaseStationRecord,
    Fleet,
    FleetError,
    FleetFileError,
    FleetKey,
    ParticleRecord,
    PhotocellLaw,
    create_fleet,
    load_fleet,
    render,
    save_fleet,
    updating_fleet,
)
from particlebot.fleet import store as fleet_store

WHEN = dt.datetime(2025, 3, 1, 12, 30, tzinfo=dt.UTC)
KEY_HEX = "00112233445566778899AABBCCDDEEFF"


def sample_fleet() -> Fleet:
    fleet = Fleet(pan_id=0x1A2B, channel=0x0C, key=FleetKey.from_hex(KEY_HEX))
    fleet.base_station = BaseStationRecord("0013a20040000001", WHEN)
    fleet.record(
        ParticleRecord(
            3,
            board_serial="FIO-3",
            radio_address="13A200400000AB",
            definition_hash=0xDCF5A94F,
            image_sha256="ab" * 32,
            flashed_at=WHEN,
            calibration={"SERVO_CAL_0": 1000, "SERVO_CAL_8": 1750},
            note='left wheel "sticks"',
        )
    )
    fleet.record(ParticleRecord(1))
    fleet.photocells = PhotocellLaw(0.5614, "m2", WHEN)
    return fleet


def test_a_fleet_survives_a_round_trip_through_its_file(tmp_path: Path) -> None:
    path = tmp_path / "fleet.toml"
    fleet = sample_fleet()
    save_fleet(fleet, path)
    assert load_fleet(path) == fleet
    text = path.read_text()
    assert "pan_id = 0x1A2B" in text and "definition_hash = 0xDCF5A94F" in text
    assert text.index("[particles.1]") < text.index("[particles.3]")
    assert "[photocells]\nscale = 0.5614" in text


def test_the_roster_answers_the_console_s_questions() -> None:
    fleet = sample_fleet()
    assert fleet.roster_ids() == [1, 3]
    assert fleet.next_free_id() == 2
    found = fleet.by_radio_address("0013A200400000ab")
    assert found is not None and found.id == 3
    assert fleet.by_radio_address("0013A20040FFFFFF") is None
    fleet.record(ParticleRecord(2))
    assert fleet.next_free_id() == 4
    assert fleet.forget(3) is not None and fleet.next_free_id() == 3


def test_a_full_fleet_says_so() -> None:
    fleet = Fleet.new()
    for particle_id in range(FIRST_ID, LAST_ID + 1):
        fleet.record(ParticleRecord(particle_id))
    with pytest.raises(FleetError, match="full"):
        fleet.next_free_id()


def test_a_new_fleet_has_a_random_key_and_avoids_the_factory_pan() -> None:
    fleets = [Fleet.new() for _ in range(20)]
    assert len({f.key.fingerprint for f in fleets}) == 20
    assert all(f.pan_id != 0x3332 for f in fleets)


def test_the_key_never_shows_in_repr_or_str() -> None:
    fleet = sample_fleet()
    for text in (repr(fleet), str(fleet), repr(fleet.key), f"{fleet.key}"):
        assert KEY_HEX not in text.upper()
        assert "hidden" in repr(fleet.key)


@pytest.mark.parametrize("umask", [0o000, 0o022])
def test_the_file_is_private_whatever_the_umask(tmp_path: Path, umask: int) -> None:
    path = tmp_path / "fleet.toml"
    previous = os.umask(umask)
    try:
        create_fleet(sample_fleet(), path)
        with updating_fleet(path) as fleet:
            fleet.record(ParticleRecord(9))
    finally:
        os.umask(previous)
    assert stat.S_IMODE(path.stat().st_mode) == 0o600
    assert [p.name for p in tmp_path.iterdir()] == ["fleet.toml"]  # no temporary left behind


def test_a_write_that_fails_halfway_leaves_the_old_file_whole(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = tmp_path / "fleet.toml"
    save_fleet(sample_fleet(), path)
    before = path.read_bytes()

    def power_cut(src: object, dst: object) -> None:
        raise OSError("power cut")

    monkeypatch.setattr(fleet_store.os, "replace", power_cut)
    # One line naming the file and the reason (FleetFileError), and the old file kept whole.
    with (
        pytest.raises(FleetFileError, match=r"cannot write .*fleet\.toml: power cut"),
        updating_fleet(path) as fleet,
    ):
        fleet.record(ParticleRecord(7))
    assert path.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == ["fleet.toml"]


def test_a_change_that_raises_is_not_written(tmp_path: Path) -> None:
    path = tmp_path / "fleet.toml"
    save_fleet(sample_fleet(), path)
    with pytest.raises(RuntimeError), updating_fleet(path) as fleet:
        fleet.record(ParticleRecord(7))
        raise RuntimeError("flash failed")
    assert load_fleet(path).get(7) is None


def test_two_tools_updating_at_once_lose_nothing(tmp_path: Path) -> None:
    path = tmp_path / "fleet.toml"
    save_fleet(Fleet.new(), path)
    inside = threading.Event()
    release = threading.Event()

    def slow_writer() -> None:
        with updating_fleet(path) as fleet:
            inside.set()
            release.wait(5)
            fleet.record(ParticleRecord(1))

    worker = threading.Thread(target=slow_writer)
    worker.start()
    assert inside.wait(5)
    second = threading.Thread(target=lambda: _record(path, 2))
    second.start()
    second.join(0.2)
    assert second.is_alive()  # waits for the lock instead of reading the old file
    release.set()
    worker.join(5)
    second.join(5)
    assert load_fleet(path).roster_ids() == [1, 2]


def _record(path: Path, particle_id: int) -> None:
    with updating_fleet(path) as fleet:
        fleet.record(ParticleRecord(particle_id))


# ---- bad files: one line that says what to do ------------------------------------------------


def test_a_file_others_can_read_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "fleet.toml"
    save_fleet(sample_fleet(), path)
    path.chmod(0o644)
    with pytest.raises(FleetFileError, match=r"mode 0644.*chmod 600"):
        load_fleet(path)


def test_a_missing_file_says_how_to_make_one(tmp_path: Path) -> None:
    with pytest.raises(FleetFileError, match="fleet init"):
        load_fleet(tmp_path / "fleet.toml")


@pytest.mark.parametrize(
    ("text", "complaint"),
    [
        ("version = 1\n[radio\n", "not valid TOML"),
        ("version = 1\n", r"\[radio\] is missing"),
        (f'[radio]\npan_id = 1\nchannel = 12\nkey = "{KEY_HEX[:30]}"\n', "16 bytes"),
        ('[radio]\npan_id = 1\nchannel = 12\nkey = "zz"\n', "hex"),
        (f'[radio]\npan_id = 1\nchannel = 40\nkey = "{KEY_HEX}"\n', "channel"),
        (f'[radio]\npan_id = "a"\nchannel = 12\nkey = "{KEY_HEX}"\n', "pan_id must be"),
        (
            f'[radio]\npan_id = 1\nchannel = 12\nkey = "{KEY_HEX}"\n[particles.300]\n',
            "1..253",
        ),
        (
            f'[radio]\npan_id = 1\nchannel = 12\nkey = "{KEY_HEX}"\n[particles.2]\ncolour = 1\n',
            "unknown key 'colour'",
        ),
        (
            f'[radio]\npan_id = 1\nchannel = 12\nkey = "{KEY_HEX}"\n'
            '[particles.2]\nradio_address = "nothex"\n',
            "radio address",
        ),
        (
            f'[radio]\npan_id = 1\nchannel = 12\nkey = "{KEY_HEX}"\n'
            "[particles.2]\nflashed_at = 2025-01-01T00:00:00\n",
            "UTC offset",
        ),
        (
            f'[radio]\npan_id = 1\nchannel = 12\nkey = "{KEY_HEX}"\n[photocells]\nscale = "a"\n',
            "scale must be a number",
        ),
        (
            f'[radio]\npan_id = 1\nchannel = 12\nkey = "{KEY_HEX}"\n[photocells]\nscale = -1.0\n'
            'unit = "m2"\n',
            "above 0",
        ),
        (
            f'[radio]\npan_id = 1\nchannel = 12\nkey = "{KEY_HEX}"\n[photocells]\nscale = 0.5\n'
            'unit = "cm"\n',
            "unit must be 'm2' or '1/lux'",
        ),
    ],
)
def test_a_malformed_file_gets_one_line_naming_the_problem(
    tmp_path: Path, text: str, complaint: str
) -> None:
    path = tmp_path / "fleet.toml"
    path.write_text(text)
    path.chmod(0o600)
    with pytest.raises(FleetFileError, match=complaint) as error:
        load_fleet(path)
    assert "\n" not in str(error.value)
    assert KEY_HEX not in str(error.value)


def test_creating_over_an_existing_fleet_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "fleet.toml"
    create_fleet(sample_fleet(), path)
    with pytest.raises(FleetFileError, match="exists already"):
        create_fleet(Fleet.new(), path)
    assert load_fleet(path) == sample_fleet()


# ---- the writer --------------------------------------------------------------------------------


@pytest.mark.slow
@given(st.text())
def test_any_note_comes_back_from_the_file_unchanged(text: str) -> None:
    fleet = Fleet.new()
    fleet.record(ParticleRecord(5, note=text or None))
    loaded = fleet_store._fleet_from(tomllib.loads(render(fleet)))
    assert loaded.particles[5].note == (text or None)


HAND_EDITED = f"""\
# Fleet of the lamp-room experiments: ask Ana before changing the key.
version = 1

[radio]
channel = 0x0C  # the quiet channel in room 2.14
pan_id = 0x1A2B
key = "{KEY_HEX}"

# Particle 3 lost a magnet on 12 March; it is kept for the calibration runs.
[particles.3]
note = 'left wheel "sticks"'
board_serial = "FIO-3"
definition_hash = 0xDCF5A94F

[particles.3.calibration]
SERVO_CAL_8 = 1750  # measured twice
SERVO_CAL_0 = 1000
"""


def test_a_hand_edited_file_keeps_its_comments_order_and_hex_through_rewrites(
    tmp_path: Path,
) -> None:
    path = tmp_path / "fleet.toml"
    path.write_text(HAND_EDITED, encoding="utf-8")
    path.chmod(0o600)
    with updating_fleet(path) as fleet:  # nothing changed: the file comes back byte for byte
        pass
    assert path.read_text(encoding="utf-8") == HAND_EDITED
    with updating_fleet(path) as fleet:
        fleet.record(ParticleRecord(7, board_serial="FIO-7", definition_hash=0x0000BEEF))
        particle = fleet.particles[3]
        fleet.record(replace(particle, calibration={**particle.calibration, "SERVO_CAL_8": 1760}))
    with updating_fleet(path) as fleet:
        fleet.pan_id = 0x2B3C
    text = path.read_text(encoding="utf-8")
    lines = text.splitlines()
    for comment in (
        "# Fleet of the lamp-room experiments: ask Ana before changing the key.",
        "channel = 0x0C  # the quiet channel in room 2.14",
        "# Particle 3 lost a magnet on 12 March; it is kept for the calibration runs.",
        "SERVO_CAL_8 = 1760  # measured twice",
    ):
        assert comment in lines
    assert "pan_id = 0x2B3C" in lines and "definition_hash = 0x0000BEEF" in lines
    # The researcher's key order stays; the new particle comes after the old one.
    assert text.index("channel =") < text.index("pan_id =") < text.index("key =")
    assert text.index("note =") < text.index("board_serial =")
    assert text.index("SERVO_CAL_8") < text.index("SERVO_CAL_0")
    assert text.index("[particles.3]") < text.index("[particles.7]")
    loaded = load_fleet(path)
    assert loaded.pan_id == 0x2B3C and loaded.particles[7].definition_hash == 0xBEEF
    assert loaded.particles[3].calibration == {"SERVO_CAL_8": 1760, "SERVO_CAL_0": 1000}


@given(st.dictionaries(st.text(min_size=1), st.integers(-(2**63), 2**63 - 1), max_size=5))
def test_calibration_tables_with_any_names_round_trip(calibration: dict[str, int]) -> None:
    fleet = Fleet.new()
    fleet.record(ParticleRecord(5, calibration=calibration))
    loaded = fleet_store._fleet_from(tomllib.loads(render(fleet)))
    assert loaded.particles[5].calibration == calibration


# ---- the command ---------------------------------------------------------------------------------


def test_fleet_init_makes_a_private_file_and_never_prints_the_key(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "fleet.toml"
    assert main(["fleet", "init", "--fleet", str(path), "--pan", "0x1A2B"]) == 0
    fleet = load_fleet(path)
    assert fleet.pan_id == 0x1A2B and fleet.channel == 0x0C
    assert stat.S_IMODE(path.stat().st_mode) == 0o600
    save_fleet_with_particle(path)
    assert main(["fleet", "show", "--fleet", str(path)]) == 0
    out, err = capsys.readouterr()
    assert fleet.key.fingerprint in out
    assert "0013A20040000042" in out and "0xDCF5A94F" in out
    assert fleet.key.secret_hex() not in (out + err).upper()


def save_fleet_with_particle(path: Path) -> None:
    with updating_fleet(path) as fleet:
        fleet.record(
            ParticleRecord(4, radio_address="0013A20040000042", definition_hash=0xDCF5A94F)
        )


def test_fleet_init_takes_a_key_from_a_file_and_replaces_one_on_request(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "fleet.toml"
    key_file = tmp_path / "key.txt"
    key_file.write_text(KEY_HEX.lower() + "\n")
    assert main(["fleet", "init", "--fleet", str(path), "--key-file", str(key_file)]) == 0
    assert load_fleet(path).key == FleetKey.from_hex(KEY_HEX)
    assert main(["fleet", "init", "--fleet", str(path), "--new-key"]) == 0
    assert load_fleet(path).key != FleetKey.from_hex(KEY_HEX)
    assert KEY_HEX not in capsys.readouterr().out.upper()


@pytest.mark.parametrize(
    ("key_file_text", "argv", "complaint"),
    [
        (KEY_HEX[:30], [], "16 bytes (32 hex digits), not 15"),
        ("not a key at all", [], "hex digits"),
        (None, ["--key-file", "missing.txt"], "cannot read the key from"),
        (None, ["--channel", "0x30"], "channel 0x30"),
        (None, ["--pan", "0xFFFF"], "PAN id"),
    ],
)
def test_fleet_init_rejects_bad_values_in_one_line(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
    key_file_text: str | None,
    argv: list[str],
    complaint: str,
) -> None:
    monkeypatch.chdir(tmp_path)
    if key_file_text is not None:
        Path("key.txt").write_text(key_file_text)
        argv = ["--key-file", "key.txt"]
    assert main(["fleet", "init", *argv]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and complaint in err, err
    assert not Path("fleet.toml").exists()


def test_fleet_init_over_an_existing_fleet_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "fleet.toml"
    assert main(["fleet", "init", "--fleet", str(path)]) == 0
    before = path.read_text()
    assert main(["fleet", "init", "--fleet", str(path)]) == 2
    assert "exists already" in capsys.readouterr().err
    assert path.read_text() == before
