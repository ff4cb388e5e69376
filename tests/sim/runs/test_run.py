"""A run in its folder: the published CSV, snapshots, a stop and a resume that changes nothing,
pictures, a video, and the folder read back by `particlebot stats`."""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from particlebot.analysis import sources
from particlebot.sim.runs import simcsv
from particlebot.sim.runs.csvlog import keep_rows_through
from particlebot.sim.runs.run import Run, RunError, latest_snapshot
from particlebot.sim.runs.video import encode
from particlebot.sim.scenarios.build import build_world
from particlebot.sim.scenarios.scenario import (
    LampSpec,
    ObjectSpec,
    OutputSpec,
    Scenario,
    SwarmSpec,
)
from particlebot.sim.scenarios.toml_file import read_scenario


def tiny(**changes: object) -> Scenario:
    """12 particles for 4 s: a row every 0.5 s, a snapshot every second."""
    base = Scenario(
        name="tiny",
        swarm=SwarmSpec(particles=12),
        lamp=LampSpec(-1.5, 0.2),
        duration_s=4.0,
        seed=3,
        output=OutputSpec(dump_interval_s=0.5, snapshot_interval_s=1.0, video_frames=4),
    )
    return replace(base, **changes)  # type: ignore[arg-type]


def stop_after(chunks: int) -> Callable[[], bool]:
    calls = [0]

    def should_stop() -> bool:
        calls[0] += 1
        return calls[0] > chunks

    return should_stop


def test_a_run_folder_holds_everything_the_run_made(tmp_path: Path) -> None:
    folder = tmp_path / "run"
    summary = Run.start(build_world(tiny()), folder).advance()

    assert summary.finished and summary.steps == 400 and summary.t_s == pytest.approx(4.0)
    names = {p.name for p in folder.iterdir()}
    assert {
        "scenario.toml", "published.cfg", "run.csv", "snapshots", "swarm-start.png",
        "swarm.png", "track.png", "summary.json",
    } <= names  # fmt: skip
    snapshots = sorted(p.name for p in (folder / "snapshots").iterdir())
    assert snapshots == [f"step-{s:09d}.npz" for s in (0, 100, 200, 300, 400)]
    assert json.loads((folder / "summary.json").read_text())["steps"] == 400
    # The scenario as run reads back as the scenario that ran.
    assert read_scenario(folder / "scenario.toml") == tiny()


def test_the_csv_is_the_published_format_row_for_row(tmp_path: Path) -> None:
    built = build_world(tiny())
    run = Run.start(built, tmp_path / "run")
    summary = run.advance()

    lines = (tmp_path / "run" / "run.csv").read_text().splitlines()
    assert lines[0] == "Seed, 3"
    assert lines[1] == "Time,Centroid X, Centroid Y, Distance"
    assert len(lines) == 2 + 9  # t = 0, 0.5, ..., 4
    assert lines[2].startswith("0.000000,") and lines[-1].startswith("4.000000,")
    cells = lines[-1].split(",")
    assert cells[-1] == "" and len(cells) == 5  # the published trailing comma
    cx, cy, distance = (float(c) for c in cells[1:4])
    assert (cx, cy) == pytest.approx(summary.centroid_end, abs=1e-6)
    assert distance == pytest.approx(summary.distance_to_light_end, abs=1e-6)
    parsed = simcsv.read_published_csv(tmp_path / "run" / "run.csv")
    np.testing.assert_allclose(parsed.time_s, np.arange(9) * 0.5)
    assert parsed.seed == 3


def test_per_particle_columns_come_in_the_published_order_with_the_object_last(
    tmp_path: Path,
) -> None:
    scenario = tiny(
        objects=(ObjectSpec(radius_factor=1.5),),
        output=OutputSpec(dump_interval_s=1.0, per_particle=True),
        duration_s=2.0,
    )
    built = build_world(scenario)
    Run.start(built, tmp_path / "run").advance()

    header = (tmp_path / "run" / "run.csv").read_text().splitlines()[1]
    names = [c.strip() for c in header.split(",") if c.strip()]
    bodies = 13
    assert names[0] == "Time"
    assert names[1:3] == ["Particlebot_0_xpos", "Particlebot_0_ypos"]
    assert names[1 + 2 * bodies : 3 + 2 * bodies] == ["Particlebot_0_xvel", "Particlebot_0_yvel"]
    assert names[1 + 4 * bodies] == "Particlebot_0_rad"
    assert names[-3:] == ["Centroid X", "Centroid Y", "Distance"]
    run = simcsv.read_published_csv(tmp_path / "run" / "run.csv")
    state = built.world.state()
    assert run.x_m is not None and run.r_m is not None
    np.testing.assert_allclose(run.x_m[-1, :12], state.x, atol=1e-6)
    # The object is the last "particle", as the published object is its last cell.
    assert run.r_m[-1, 12] == pytest.approx(1.5 * 0.0775, abs=1e-6)
    assert run.x_m[-1, 12] == pytest.approx(state.objects[0, 0], abs=1e-6)


def test_stats_reads_the_run_folder_and_finds_the_lamp(tmp_path: Path) -> None:
    Run.start(build_world(tiny()), tmp_path / "run").advance()

    (series,) = sources.load_source(tmp_path / "run")

    assert series.kind == "simulator"
    assert series.lamp_cm == pytest.approx((-150.0, 20.0))
    assert series.lamp_from == "published.cfg"
    assert len(series.t_s) == 9


@pytest.mark.slow
def test_a_stopped_run_resumes_to_exactly_the_uninterrupted_result(tmp_path: Path) -> None:
    Run.start(build_world(tiny()), tmp_path / "straight").advance()
    stopped = Run.start(build_world(tiny()), tmp_path / "stopped").advance(stop_after(3))
    assert not stopped.finished and 0 < stopped.steps < 400

    resumed = Run.resume(tmp_path / "stopped").advance()

    assert resumed.finished and resumed.steps_now == 400 - stopped.steps
    straight_csv = (tmp_path / "straight" / "run.csv").read_text()
    assert (tmp_path / "stopped" / "run.csv").read_text() == straight_csv
    end = {}
    for name in ("straight", "stopped"):
        with np.load(tmp_path / name / "snapshots" / "step-000000400.npz") as data:
            end[name] = {key: data[key] for key in data.files if key.startswith("state_")}
    for key, value in end["straight"].items():
        np.testing.assert_array_equal(end["stopped"][key], value, err_msg=key)
    assert resumed.centroid_start == pytest.approx(stopped.centroid_start)


@pytest.mark.slow
def test_resuming_drops_rows_written_after_the_last_snapshot(tmp_path: Path) -> None:
    folder = tmp_path / "run"
    Run.start(build_world(tiny()), folder).advance(stop_after(4))
    snapshot_t = int(latest_snapshot(folder).stem.split("-")[1]) * 0.01  # type: ignore[union-attr]
    csv = folder / "run.csv"
    # As if the run had gone on writing rows before it was killed (no snapshot for them).
    csv.write_text(csv.read_text() + f"{snapshot_t + 0.5:f},9, 9, 9,\n{snapshot_t + 1:f},9, 9")

    Run.resume(folder).advance()

    times = simcsv.read_published_csv(csv).time_s
    np.testing.assert_allclose(times, np.arange(9) * 0.5)


def test_keep_rows_through_keeps_the_header_and_earlier_complete_rows(tmp_path: Path) -> None:
    path = tmp_path / "x.csv"
    path.write_text("Seed, 1\nTime,Centroid X, Centroid Y, Distance\n0.000000,1, 2, 3,\n"
                    "1.000000,1, 2, 3,\n2.000000,1, 2, 3,\n3.0000")  # fmt: skip

    keep_rows_through(path, 1.0)

    assert path.read_text().splitlines()[2:] == ["0.000000,1, 2, 3,", "1.000000,1, 2, 3,"]


def test_a_run_never_writes_into_a_taken_folder(tmp_path: Path) -> None:
    (tmp_path / "taken").mkdir()
    (tmp_path / "taken" / "notes.txt").write_text("mine")

    with pytest.raises(RunError, match="exists and is not empty"):
        Run.start(build_world(tiny()), tmp_path / "taken")
    assert [p.name for p in (tmp_path / "taken").iterdir()] == ["notes.txt"]


def test_resume_wants_a_run_folder_with_a_snapshot(tmp_path: Path) -> None:
    with pytest.raises(RunError, match="not a run folder"):
        Run.resume(tmp_path)
    folder = tmp_path / "run"
    Run.start(build_world(tiny()), folder).advance()
    for snapshot in (folder / "snapshots").iterdir():
        snapshot.unlink()
    with pytest.raises(RunError, match="no snapshot to resume from"):
        Run.resume(folder)


@pytest.mark.slow
def test_a_video_is_made_of_the_runs_frames(tmp_path: Path) -> None:
    folder = tmp_path / "run"
    Run.start(build_world(tiny()), folder, record_video=True).advance()

    frames = sorted((folder / "frames").glob("0*.png"))
    assert [f.name for f in frames] == [f"{i:06d}.png" for i in range(5)]
    video = folder / "run.mp4"
    assert video.stat().st_size > 1000
    import cv2

    capture = cv2.VideoCapture(str(video))
    count = 0
    while capture.read()[0]:
        count += 1
    capture.release()
    assert count == 5
    gif = encode(folder / "frames", folder / "run.gif")
    assert gif.read_bytes()[:6] == b"GIF89a"
