"""The seam on the real simulator: the study frame, placements turned clear of obstacles, resuming
a retried run, every study's world running, and a tiny study end to end on two Dask workers."""

from __future__ import annotations

import io
import json
import math
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from particlebot.commands.study import main
from particlebot.sim.particles.model.published import PublishedSettings
from particlebot.sim.scenarios.build import place_swarm
from particlebot.sim.world.arena import Arena
from particlebot.sim.world.params import PhysicsParams
from particlebot.sim.world.world import PARALLEL_FROM
from particlebot.studies import published as paper
from particlebot.studies import seam
from particlebot.studies.definitions import PLACEMENTS, STUDIES, RawOptions, resolve
from particlebot.studies.runners import SimulatorRunner, execute
from particlebot.studies.spec import Rect, WorldSetup

# A hang guard far above the time on an idle machine, room for a cold numba cache on a loaded one.
pytestmark = pytest.mark.timeout(1800)

# A 10-particle swarm with a lamp 3 m ahead and a wall across its path 0.6 m ahead.
WALLED = WorldSetup(
    particles=10,
    seed=4,
    duration_s=120.0,
    lamp_x=3.0,
    lamp_y=0.5,
    rects=(Rect(0.6, 0.755, -2.0, 2.0),),
    dump_interval_s=30.0,
)


def test_the_studies_numbers_are_the_worlds_and_the_published_controllers() -> None:
    physics, light = PhysicsParams(), PublishedSettings()
    assert (physics.r_min, physics.r_max, physics.dt) == (paper.R_MIN_M, paper.R_MAX_M, paper.DT_S)
    assert (light.nx + 1) * light.rise_s == paper.CYCLE_S


def test_the_study_frame_is_the_simulators_moved_to_the_initial_centroid() -> None:
    framed = seam.frame(WALLED)
    xy = place_swarm(framed.scenario).xy
    cx, cy = framed.offset
    assert (cx, cy) == pytest.approx(tuple(xy.mean(axis=0)))
    assert math.hypot(cx, cy) > 0.01, "Algorithm 5 starts at the origin, not at the centroid"
    lamp = framed.scenario.lamp
    assert (lamp.x - cx, lamp.y - cy) == pytest.approx((3.0, 0.5))
    (wall,) = framed.scenario.rects
    assert (wall.x_min - cx, wall.y_max - cy) == pytest.approx((0.6, 2.0))
    assert framed.turned_deg == 0.0 and framed.positions is None

    shares: list[float] = []
    outcome = seam.simulate(WALLED, progress=shares.append)
    # The run told its progress how far it was, up to the end.
    assert shares and shares == sorted(shares) and shares[-1] == 1.0
    track = outcome.track
    # The published CSV's first row is the initial centroid: the study frame's origin.
    assert (track.centroid_x[0], track.centroid_y[0]) == pytest.approx((0.0, 0.0), abs=2e-6)
    assert track.time_s[-1] == WALLED.duration_s
    assert track.distance_m[0] == pytest.approx(math.hypot(3.0, 0.5), abs=2e-6)
    final = outcome.final_xy
    assert final.shape == (10, 2)
    assert final.mean(axis=0) == pytest.approx(
        (track.centroid_x[-1], track.centroid_y[-1]), abs=2e-6
    )
    # The wall holds: no centre got past its near face less a radius.
    assert final[:, 0].max() < 0.6 - paper.R_MIN_M + 1e-3


def test_every_placement_option_reaches_the_scenario_and_names_its_own_runs() -> None:
    assert set(seam.PLACEMENT_KINDS) == set(PLACEMENTS)
    open_floor = replace(WALLED, rects=())
    for name, kind in seam.PLACEMENT_KINDS.items():
        assert seam.frame(replace(open_floor, placement=name)).scenario.swarm.placement is kind
    study = STUDIES["dead"]
    run_ids = {
        study.specs(resolve(study, RawOptions(sizes="10", seeds="1", placement=name)))[0].run_id
        for name in PLACEMENTS
    }
    assert len(run_ids) == len(PLACEMENTS)


def test_published_numbers_changed_with_set_reach_the_world_and_the_controller() -> None:
    study = STUDIES["dead"]
    options = resolve(
        study,
        RawOptions(
            sizes="10", seeds="1", overrides="static_factor=1, phase_noise=0, update_cycles=2"
        ),
    )
    changed = study.specs(options)[0]
    plain = study.specs(replace(options, overrides=()))[0]
    assert changed.run_id != plain.run_id
    scenario = seam.frame(changed.setup).scenario
    assert scenario.physics == replace(PhysicsParams(), static_factor=1.0)
    assert scenario.controller.published == PublishedSettings(phase_noise=0.0, update_cycles=2)
    assert seam.frame(plain.setup).scenario.physics == PhysicsParams()
    bool_set = replace(WALLED, overrides=(("constrain_contraction", 1.0),))
    assert seam.frame(bool_set).scenario.physics.constrain_contraction is True


def test_a_placement_that_cuts_into_an_obstacle_is_turned_until_it_clears() -> None:
    relative = place_swarm(seam.frame(WALLED).scenario).xy
    relative = relative - relative.mean(axis=0)
    front = float(relative[:, 0].max()) + paper.R_MIN_M
    # A thin post whose face is 2 cm inside the blob's leading edge, level with its front disc.
    tip = relative[np.argmax(relative[:, 0])]
    post = Rect(front - 0.02, front + 0.2, tip[1] - 0.01, tip[1] + 0.01)
    setup = replace(WALLED, rects=(post,), duration_s=30.0)
    framed = seam.frame(setup)
    assert framed.turned_deg != 0.0 and abs(framed.turned_deg) % seam.TURN_STEP_DEG == 0
    assert framed.positions is not None
    x, y = framed.positions.T
    radii = np.full(len(x), paper.R_MIN_M)
    assert not Arena(rects=framed.scenario.rects).overlapping(x, y, radii).any()
    # Turned about the centroid: the same blob, the same centroid.
    assert framed.positions.mean(axis=0) == pytest.approx(framed.offset)
    outcome = seam.simulate(setup)
    assert outcome.summary["turned_deg"] == framed.turned_deg
    assert (outcome.track.centroid_x[0], outcome.track.centroid_y[0]) == pytest.approx(
        (0.0, 0.0), abs=2e-6
    )


def test_a_setup_no_turn_can_clear_is_one_line_naming_the_swarm() -> None:
    through_the_middle = replace(WALLED, rects=(Rect(-0.05, 0.05, -3.0, 3.0),))
    with pytest.raises(seam.SetupError, match=r"^the swarm of 10 particles \(seed 4\) cuts into"):
        seam.frame(through_the_middle)
    with pytest.raises(seam.SetupError, match="free particles need a free_region"):
        seam.frame(replace(WALLED, free_particles=3))
    with pytest.raises(seam.SetupError, match="no 'spiral'"):
        seam.frame(replace(WALLED, placement="spiral"))


@pytest.mark.slow
def test_a_retried_run_resumes_from_its_folder_and_ends_as_an_uninterrupted_one(
    tmp_path: Path,
) -> None:
    setup = replace(WALLED, duration_s=1200.0, rects=())
    folder = tmp_path / "run"
    # A first attempt that stopped (its worker died) after some minutes, leaving snapshots.
    run = seam.start_run(seam.frame(setup), folder, pictures=False)
    run.advance(should_stop=lambda: run.world.t >= 700.0)
    stopped_at = run.world.t
    assert 700.0 <= stopped_at < 1200.0
    resumed = seam.simulate(setup, folder)
    assert resumed.summary["resumed_at_s"] == pytest.approx(stopped_at)
    fresh = seam.simulate(setup)
    assert fresh.summary["resumed_at_s"] == 0.0
    np.testing.assert_array_equal(resumed.final_xy, fresh.final_xy)
    np.testing.assert_array_equal(resumed.track.distance_m, fresh.track.distance_m)
    # A kept folder has the simulator's pictures; it resumes, never restarts, when asked again.
    assert (folder / "swarm.png").is_file() and (folder / "track.png").is_file()
    again = seam.simulate(setup, folder)
    assert again.summary["steps_now"] == 0


@pytest.mark.parametrize("name", list(STUDIES))
def test_every_study_runs_on_the_simulator_at_a_tiny_size(name: str) -> None:
    study = STUDIES[name]
    sweep = {"gap": "0.8", "carry": "0.4", "annex": "1", "noise": "1", "dead": "0.3"}
    skip = "2min" if study.uses_skip else None
    options = resolve(
        study,
        RawOptions(sizes="10", values=sweep.get(name), seeds="1", duration="15min", skip=skip),
    )
    (spec,) = study.specs(options)
    record = execute(SimulatorRunner(), spec)
    assert record.runner == "simulator"
    # A run measures every metric but those the report derives from another one.
    assert set(record.metrics) == {m.key for m in study.metrics if m.derived_from is None}
    assert all(math.isfinite(value) for value in record.metrics.values())
    assert record.summary["steps"] == 15 * 60 / paper.DT_S
    if name == "gap":
        assert 0.0 <= record.metrics["success"] <= 1.0
    if name == "annex":
        assert record.metrics["robot_size_ratio"] > 0


@pytest.mark.dask
def test_a_tiny_study_runs_end_to_end_on_the_simulator_and_two_workers(tmp_path: Path) -> None:
    results = tmp_path / "results"
    argv = ["dead", "--sizes", "10", "--fractions", "0,0.8", "--seeds", "2", "--duration", "10min"]
    argv += ["--skip", "2min", "--results", str(results), "--workers", "2"]
    progress = io.StringIO()
    assert main(argv, stream=progress) == 0
    records = [json.loads(path.read_text()) for path in (results / "runs").glob("*.json")]
    assert len(records) == 4 and {r["runner"] for r in records} == {"simulator"}
    assert all(r["worker"].startswith("tcp://") for r in records)
    speeds = {(r["cell"]["dead_fraction"], r["seed"]): r["metrics"]["speed_mm_s"] for r in records}
    # Eight of ten particles dead stop the swarm: slower than the whole one, seed for seed.
    assert all(speeds[0.8, seed] < speeds[0.0, seed] for seed in (1, 2))
    assert "4/4 runs" in progress.getvalue()
    report = (results / "report.md").read_text()
    assert "4 of 4 runs finished" in report and "stand-in" not in report
    # Asked again, the study finds every run done and runs nothing.
    before = {p.name: p.stat().st_mtime_ns for p in (results / "runs").iterdir()}
    assert main(argv, stream=io.StringIO()) == 0
    assert {p.name: p.stat().st_mtime_ns for p in (results / "runs").iterdir()} == before


@pytest.mark.dask
def test_a_study_started_from_the_command_line_runs_each_run_on_one_thread(
    tmp_path: Path,
) -> None:
    # A spawned Dask worker imports the command line's main module, and with it numba, before
    # the cluster's environment applies: numba then starts a thread per core in every worker.
    # Only a real command line shows it (pytest's main module does not import numba), and only
    # a swarm that steps in parallel (World's PARALLEL_FROM particles and more).
    results = tmp_path / "results"
    argv = ["study", "dead", "--sizes", str(PARALLEL_FROM), "--fractions", "0", "--seeds", "1"]
    argv += ["--duration", "20s", "--skip", "10s", "--results", str(results), "--workers", "1"]
    done = subprocess.run(
        [sys.executable, "-m", "particlebot.cli", *argv],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stderr
    (record,) = [json.loads(path.read_text()) for path in (results / "runs").glob("*.json")]
    assert record["summary"]["threads"] == 1


@pytest.mark.parametrize(
    ("duration_s", "interval_s"), [(7200.0, 60.0), (20.0, 20.0), (90.0, 45.0), (54000.0, 60.0)]
)
def test_the_track_ends_at_the_end_of_any_run(duration_s: float, interval_s: float) -> None:
    setup = replace(WALLED, duration_s=duration_s, dump_interval_s=60.0)
    assert seam.track_interval_s(setup) == interval_s


def test_a_run_shorter_than_the_track_interval_is_still_measured() -> None:
    outcome = seam.simulate(replace(WALLED, duration_s=20.0))
    assert list(outcome.track.time_s) == [0.0, 20.0]
