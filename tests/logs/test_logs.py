"""Session logs: written line by line (a killed process loses nothing), read, exported, replayed."""

from __future__ import annotations

import csv
import io
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from particlebot.cli import main
from particlebot.logs.export import export_csv
from particlebot.logs.jsonl import JsonlWriter, LogFormatError, default_log_path, read_log
from particlebot.logs.replay import ReplayRadio
from particlebot.protocol import (
    DropReason,
    Method,
    Param,
    ParamResult,
    ParamValue,
    State,
    Stop,
    decode_frame,
    encode_frame,
)
from particlebot.radio import Packet, ReadOnlyRadioError
from particlebot.radio.serial import SerialRadio
from particlebot.session import Note, ReceivedFrame, Session
from tests.support.fakes import FakeRadio, ManualClock, Recorder, status_frame, wait_until
from tests.support.ptys import VanishingPty


def record_session(radio: FakeRadio, path: Path) -> Recorder:
    """A session over the fake radio with a log writer; returns what the session saw."""
    recorder = Recorder()
    writer = JsonlWriter(path, radio=radio.url)
    with Session(radio, [writer, recorder]) as session:
        radio.inject(status_frame(3, seq=1, s_n=2, intensity=700), source="A")
        radio.clock.advance(0.5)
        corrupted = bytearray(status_frame(4, seq=9))
        corrupted[12] ^= 0x40
        radio.inject(b"noise" + bytes(corrupted), source="B")
        radio.clock.advance(0.5)
        radio.inject(status_frame(4, seq=10, s_n=3, sensors=(1, 2, 3, 4, 5, 6)), source="B")
        assert recorder.wait(lambda: len(recorder.frames) == 2)
        session.send(Stop())
    return recorder


def log_command(radio: str, log_dir: Path) -> list[str]:
    return [
        sys.executable,
        "-m",
        "particlebot.cli",
        "log",
        "--radio",
        radio,
        "--log-dir",
        f"{log_dir}",
    ]


def test_every_line_is_one_json_object_with_time_sender_bytes_and_fields(tmp_path: Path) -> None:
    path = tmp_path / "session.jsonl"
    record_session(FakeRadio(), path)
    records = list(read_log(path))
    kinds = [r["kind"] for r in records]
    assert kinds[0] == "session" and kinds[-1] == "end"
    frames = [r for r in records if r["kind"] == "frame"]
    assert [(f["src"], f["sender"], f["seq"]) for f in frames] == [("A", 3, 1), ("B", 4, 10)]
    assert frames[0]["fields"]["s_n"] == 2
    assert frames[0]["hex"] == status_frame(3, seq=1, s_n=2, intensity=700).hex()
    assert frames[0]["t"] == 1000.0
    drops = {r["reason"] for r in records if r["kind"] == "drop"}
    assert drops == {"skipped", "bad_crc"}
    (sent,) = [r for r in records if r["kind"] == "tx"]
    assert (sent["type"], sent["sender"]) == ("STOP", 0)
    raw = [r for r in records if r["kind"] == "rx"]
    assert len(raw) == 3 and raw[1]["hex"].startswith(b"noise".hex())


@pytest.mark.slow
def test_a_killed_logger_leaves_a_log_whose_every_line_parses(tmp_path: Path) -> None:
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    process = subprocess.Popen(
        log_command("virtual://4?speed=50", tmp_path),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        env=env,
    )
    try:
        assert wait_until(lambda: any(tmp_path.glob("*.jsonl")), timeout=30)
        (path,) = tmp_path.glob("*.jsonl")
        assert wait_until(lambda: path.read_bytes().count(b"\n") >= 40, timeout=30)
        process.send_signal(signal.SIGKILL)
    finally:
        process.wait(timeout=10)
    data = path.read_bytes()
    assert data.endswith(b"\n")
    lines = data.splitlines()
    records = [json.loads(line) for line in lines]
    assert records[0]["kind"] == "session"
    assert any(r["kind"] == "frame" and r["type"] == "STATUS" for r in records)
    assert records[-1]["kind"] != "end"  # it really was killed mid-session


@pytest.mark.slow
def test_a_log_ended_by_sigterm_is_closed_properly(tmp_path: Path) -> None:
    process = subprocess.Popen(
        log_command("virtual://2?speed=20", tmp_path),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    assert wait_until(lambda: any(tmp_path.glob("*.jsonl")), timeout=30)
    (path,) = tmp_path.glob("*.jsonl")
    assert wait_until(lambda: b'"STATUS"' in path.read_bytes(), timeout=30)
    process.send_signal(signal.SIGTERM)
    out, _ = process.communicate(timeout=20)
    assert process.returncode == 0
    assert list(read_log(path))[-1]["kind"] == "end"
    assert f"Log: {path}" in out.decode()


def test_a_torn_last_line_is_skipped_but_a_bad_line_inside_is_reported(tmp_path: Path) -> None:
    path = tmp_path / "torn.jsonl"
    path.write_text('{"t": 1, "kind": "session"}\n{"t": 2, "kind": "no')
    assert [r["kind"] for r in read_log(path)] == ["session"]
    path.write_text('{"t": 1}\nnot json\n{"t": 3}\n')
    with pytest.raises(LogFormatError, match=":2:"):
        list(read_log(path))


def test_log_names_never_overwrite_an_earlier_session(tmp_path: Path) -> None:
    first = default_log_path(tmp_path)
    first.write_text("")
    second = default_log_path(tmp_path)
    assert second != first and second.parent == tmp_path and second.suffix == ".jsonl"


def test_csv_export_has_a_row_per_frame_and_a_column_per_field(tmp_path: Path) -> None:
    path = tmp_path / "session.jsonl"
    record_session(FakeRadio(), path)
    out = io.StringIO()
    assert export_csv(path, out) == 3
    rows = list(csv.DictReader(io.StringIO(out.getvalue())))
    assert [(r["direction"], r["type"], r["sender"]) for r in rows] == [
        ("rx", "STATUS", "3"),
        ("rx", "STATUS", "4"),
        ("tx", "STOP", "0"),
    ]
    assert rows[1]["s_n"] == "3"
    assert [rows[1][f"sensors_{k}"] for k in range(6)] == ["1", "2", "3", "4", "5", "6"]
    assert rows[2]["s_n"] == ""
    only = io.StringIO()
    assert export_csv(path, only, ["stop"]) == 1


def test_a_replayed_log_gives_the_same_frames_and_the_same_faults(tmp_path: Path) -> None:
    path = tmp_path / "session.jsonl"
    live = record_session(FakeRadio(), path)
    replayed = Recorder()
    radio = ReplayRadio(path, speed=float("inf"))
    with Session(radio, [replayed]) as session:
        assert replayed.wait(lambda: len(replayed.frames) == 2)
        assert wait_until(lambda: radio.finished)
        with pytest.raises(ReadOnlyRadioError):
            session.send(Stop())
    assert [r.frame for r in replayed.frames] == [r.frame for r in live.frames]
    assert [(r.source, r.time) for r in replayed.frames] == [
        (r.source, r.time) for r in live.frames
    ]
    reasons = sorted(d.event.reason.value for d in replayed.dropped)
    assert reasons == sorted(d.event.reason.value for d in live.dropped)
    assert DropReason.BAD_CRC.value in reasons


def test_replay_keeps_the_original_spacing_divided_by_speed(tmp_path: Path) -> None:
    path = tmp_path / "session.jsonl"
    record_session(FakeRadio(), path)
    radio = ReplayRadio(path, speed=10.0)
    first = radio.receive(timeout=2)
    second = radio.receive(timeout=2)
    assert first is not None and second is not None
    assert second.time - first.time == pytest.approx(0.5)
    assert radio.now() - first.time >= 0.5
    radio.close()


def test_an_unplugged_port_is_logged_and_logging_goes_on_when_it_returns(tmp_path: Path) -> None:
    pty = VanishingPty(tmp_path / "ttyUSB0")
    recorder = Recorder()
    log_path = tmp_path / "session.jsonl"
    radio = SerialRadio(str(pty.path), retry_s=0.05)
    with Session(radio, [JsonlWriter(log_path, radio=radio.url), recorder]):
        pty.write(status_frame(1, seq=1))
        assert recorder.wait(lambda: len(recorder.frames) == 1)
        pty.unplug()
        assert recorder.wait(lambda: len(recorder.links) == 1)
        pty.replug()
        assert recorder.wait(lambda: len(recorder.links) == 2)
        pty.write(status_frame(1, seq=2))
        assert recorder.wait(lambda: len(recorder.frames) == 2)
    pty.close()
    records = [r for r in read_log(log_path) if r["kind"] in ("frame", "link")]
    assert [(r["kind"], r.get("seq", r.get("state"))) for r in records] == [
        ("frame", 1),
        ("link", "lost"),
        ("link", "connected"),
        ("frame", 2),
        ("link", "closed"),
    ]


def test_the_end_of_a_log_is_never_stamped_before_what_it_ends(tmp_path: Path) -> None:
    # A sped-up virtual radio's clock runs ahead of the wall clock, and so do its frames' times.
    clock = ManualClock(start=time.time() + 3600.0)
    path = tmp_path / "fast.jsonl"
    writer = JsonlWriter(path, radio="virtual://1?speed=max", clock=clock)
    clock.advance(5.0)
    writer.on_frame(ReceivedFrame(clock() + 0.01, "virtual-01", decode_frame(status_frame(1))))
    writer.on_close()
    times = [record["t"] for record in read_log(path)]
    assert times == sorted(times)
    assert list(read_log(path))[-1]["kind"] == "end"


def test_csv_shows_state_method_param_and_result_by_name(tmp_path: Path) -> None:
    path = tmp_path / "names.jsonl"
    writer = JsonlWriter(path)
    status = status_frame(3, state=int(State.CYCLING), method=int(Method.NONLINEAR))
    writer.on_frame(ReceivedFrame(1.0, None, decode_frame(status)))
    reply = ParamValue(param=int(Param.CYCLE_STEPS), result=int(ParamResult.BUSY), value=150)
    writer.on_frame(ReceivedFrame(2.0, None, decode_frame(encode_frame(reply, 3, 1))))
    writer.on_note(Note(3.0, "STOP confirmed"))
    writer.on_close()
    out = io.StringIO()
    assert export_csv(path, out) == 2
    status_row, reply_row = csv.DictReader(io.StringIO(out.getvalue()))
    assert (status_row["state"], status_row["method"]) == ("CYCLING", "NONLINEAR")
    assert (reply_row["param"], reply_row["result"]) == ("CYCLE_STEPS", "BUSY")
    assert "note" not in status_row
    with_notes = io.StringIO()
    assert export_csv(path, with_notes, notes=True) == 3
    note = list(csv.DictReader(io.StringIO(with_notes.getvalue())))[-1]
    assert (note["direction"], note["note"]) == ("note", "STOP confirmed")


@pytest.mark.slow
def test_csv_to_a_reader_that_stops_early_ends_quietly(tmp_path: Path) -> None:
    path = tmp_path / "long.jsonl"
    writer = JsonlWriter(path)
    frame = decode_frame(status_frame(3))
    for k in range(3000):  # some 500 KB of CSV: far more than a pipe holds
        writer.on_frame(ReceivedFrame(float(k), None, frame))
    writer.on_close()
    process = subprocess.Popen(
        [sys.executable, "-m", "particlebot.cli", "export", str(path), "-o", "-"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    assert process.stdout is not None and process.stderr is not None
    assert process.stdout.readline().startswith(b"t,direction")  # what `| head -1` does
    process.stdout.close()
    error = process.stderr.read()
    assert process.wait(timeout=60) == 0
    assert error == b""


def write_timed_log(path: Path, span_s: float, packets: int = 20) -> Path:
    writer = JsonlWriter(path)
    for k in range(packets):
        at = 1000.0 + span_s * k / (packets - 1)
        writer.on_packet(Packet(status_frame(1 + k % 3, seq=k), None, at))
    writer.on_close()
    return path


def test_replay_without_the_console_goes_as_fast_as_possible(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # Ten minutes of log: at the old default, real time, this would outlast the test's timeout.
    log = write_timed_log(tmp_path / "long.jsonl", span_s=600.0)
    assert main(["replay", str(log), "--no-ui"]) == 0
    out = capsys.readouterr().out
    assert "Replaying 20 packets (600.0 s of log)" in out and "as fast as possible" in out
    assert "Replayed 20 packets" in out


def test_replay_without_the_console_shows_its_progress(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr("particlebot.commands.replay.PROGRESS_EVERY_S", 0.1)
    log = write_timed_log(tmp_path / "short.jsonl", span_s=4.0)
    assert main(["replay", str(log), "--no-ui", "--speed", "8"]) == 0  # half a second
    progress = [line for line in capsys.readouterr().out.splitlines() if " of 4.0 s" in line]
    assert progress and progress[0].strip().endswith("of 4.0 s")


def test_a_finished_replay_stops_its_clock_where_the_session_ended(tmp_path: Path) -> None:
    # Run on, every particle turned SILENT in the console once the log had played out.
    clock = ManualClock(start=1000.0)
    path = tmp_path / "short.jsonl"
    writer = JsonlWriter(path, clock=clock)
    for k in range(3):
        writer.on_packet(Packet(status_frame(1, seq=k), None, clock()))
        clock.advance(1.0)
    clock.advance(2.0)  # the session went on quietly for 2 s more: that silence is the log's
    writer.on_close()
    radio = ReplayRadio(path, speed=1000.0)  # 5 s of log in 5 ms
    while radio.receive(timeout=1.0) is not None:
        pass
    assert radio.finished
    assert wait_until(lambda: radio.now() == 1005.0)
    assert radio.now() == 1005.0
    radio.close()


def test_replay_without_the_console_lists_resets_and_flags(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    clock = ManualClock(start=1000.0)
    path = tmp_path / "reset.jsonl"
    writer = JsonlWriter(path, clock=clock)
    running = {"state": int(State.CYCLING), "run_id": 4}
    for k, (uptime, fields) in enumerate([(50_000, running), (51_000, running), (300, {})]):
        writer.on_packet(Packet(status_frame(2, seq=k, uptime_ms=uptime, **fields), None, clock()))
        clock.advance(1.0)
    last = status_frame(2, seq=3, uptime_ms=1300, resets=2, last_reset_cause=0x04)
    writer.on_packet(Packet(last, None, clock()))
    writer.on_close()
    assert main(["replay", str(path), "--no-ui"]) == 0
    (line,) = [line for line in capsys.readouterr().out.splitlines() if "particle   2" in line]
    assert line.endswith("resets 2 (brown-out)  RESET in run 4")
