"""Bad input on the command line: one line on stderr and a non-zero exit, never a traceback."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from particlebot.cli import main
from tests.support.fakes import status_frame

NOT_ROOT = pytest.mark.skipif(
    hasattr(os, "geteuid") and os.geteuid() == 0, reason="root may write to read-only folders"
)


def assert_one_line_failure(
    argv: list[str], complaint: str, capsys: pytest.CaptureFixture[str]
) -> None:
    try:
        code = main(argv)
    except SystemExit as exc:  # argparse ends the process itself
        code = exc.code if isinstance(exc.code, int) else 1
    err = capsys.readouterr().err
    assert code == 2
    assert "Traceback" not in err
    assert len(err.strip().splitlines()) == 1, err
    assert complaint in err


def write_log(path: Path, *records: dict[str, object]) -> Path:
    path.write_text("".join(json.dumps(record) + "\n" for record in records))
    return path


SESSION = {"t": 1.0, "kind": "session", "format": 1}
GOOD_RX = {"t": 2.0, "kind": "rx", "src": None, "hex": status_frame(1).hex()}
GOOD_FRAME = {
    "t": 2.0,
    "kind": "frame",
    "src": None,
    "sender": 1,
    "type": "STATUS",
    "seq": 0,
    "hex": "a55a",
    "fields": {"state": 0},
}


@pytest.fixture
def a_file(tmp_path: Path) -> Path:
    """A plain file where a folder is expected."""
    path = tmp_path / "not-a-folder"
    path.write_text("")
    return path


@pytest.fixture(autouse=True)
def no_radio_from_the_environment(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("PARTICLEBOT_RADIO", raising=False)


@pytest.mark.parametrize("command", ["log", "console", "demo"])
def test_a_log_folder_that_cannot_be_written_is_one_line(
    command: str,
    a_file: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # The console checks for a terminal first; here the log folder is what must be reported.
    monkeypatch.setattr("particlebot.commands.console.has_terminal", lambda: True)
    argv = [command, "--log-dir", str(a_file / "logs")]
    argv += ["--no-ui"] if command == "demo" else ["--radio", "virtual://2"]
    assert_one_line_failure(argv, "cannot write the session log", capsys)


@pytest.mark.parametrize("log_dir", ["", "logs"], ids=["is the file", "under the file"])
def test_a_file_where_the_log_folder_belongs_is_named(
    log_dir: str, a_file: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # Not "File exists" or "Not a directory", which name neither the file nor what to do.
    argv = ["log", "--radio", "virtual://2", "--log-dir", str(a_file / log_dir)]
    assert_one_line_failure(argv, f"({a_file} is a file); give --log-dir a folder", capsys)


@NOT_ROOT
def test_a_read_only_log_folder_is_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    tmp_path.chmod(0o555)
    try:
        argv = ["log", "--radio", "virtual://2", "--log-dir", str(tmp_path / "logs")]
        assert_one_line_failure(argv, "cannot write the session log", capsys)
    finally:
        tmp_path.chmod(0o755)


@pytest.mark.parametrize("command", ["export", "replay", "plot"])
def test_a_folder_given_as_a_log_is_one_line(
    command: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = [command, str(tmp_path)] + (["--no-ui"] if command == "replay" else [])
    assert_one_line_failure(argv, str(tmp_path), capsys)


@NOT_ROOT
@pytest.mark.parametrize("command", ["export", "replay"])
def test_an_unreadable_log_is_one_line(
    command: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    log = write_log(tmp_path / "x.jsonl", SESSION, GOOD_RX)
    log.chmod(0)
    argv = [command, str(log)] + (["--no-ui"] if command == "replay" else [])
    assert_one_line_failure(argv, "Permission denied", capsys)


@pytest.mark.parametrize("target", ["a folder", "a missing folder"])
def test_export_to_a_place_that_cannot_be_written_is_one_line_and_leaves_nothing(
    target: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    log = write_log(tmp_path / "x.jsonl", SESSION, GOOD_FRAME)
    output = tmp_path / "out" if target == "a folder" else tmp_path / "missing" / "x.csv"
    if target == "a folder":
        output.mkdir()
    assert_one_line_failure(["export", str(log), "-o", str(output)], "cannot write", capsys)
    assert not (tmp_path / "x.csv").exists()


@NOT_ROOT
def test_export_into_a_read_only_folder_is_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    log = write_log(tmp_path / "x.jsonl", SESSION, GOOD_FRAME)
    folder = tmp_path / "read-only"
    folder.mkdir(mode=0o555)
    argv = ["export", str(log), "-o", str(folder / "x.csv")]
    assert_one_line_failure(argv, "Permission denied", capsys)


@pytest.mark.parametrize(
    ("record", "complaint"),
    [
        ({**GOOD_RX, "hex": "zz"}, "'hex' must be bytes in hex"),
        ({**GOOD_RX, "hex": "a5a"}, "'hex' must be bytes in hex"),
        ({**GOOD_RX, "hex": 42}, "'hex' must be bytes in hex"),
        ({**GOOD_RX, "t": "soon"}, "'t' must be a number"),
        ({**GOOD_RX, "src": 5}, "'src' must be a string"),
    ],
)
def test_replay_of_a_damaged_record_names_its_line(
    record: dict[str, object], complaint: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    log = write_log(tmp_path / "x.jsonl", SESSION, GOOD_RX, record)
    assert_one_line_failure(["replay", str(log), "--no-ui"], f"{log}:3: {complaint}", capsys)


@pytest.mark.parametrize(
    ("record", "complaint"),
    [
        ({**GOOD_FRAME, "fields": "state=0"}, "'fields' must be an object"),
        ({**GOOD_FRAME, "fields": [0, 1]}, "'fields' must be an object"),
        ({**GOOD_FRAME, "sender": "one"}, "'sender' must be a whole number"),
        ({**GOOD_FRAME, "t": None}, "'t' must be a number"),
        ({**GOOD_FRAME, "type": 32}, "'type' must be a string"),
    ],
)
def test_export_of_a_record_of_the_wrong_shape_names_its_line(
    record: dict[str, object], complaint: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    log = write_log(tmp_path / "x.jsonl", SESSION, GOOD_FRAME, record)
    assert_one_line_failure(["export", str(log), "-o", "-"], f"{log}:3: {complaint}", capsys)


@pytest.mark.parametrize("content", [b"", b"\x00" * 4096], ids=["empty", "all NUL"])
@pytest.mark.parametrize("command", ["export", "replay"])
def test_a_log_without_records_is_an_error(
    command: str, content: bytes, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    log = tmp_path / "x.jsonl"
    log.write_bytes(content)
    argv = [command, str(log)] + (["--no-ui"] if command == "replay" else [])
    assert_one_line_failure(argv, "holds no log records", capsys)


@pytest.mark.parametrize(
    ("argv", "complaint"),
    [
        (["replay", "x.jsonl", "--speed", "abc"], "--speed: must be a number > 0 or max"),
        (["demo", "--particles", "0"], "--particles: must be a whole number 1..200, not '0'"),
        (["demo", "--particles", "-1"], "--particles: must be a whole number 1..200"),
        (["demo", "--particles", "300"], "--particles: must be a whole number 1..200"),
        (["demo", "--speed", "0"], "--speed: must be a number > 0 or max, not '0'"),
        (["demo", "--speed", "-2"], "--speed: must be a number > 0 or max"),
        (["demo", "--no-ui", "--run-s", "nan"], "--run-s: must be a number > 0, not 'nan'"),
        (["log", "--radio", "virtual://2", "--duration", "nan"], "--duration: must be a number"),
        (["log", "--radio", "virtual://2", "--duration", "-1"], "--duration: must be a number"),
        (["log", "--radio", "virtual://2?seed=-1"], "seed must be a whole number >= 0"),
        (["log", "--radio", "virtual://2?lamp=0,0,nan"], "lamp=X,Y,H in metres"),
        (["log", "--radio", "virtual://2?spacing=nan"], "spacing must be a number > 0"),
        (["log", "--radio", "virtual://2?start=inf"], "start must be a number >= 0"),
        (["log", "--radio", "virtual://2?speed=nan"], "speed must be a number > 0 or max"),
        (["log", "--radio", "virtual://2?noise=-1"], "noise must be a number >= 0"),
        (["log", "--radio", "emulated://2?loss=nan"], "loss must be a number >= 0 and < 1"),
        (["log", "--radio", "serial:///dev/null?baud=0"], "baud must be a whole number > 0"),
        (["export", "x.jsonl", "--type", "STATUSS"], "--type: no message type 'STATUSS'"),
        (["console", "--radio", "virtual://2"], "the console needs a terminal"),
        (["log"], "say which radio to record: --radio URL (see particlebot log --help)"),
        ([], "the following arguments are required: COMMAND"),
    ],
)
def test_bad_options_are_one_line(
    argv: list[str], complaint: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert_one_line_failure(argv, complaint, capsys)


def test_a_backend_that_cannot_be_imported_is_one_line(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    # As if digi-xbee were missing or broken: importing the backend's module fails.
    monkeypatch.setitem(sys.modules, "particlebot.radio.xbee", None)
    assert_one_line_failure(
        ["log", "--radio", "xbee:///dev/ttyUSB0"], "The xbee:// backend cannot be loaded", capsys
    )


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="needs Linux's /dev/full")
@pytest.mark.parametrize("command", [["export", "-o", "-"], ["replay", "--no-ui"]])
def test_output_to_a_full_disk_is_one_line(command: list[str], tmp_path: Path) -> None:
    log = write_log(tmp_path / "x.jsonl", SESSION, GOOD_RX, GOOD_FRAME)
    argv = [sys.executable, "-m", "particlebot.cli", command[0], str(log), *command[1:]]
    with open("/dev/full", "w") as full:  # every write fails: No space left on device
        done = subprocess.run(argv, stdout=full, stderr=subprocess.PIPE, text=True, timeout=60)
    assert done.returncode == 2
    assert done.stderr == "particlebot: cannot write the output: No space left on device\n"
