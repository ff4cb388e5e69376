"""`simulate --gsd --xyz`: the whole trajectory in files other tools open, read back with the gsd
package's own reader and agreeing with the run's snapshots and CSV; `particlebot.read_run`."""

from __future__ import annotations

from pathlib import Path

import gsd.hoomd
import numpy as np
import pandas as pd
import pytest

import particlebot
from particlebot.cli import main

QUICK = ["simulate", "--particles", "8", "--seed", "2", "--lamp", "-2,0.5,0.3"]


def published_csv(folder: Path) -> pd.DataFrame:
    """The README's recipe for the published CSV."""
    return pd.read_csv(folder / "run.csv", skiprows=1, skipinitialspace=True, index_col=False)


@pytest.fixture(scope="module")
def run_folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("trajectory") / "run"
    argv = [*QUICK, "--duration", "2", "--dump-interval", "0.25", "--gsd", "--xyz"]
    assert main([*argv, "-o", str(folder)]) == 0
    # Resumed to a later end, the files go on where they stopped.
    assert main(["simulate", "--resume", str(folder), "--duration", "4"]) == 0
    return folder


def test_the_gsd_file_holds_a_frame_per_csv_row(run_folder: Path) -> None:
    csv = published_csv(run_folder)
    assert len(csv) == 17  # 0, 0.25, ..., 4 s
    assert list(csv.columns) == ["Time", "Centroid X", "Centroid Y", "Distance"]
    with gsd.hoomd.open(str(run_folder / "trajectory.gsd"), "r") as trajectory:
        assert len(trajectory) == len(csv)
        steps = [int(frame.configuration.step) for frame in trajectory]
        assert steps == sorted(set(steps))
        for frame, row in zip(trajectory, csv.itertuples(index=False), strict=True):
            assert frame.configuration.dimensions == 2
            assert frame.particles.types == ["particle", "dead", "object", "obstacle"]
            assert float(frame.log["particlebot/time_s"][0]) == pytest.approx(row[0], abs=1e-6)
            # The CSV's centroid is the mean of every body; the GSD's positions are float32.
            bodies = frame.particles.typeid != 3
            mean = frame.particles.position[bodies, :2].astype(np.float64).mean(axis=0)
            assert mean == pytest.approx([row[1], row[2]], abs=1e-5)
            assert frame.log["particlebot/centroid"] == pytest.approx([row[1], row[2]], abs=1e-6)


def test_the_gsd_frames_agree_with_the_snapshots(run_folder: Path) -> None:
    snapshots = sorted((run_folder / "snapshots").glob("step-*.npz"))
    assert len(snapshots) >= 2
    with gsd.hoomd.open(str(run_folder / "trajectory.gsd"), "r") as trajectory:
        by_step = {int(frame.configuration.step): frame for frame in trajectory}
        for path in snapshots:
            frame = by_step[int(path.stem.removeprefix("step-"))]
            with np.load(path, allow_pickle=False) as snap:
                n = len(snap["state_x"])
                xy = frame.particles.position[:n, :2].astype(np.float64)
                assert xy[:, 0] == pytest.approx(snap["state_x"], rel=1e-6, abs=1e-6)
                assert xy[:, 1] == pytest.approx(snap["state_y"], rel=1e-6, abs=1e-6)
                velocity = frame.particles.velocity[:n, :2].astype(np.float64)
                assert velocity[:, 0] == pytest.approx(snap["state_vx"], rel=1e-5, abs=1e-7)
                radius = frame.particles.diameter[:n].astype(np.float64) / 2
                assert radius == pytest.approx(snap["state_radius"], rel=1e-6)
                assert list(frame.particles.typeid[:n]) == [
                    0 if alive else 1 for alive in snap["state_alive"]
                ]
                phase = frame.log["particles/phase"][:n].astype(np.float64)
                assert phase == pytest.approx(snap["state_phase"], rel=1e-6, nan_ok=True)


def test_the_xyz_file_holds_the_same_frames(run_folder: Path) -> None:
    lines = (run_folder / "trajectory.xyz").read_text(encoding="utf-8").splitlines()
    with gsd.hoomd.open(str(run_folder / "trajectory.gsd"), "r") as trajectory:
        index = 0
        for frame in trajectory:
            count = int(lines[index])
            assert count == frame.particles.N
            assert f"Step={frame.configuration.step}" in lines[index + 1]
            assert "Properties=species:S:1:pos:R:3:velo:R:3" in lines[index + 1]
            rows = [line.split() for line in lines[index + 2 : index + 2 + count]]
            xy = np.array([[float(row[1]), float(row[2])] for row in rows])
            assert xy == pytest.approx(frame.particles.position[:, :2], rel=1e-6, abs=1e-6)
            index += 2 + count
        assert index == len(lines)


def test_read_run_gives_dataframes(run_folder: Path) -> None:
    tables = particlebot.read_run(run_folder)
    csv = published_csv(run_folder)
    assert tables.source == "trajectory.gsd"
    assert list(tables.track.columns) == ["t_s", "centroid_x_m", "centroid_y_m", "distance_m"]
    np.testing.assert_array_equal(tables.track.to_numpy(), csv.to_numpy())
    frames = tables.frames
    assert len(frames) == 17 * 8 and set(frames["kind"]) == {"particle"}
    last = frames[frames["frame"] == 16]
    assert last["t_s"].iloc[0] == pytest.approx(4.0)
    assert last["x_m"].mean() == pytest.approx(csv["Centroid X"].iloc[-1], abs=1e-5)


def test_read_run_without_a_trajectory_reads_the_snapshots(tmp_path: Path) -> None:
    folder = tmp_path / "run"
    assert main([*QUICK, "--duration", "1", "-o", str(folder)]) == 0
    tables = particlebot.read_run(folder)
    assert tables.source == "snapshots"
    assert sorted(set(tables.frames["t_s"])) == pytest.approx([0.0, 1.0])
    assert tables.frames["alive"].all() and len(tables.frames) == 2 * 8
