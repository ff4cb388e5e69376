"""`particlebot plot`: a log drawn as a PNG, its series extracted right, bad logs refused."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import pytest
from matplotlib.image import imread

from particlebot.cli import main
from particlebot.logs.jsonl import JsonlWriter
from particlebot.plots import (
    ParticleSeries,
    PlotInputError,
    StateBand,
    extract,
    read_records,
    render,
    state_bands,
)
from particlebot.protocol import Method, Start, State, Stop, decode_frame, encode_frame
from particlebot.session import Note, ReceivedFrame, SentFrame
from tests.support.fakes import status_message

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"

# (seconds after the session record, state, s_n, radius_um, intensity) per particle.
SCRIPT: dict[int, list[tuple[float, State, int, int, int]]] = {
    2: [
        (0.5, State.IDLE, 0, 77500, 0),
        (2.5, State.IDLE, 0, 77500, 950),
        (4.5, State.ESTIMATING, 0, 77500, 951),
        (6.5, State.CYCLING, 1, 101250, 952),
        (8.5, State.CYCLING, 1, 120000, 953),
        (10.5, State.IDLE, 1, 77500, 954),
    ],
    1: [
        (0.7, State.IDLE, 0, 77500, 800),
        (2.7, State.ESTIMATING, 0, 77500, 801),
        (4.7, State.WAITING, 2, 77500, 802),
        (6.7, State.PAUSED, 2, 77500, 803),
        (8.7, State.STOPPING, 2, 90000, 804),
    ],
    # Never estimated: it must come last whatever its id.
    0: [(1.1, State.IDLE, 0, 77500, 500), (3.1, State.IDLE, 0, 77500, 501)],
}
START_AT = (3.0, 3.25)  # the console's campaign sends START twice
STOP_AT = 9.0
NOTE_AT = 11.5  # the last thing the session logged: the end of the time axis


@dataclass
class Written:
    path: Path
    started: float


def write_session(path: Path) -> Written:
    """A log written by the project's own JsonlWriter from real encoded frames."""
    writer = JsonlWriter(path, radio="virtual://3")
    started = json.loads(path.read_text().splitlines()[0])["t"]
    events: list[tuple[float, object]] = []
    for sender, samples in SCRIPT.items():
        for seq, (at, state, s_n, radius, intensity) in enumerate(samples):
            message = status_message(
                state=int(state), s_n=s_n, radius_um=radius, intensity=intensity, run_id=7
            )
            frame = decode_frame(encode_frame(message, sender, seq))
            events.append((at, ReceivedFrame(started + at, f"virtual-{sender:02d}", frame)))
    start = Start(
        run_id=7,
        method=int(Method.COUNTING),
        cycle_steps=100,
        wave_size=0,
        update_interval_s=0,
        phototaxis=0,
    )
    for seq, at in enumerate(START_AT):
        events.append((at, SentFrame(started + at, decode_frame(encode_frame(start, 0, seq)))))
    stop = decode_frame(encode_frame(Stop(), 0, 9))
    events.append((STOP_AT, SentFrame(started + STOP_AT, stop)))
    events.append((NOTE_AT, Note(started + NOTE_AT, "done")))
    for _, event in sorted(events, key=lambda item: item[0]):
        if isinstance(event, ReceivedFrame):
            writer.on_frame(event)
        elif isinstance(event, SentFrame):
            writer.on_sent(event)
        elif isinstance(event, Note):
            writer.on_note(event)
    writer.on_close()
    return Written(path, started)


@pytest.fixture
def session_log(tmp_path: Path) -> Written:
    return write_session(tmp_path / "session.jsonl")


def extracted(path: Path) -> list[ParticleSeries]:
    loaded = read_records(path)
    return extract(loaded.records, loaded.warnings).particles


def test_the_plot_command_writes_a_png_next_to_the_log(
    session_log: Written, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["plot", str(session_log.path)]) == 0
    png = session_log.path.with_suffix(".png")
    assert f"Plot: {png} (3 particles, 13 STATUS frames)" in capsys.readouterr().out
    assert png.read_bytes().startswith(PNG_MAGIC)
    pixels = imread(png)
    # A real drawing, not a blank canvas: many distinct colours over a sizeable image.
    assert pixels.shape[0] > 400 and pixels.shape[1] > 600
    assert len({tuple(p) for p in pixels.reshape(-1, pixels.shape[2])[::97]}) > 20


def test_the_output_option_chooses_where_the_png_goes(session_log: Written, tmp_path: Path) -> None:
    output = tmp_path / "elsewhere.png"
    assert main(["plot", str(session_log.path), "-o", str(output)]) == 0
    assert output.read_bytes().startswith(PNG_MAGIC)
    assert not session_log.path.with_suffix(".png").exists()


def test_the_radius_series_of_a_particle_is_its_status_radius_in_order(
    session_log: Written,
) -> None:
    particle = next(p for p in extracted(session_log.path) if p.particle_id == 2)
    assert particle.radius_um == [sample[3] for sample in SCRIPT[2]]
    assert particle.radius_mm == [sample[3] / 1000 for sample in SCRIPT[2]]
    assert particle.intensity == [sample[4] for sample in SCRIPT[2]]
    # Times count from the session record, the first line of the log.
    assert particle.times == pytest.approx([sample[0] for sample in SCRIPT[2]], abs=1e-5)


def test_particles_are_ordered_by_their_latest_s_n_and_the_unestimated_come_last(
    session_log: Written,
) -> None:
    particles = extracted(session_log.path)
    assert [p.particle_id for p in particles] == [2, 1, 0]
    assert [p.label for p in particles] == ["id 2  S_n 1", "id 1  S_n 2", "id 0"]


def test_state_bands_begin_and_end_at_the_status_frames_that_report_them(
    session_log: Written,
) -> None:
    loaded = read_records(session_log.path)
    session = extract(loaded.records)
    assert session.duration == pytest.approx(NOTE_AT, abs=1e-5)
    bands = state_bands(session.particle(2), session.duration)
    assert [band.state for band in bands] == [
        State.IDLE,
        State.ESTIMATING,
        State.CYCLING,
        State.IDLE,
    ]
    edges = [edge for band in bands for edge in (band.start, band.end)]
    # The last sample holds for one STATUS period (2 s) but not past the session's end.
    assert edges == pytest.approx([0.5, 4.5, 4.5, 6.5, 6.5, 10.5, 10.5, NOTE_AT], abs=1e-5)


def test_a_silence_longer_than_three_status_periods_is_left_out_of_the_state_bands() -> None:
    particle = ParticleSeries(
        7,
        times=[1.0, 3.0, 5.0, 7.0, 15.0],
        states=[int(State.WAITING)] * 4 + [int(State.DONE)],
        s_n=[3] * 5,
        intensity=[600] * 5,
        radius_um=[77500] * 5,
    )
    assert state_bands(particle, session_end=30.0) == [
        StateBand(State.WAITING, 1.0, 9.0),
        StateBand(State.DONE, 15.0, 17.0),
    ]


def test_commands_sent_are_found_and_resends_of_one_command_are_one_mark(
    session_log: Written,
) -> None:
    loaded = read_records(session_log.path)
    commands = extract(loaded.records).commands
    assert [(c.name, c.sends) for c in commands] == [("START", 2), ("STOP", 1)]
    assert [c.t for c in commands] == pytest.approx([START_AT[0], STOP_AT], abs=1e-5)
    assert commands[0].label == "START run 7 COUNTING (sent 2x)"


def test_a_missing_log_is_a_clear_error_with_exit_code_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["plot", str(tmp_path / "absent.jsonl")]) == 2
    err = capsys.readouterr().err
    assert "no log file" in err and "Traceback" not in err
    assert not (tmp_path / "absent.png").exists()


def test_an_empty_log_is_a_clear_error_with_exit_code_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    log = tmp_path / "empty.jsonl"
    log.write_bytes(b"")
    assert main(["plot", str(log)]) == 2
    assert "holds no log records" in capsys.readouterr().err


def test_a_log_without_status_frames_is_a_clear_error_with_exit_code_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    log = tmp_path / "quiet.jsonl"
    writer = JsonlWriter(log, radio="virtual://0")
    writer.on_note(Note(1.0, "nobody answered"))
    writer.on_close()
    assert main(["plot", str(log)]) == 2
    assert "no STATUS frames" in capsys.readouterr().err
    assert not log.with_suffix(".png").exists()


def test_a_truncated_last_line_is_skipped_with_a_warning_and_the_rest_is_plotted(
    session_log: Written, capsys: pytest.CaptureFixture[str]
) -> None:
    whole = extracted(session_log.path)
    with session_log.path.open("ab") as log:
        log.write(b'{"t":12.0,"kind":"frame","sender":2,"type":"STAT')
    assert main(["plot", str(session_log.path)]) == 0
    captured = capsys.readouterr()
    assert "last line is truncated" in captured.err
    assert session_log.path.with_suffix(".png").read_bytes().startswith(PNG_MAGIC)
    assert extracted(session_log.path) == whole


def test_a_damaged_line_inside_the_log_is_skipped_with_a_warning(session_log: Written) -> None:
    lines = session_log.path.read_bytes().split(b"\n")
    lines[3] = lines[3][:20]
    session_log.path.write_bytes(b"\n".join(lines))
    loaded = read_records(session_log.path)
    assert loaded.warnings == [f"{session_log.path}:4: not a JSON object; skipped"]
    assert extract(loaded.records).status_frames == 12


def test_an_unwritable_output_is_a_clear_error_with_exit_code_2(
    session_log: Written, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    output = tmp_path / "no-such-dir" / "plot.png"
    assert main(["plot", str(session_log.path), "-o", str(output)]) == 2
    assert "cannot write" in capsys.readouterr().err


def test_read_records_refuses_a_directory_without_a_traceback(tmp_path: Path) -> None:
    with pytest.raises(PlotInputError, match="cannot read"):
        read_records(tmp_path)


@pytest.mark.e2e
def test_the_headless_demo_writes_its_plot_and_its_film_next_to_its_log(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code = main(["demo", "--particles", "3", "--run-s", "61", "--log-dir", str(tmp_path)])
    out = capsys.readouterr().out
    assert code == 0, out
    (log,) = tmp_path.glob("*.jsonl")
    png = log.with_suffix(".png")
    assert f"Plot: {png} (3 particles," in out
    assert png.read_bytes().startswith(PNG_MAGIC)
    film = log.with_suffix(".mp4")
    assert f"Animation: {film}" in out
    assert film.read_bytes()[4:8] == b"ftyp"  # an MP4 container
    # The plot of a simulated radio's log has the top view beside the time panels.
    session = extract(read_records(log).records)
    assert session.world is not None and session.world.ids == [1, 2, 3]
    assert len(session.world.body_t) >= 120  # 2 Hz over the session


def test_particles_that_obeyed_a_stop_are_drawn_stopped_from_the_stop_on(
    session_log: Written,
) -> None:
    loaded = read_records(session_log.path)
    session = extract(loaded.records)
    bands = state_bands(session.particle(2), session.duration, session.stop_times)
    # Particle 2 reported CYCLING at 8.5 s and IDLE at 10.5 s; STOP went out at 9.0 s.
    assert [band.state for band in bands[-2:]] == [State.CYCLING, State.IDLE]
    edges = [edge for band in bands[-2:] for edge in (band.start, band.end)]
    assert edges == pytest.approx([6.5, STOP_AT, STOP_AT, NOTE_AT], abs=1e-5)


def test_a_stop_the_next_status_does_not_show_obeyed_leaves_the_band_alone() -> None:
    particle = ParticleSeries(
        5,
        times=[1.0, 3.0, 5.0],
        states=[int(State.CYCLING), int(State.CYCLING), int(State.PAUSED)],
        s_n=[1] * 3,
        intensity=[600] * 3,
        radius_um=[77500] * 3,
    )
    # A STOP it missed: its next STATUS still shows it running.
    assert state_bands(particle, session_end=10.0, stops=[4.0]) == [
        StateBand(State.CYCLING, 1.0, 5.0),
        StateBand(State.PAUSED, 5.0, 7.0),
    ]


def test_the_radius_legend_lists_particles_by_id(session_log: Written) -> None:
    loaded = read_records(session_log.path)
    session = extract(loaded.records)
    assert [p.particle_id for p in session.particles] == [2, 1, 0]  # rows follow the wave
    figure = render(session, "title")
    legend = figure.axes[0].get_legend()
    assert legend is not None
    assert [text.get_text() for text in legend.get_texts()] == [
        "id 0",
        "id 1  S_n 2",
        "id 2  S_n 1",
    ]


def write_two_runs(path: Path) -> Path:
    """Particle 1 in run 1 (START at 1 s), then run 2 (START at 10 s), STATUS every 2 s; at
    14.5 s it reports having reset (a brown-out)."""
    writer = JsonlWriter(path, radio="virtual://1")
    t0 = json.loads(path.read_text().splitlines()[0])["t"]
    for run_id, at in ((1, 1.0), (2, 10.0)):
        start = Start(
            run_id=run_id,
            method=int(Method.COUNTING),
            cycle_steps=100,
            wave_size=0,
            update_interval_s=0,
            phototaxis=0,
        )
        writer.on_sent(SentFrame(t0 + at, decode_frame(encode_frame(start, 0, run_id))))
    for seq, at in enumerate([0.5 + 2 * k for k in range(9)]):
        reset = at > 14.0
        message = status_message(
            state=int(State.IDLE if reset else State.CYCLING),
            run_id=1 if at < 10 else 2,
            uptime_ms=200 if reset else int(at * 1000) + 5000,
            resets=2 if reset else 1,
            last_reset_cause=0x04 if reset else 0x01,
        )
        frame = decode_frame(encode_frame(message, 1, seq))
        writer.on_frame(ReceivedFrame(t0 + at, "virtual-01", frame))
    writer.on_close()
    return path


def test_one_run_or_a_time_window_can_be_plotted(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    log = write_two_runs(tmp_path / "runs.jsonl")
    assert main(["plot", str(log), "--run", "2", "-o", str(tmp_path / "run2.png")]) == 0
    assert "(1 particles, 4 STATUS frames)" in capsys.readouterr().out  # 10.5 .. 16.5 s
    assert main(["plot", str(log), "--from", "2", "--to", "7", "-o", str(tmp_path / "w.png")]) == 0
    assert "(1 particles, 3 STATUS frames)" in capsys.readouterr().out  # 2.5, 4.5, 6.5 s
    assert main(["plot", str(log), "--run", "1"]) == 0
    assert "(1 particles, 4 STATUS frames)" in capsys.readouterr().out  # 2.5 .. 8.5 s
    assert main(["plot", str(log), "--run", "3"]) == 2
    assert "no START of run 3 in the log (runs started: 1, 2)" in capsys.readouterr().err


def test_resets_are_found_in_the_log_and_reported(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    log = write_two_runs(tmp_path / "runs.jsonl")
    loaded = read_records(log)
    (particle,) = extract(loaded.records).particles
    assert [(round(r.t, 3), r.cause) for r in particle.resets] == [(14.5, "brown-out")]
    assert main(["plot", str(log)]) == 0
    assert "particle 1 reset at 14.5 s (brown-out)" in capsys.readouterr().err
