"""Table S2 statistics: sampling, the lamp on +y, the t-test and the speed units, from tracks and
from simulator runs in the published format."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy import stats as scipy_stats

from particlebot.analysis.sources import (
    PUBLISHED_CYCLE_S,
    CentroidSeries,
    SourceError,
    load_source,
    trilaterate,
)
from particlebot.analysis.stats import EXPERIMENT_CYCLE_S, StatsSettings, analyse
from particlebot.analysis.trackfile import TrackRow, write_track
from particlebot.sim.runs.simcsv import read_published_csv, write_published_csv
from particlebot.swarm.api import Swarm


def series(
    t: np.ndarray, x: np.ndarray, y: np.ndarray, lamp: tuple[float, float], y_down: bool = False
) -> CentroidSeries:
    return CentroidSeries(
        "test", Path("test.csv"), "track", t, x, y, np.ones(len(t), bool), y_down, lamp, "given"
    )


def walk(
    angle: float, speed_cm_s: float, seconds: float = 1800.0, noise: float = 1.0, seed: int = 0
) -> tuple[np.ndarray, np.ndarray, np.ndarray, tuple[float, float]]:
    """A centroid drifting toward a lamp 300 cm away in direction `angle`, sampled at 2 Hz; the
    noise is drawn along and across that direction, so turning `angle` turns the whole run."""
    rng = np.random.default_rng(seed)
    t = np.arange(0, seconds + 0.25, 0.5)
    c, s = math.cos(angle), math.sin(angle)
    along = t * speed_cm_s + rng.normal(0, noise, len(t))
    across = rng.normal(0, noise, len(t))
    start = np.array([40.0, 20.0])
    x = start[0] + along * c - across * s
    y = start[1] + along * s + across * c
    return t, x, y, (start[0] + 300 * c, start[1] + 300 * s)


def test_speeds_and_p_value_follow_their_definitions() -> None:
    t, x, y, lamp = walk(0.3, 0.05)
    result = analyse(series(t, x, y, lamp), StatsSettings(cycle_s=9.0))
    # Independently: the positions at 0, 30, 60 ... s projected on the direction to the lamp.
    samples = np.arange(0, 1800.1, 30.0)
    index = np.searchsorted(t, samples)
    towards = np.array(lamp) - np.array([x[0], y[0]])
    towards /= np.linalg.norm(towards)
    along = (np.stack([x[index], y[index]], 1) - [x[0], y[0]]) @ towards
    steps = np.diff(along)
    assert result.steps_cm == pytest.approx(steps)
    assert result.average_mm_s == pytest.approx(steps.mean() * 10 / 30)
    assert result.peak_mm_s == pytest.approx(steps.max() * 10 / 30)
    # % of the contracted diameter per cycle: mm/s x 9 s / 155 mm x 100.
    assert result.average_pct == pytest.approx(steps.mean() / 30 * 10 * 9 / 155 * 100)
    t_statistic = steps.mean() / (steps.std(ddof=1) / math.sqrt(len(steps)))
    assert result.p_value == pytest.approx(scipy_stats.t.sf(t_statistic, len(steps) - 1))
    assert result.average_mm_s == pytest.approx(0.5, abs=0.02)


def test_the_row_does_not_depend_on_where_the_lamp_is_around_the_swarm() -> None:
    rows = []
    for angle in (0.0, 1.0, 2.5, -2.0):
        t, x, y, lamp = walk(angle, 0.03, seed=3)
        rows.append(analyse(series(t, x, y, lamp), StatsSettings()))
    for row in rows[1:]:
        assert row.steps_cm == pytest.approx(rows[0].steps_cm)
        assert row.p_value == pytest.approx(rows[0].p_value)
        assert row.sample_x_cm == pytest.approx(rows[0].sample_x_cm)


def test_image_coordinates_are_turned_y_up_before_the_lamp_goes_on_plus_y() -> None:
    # In the picture the swarm moves up (y shrinks) toward a lamp near the top: toward it.
    t = np.arange(0, 600.1, 1.0)
    x = np.full_like(t, 100.0) + np.sin(t / 7)
    y = 120.0 - 0.02 * t
    result = analyse(series(t, x, y, (100.0, 10.0), y_down=True), StatsSettings())
    assert result.average_mm_s == pytest.approx(0.2)
    assert result.p_value < 1e-6
    # The lamp's right on the floor seen from above is the picture's right.
    assert result.sample_x_cm[7] == pytest.approx(x[210] - x[0], abs=1e-6)


def test_a_swarm_going_nowhere_is_not_significant() -> None:
    t, x, y, lamp = walk(1.0, 0.0, noise=2.0, seed=5)
    result = analyse(series(t, x, y, lamp), StatsSettings())
    assert result.p_value > 0.01
    assert abs(result.average_mm_s) < 0.2


def test_flagged_frames_leave_gaps_that_are_not_bridged(tmp_path: Path) -> None:
    rows = [
        TrackRow(t, 100.0, 100.0 - 0.1 * t, 2000.0, "ok" if not 50 <= t <= 75 else "lamp", int(t))
        for t in np.arange(0.0, 300.5, 0.5)
    ]
    path = tmp_path / "run.track.csv"
    write_track(path, rows, {"lamp_cm": "100.0,0.0"})
    (source,) = load_source(path)
    result = analyse(source, StatsSettings())
    # The sample at 60 s falls in the flagged stretch: the two intervals touching it are missing.
    assert result.steps == 8
    assert any("2 of 10 intervals" in note for note in result.notes)
    accepted = analyse(load_source(path, frozenset({"lamp"}))[0], StatsSettings())
    assert accepted.steps == 10
    assert accepted.average_mm_s == pytest.approx(1.0)


def test_averaging_over_a_cycle_removes_the_breathing_wobble() -> None:
    t = np.arange(0, 900.1, 0.5)
    # Drift 0.5 mm/s toward +y plus a 4 cm wobble with the 9 s cycle (the region's lean).
    y = 0.05 * t + 4 * np.sin(2 * math.pi * t / 9.0)
    x = np.zeros_like(t)
    single = analyse(series(t, x, y, (0.0, 500.0)), StatsSettings(interval_s=20.0))
    averaged = analyse(series(t, x, y, (0.0, 500.0)), StatsSettings(interval_s=20.0, average_s=9.0))
    assert np.std(averaged.steps_cm) < 0.05 * np.std(single.steps_cm)
    assert averaged.average_mm_s == pytest.approx(0.5, abs=1e-3)


def test_a_published_run_reproduces_the_table_s3_to_s4_conversion(tmp_path: Path) -> None:
    """Our notes: 1.24 mm/s x the 12 s cycle = 14.9 mm = 9.6 % of 155 mm (Tables S3/S4)."""
    t = np.arange(0, 3600.1, 10.0)
    light = (2.0, -3.0)
    start = np.array([0.3, 0.2])
    toward = (np.array(light) - start) / np.linalg.norm(np.array(light) - start)
    centre = start + np.outer(t * 1.24e-3, toward)
    line = np.arange(5) * 0.155
    x, y = centre[:, :1] + line - line.mean(), centre[:, 1:] + 0 * line
    folder = tmp_path / "run-0007"
    folder.mkdir()
    write_published_csv(folder / "out.csv", 7, t, x, y, np.full_like(x, 0.0775), light_m=light)
    (source,) = load_source(folder)
    assert source.lamp_from == "placed from the Distance column"
    assert source.lamp_cm == pytest.approx((200.0, -300.0), abs=0.01)
    result = analyse(source, StatsSettings())
    assert result.cycle_s == PUBLISHED_CYCLE_S
    assert result.average_mm_s == pytest.approx(1.24, abs=1e-4)
    assert result.average_pct == pytest.approx(9.6, abs=0.05)
    # A config file beside it names the light instead.
    (folder / "config.txt").write_text("# run\nlight_x\n2.0\nlight_y\n-3.0\nnCells\n5\n")
    (source,) = load_source(folder)
    assert source.lamp_from == "config.txt"


def test_a_published_csv_round_trips(tmp_path: Path) -> None:
    x = np.array([[0.0, 0.2], [0.1, 0.3]])
    y = np.array([[1.0, 1.0], [1.1, 1.2]])
    write_published_csv(tmp_path / "a.csv", 42, [0.0, 60.0], x, y, np.full_like(x, 0.1))
    with (tmp_path / "a.csv").open("a") as stream:
        stream.write("120.0, 0.1, ")  # a run killed while writing
    run = read_published_csv(tmp_path / "a.csv")
    assert run.seed == 42 and run.particles == 2
    assert run.x_m == pytest.approx(x) and run.y_m == pytest.approx(y)
    assert run.centroid_m == pytest.approx(np.stack([x.mean(1), y.mean(1)], 1))
    assert run.warnings and "incomplete last line" in run.warnings[0]


def test_trilateration_needs_a_path_that_turns_or_says_it_cannot() -> None:
    rng = np.random.default_rng(1)
    points = rng.uniform(-1, 1, (10, 2))
    light = np.array([3.0, 4.0])
    assert trilaterate(points, np.hypot(*(points - light).T)) == pytest.approx(tuple(light))
    straight = np.stack([np.linspace(0, 1, 10), np.zeros(10)], 1)
    assert trilaterate(straight, np.hypot(*(straight - light).T)) is None
    # Heading straight for the light, the mirror images meet: placed.
    ahead = np.array([3.0, 0.0])
    assert trilaterate(straight, np.hypot(*(straight - ahead).T)) == pytest.approx((3.0, 0.0))


def test_sources_the_statistics_cannot_use_say_why(tmp_path: Path) -> None:
    (tmp_path / "notes.csv").write_text("a,b\n1,2\n")
    (tmp_path / "session.jsonl").write_text("{}\n")
    with pytest.raises(SourceError, match=r"neither a TRACK\.csv"):
        load_source(tmp_path / "notes.csv")
    with pytest.raises(SourceError, match=r"holds no TRACK\.csv"):
        load_source(tmp_path)
    with pytest.raises(SourceError, match="no positions in this log: only a simulated radio"):
        load_source(tmp_path / "session.jsonl")
    with pytest.raises(SourceError, match="no such file"):
        load_source(tmp_path / "missing.csv")
    t, x, y, _ = walk(0.0, 0.01, seconds=600)
    no_lamp = CentroidSeries("run", Path("run"), "track", t, x, y, np.ones(len(t), bool), True)
    with pytest.raises(SourceError, match="give --lamp"):
        analyse(no_lamp, StatsSettings())
    short = series(t[:100], x[:100], y[:100], (0.0, 0.0))
    with pytest.raises(SourceError, match="fewer than two 30 s intervals"):
        analyse(short, StatsSettings())


def test_the_default_cycle_is_the_sources_own_else_the_papers_experiments() -> None:
    t, x, y, lamp = walk(0.0, 0.05, seconds=300)
    assert analyse(series(t, x, y, lamp), StatsSettings()).cycle_s == EXPERIMENT_CYCLE_S
    assert analyse(series(t, x, y, lamp), StatsSettings(cycle_s=12.0)).cycle_s == 12.0


@pytest.mark.slow
def test_a_simulated_radios_session_log_is_a_source_with_its_lamp_and_cycle(
    tmp_path: Path,
) -> None:
    # Ten virtual particles (the firmware logic) in a blob 1.5 m from the lamp, method A: START,
    # two minutes, STOP. The log records the world: positions at 2 Hz, commanded radii at 10 Hz.
    with Swarm.open("virtual://10?speed=max&scenario=blob&seed=2", log_dir=tmp_path) as swarm:
        swarm.wait_for(count=10, timeout=15)
        swarm.start("A", cycle_steps=150)
        swarm.sleep(120)
        swarm.stop()
        log = swarm.log_path
    assert log is not None
    (series,) = load_source(log)
    assert series.kind == "log" and series.lamp_cm == (0.0, 0.0)
    # Method A's wave is WAVE_SIZE (5) long: T + t_p = 3 s + 4 x 1.5 s.
    assert series.cycle_s == pytest.approx(9.0, abs=0.05)
    assert series.t_s[-1] - series.t_s[0] == pytest.approx(120, abs=2)  # START to STOP
    result = analyse(series, StatsSettings())
    assert result.steps == 4 and result.average_mm_s > 0  # toward the lamp
    # In a folder, the log is found with whatever else lies there.
    assert [s.name for s in load_source(tmp_path)] == [log.name]
