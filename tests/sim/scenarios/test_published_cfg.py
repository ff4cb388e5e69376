"""The published simulator's configuration files, read as is: good files give the scenario they
describe, bad ones one line naming the file, the line and the key."""

from __future__ import annotations

from pathlib import Path

import pytest

from particlebot.sim.scenarios.published_cfg import (
    PUBLISHED_START,
    looks_like_published_cfg,
    read_published_cfg,
)
from particlebot.sim.scenarios.scenario import PlacementKind, ScenarioError
from particlebot.sim.world.light import ShadowMode
from tests.support.repo import REPO_ROOT

REPO = REPO_ROOT

GAP = """# Camera height: display only
camera_y
12

# Number of particles
nCells
250

nDead
25

time_to_dead
300

light_x
-4.5

light_y
0.5

max_time
5400

nobstacles
2

x1obs
-1.2 -1.2

x2obs
-1.0 -1.0

y1obs
-8 0.7

y2obs
-0.7 8

light_shadow
1

testing
1

dump_interval
30

seed
77

csv_filename
some/folder/gap_data.csv

video_filename
gap_video.avi
"""


def write(tmp_path: Path, text: str, name: str = "run.cfg") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def test_a_gap_configuration_becomes_its_scenario(tmp_path: Path) -> None:
    scenario = read_published_cfg(write(tmp_path, GAP))

    assert scenario.swarm.particles == 250
    assert scenario.swarm.placement is PlacementKind.ALGORITHM5_PUBLISHED
    assert scenario.swarm.at == PUBLISHED_START
    assert scenario.dead.count == 25 and scenario.dead.at_s == 300
    assert (scenario.lamp.x, scenario.lamp.y) == (-4.5, 0.5)
    assert scenario.duration_s == 5400 and scenario.seed == 77
    assert [(r.x_min, r.x_max, r.y_min, r.y_max) for r in scenario.rects] == [
        (-1.2, -1.0, -8.0, -0.7),
        (-1.2, -1.0, 0.7, 8.0),
    ]
    assert scenario.shadow is ShadowMode.LAST
    assert scenario.output.per_particle and scenario.output.dump_interval_s == 30
    # Output names only, never paths: everything goes into the run folder.
    assert scenario.output.csv_name == "gap_data.csv"
    assert scenario.output.video_name == "gap_video.mp4"
    assert scenario.objects == ()


def test_n_dead_minus_one_makes_the_last_cell_the_object(tmp_path: Path) -> None:
    text = "nCells\n201\nnDead\n-1\nradFactor\n2.5\nmassFactor\n3\nattractionFactor\n0.5\n"

    scenario = read_published_cfg(write(tmp_path, text))

    assert scenario.swarm.particles == 200
    (obj,) = scenario.objects
    assert (obj.x, obj.y) == (None, None)  # in front of the swarm
    assert (obj.radius_factor, obj.mass_factor, obj.friction_factor) == (2.5, 3.0, 1.0)
    assert obj.attraction_factor == 0.5
    assert scenario.dead.resolve(200) == 0


def test_left_out_keys_take_the_published_mains_defaults(tmp_path: Path) -> None:
    scenario = read_published_cfg(write(tmp_path, "# nothing but a seed\nseed\n3\n"))

    assert scenario.swarm.particles == 500 and len(scenario.objects) == 1  # nCells 501, nDead -1
    assert (scenario.lamp.x, scenario.lamp.y) == (-5.0, 0.0)
    assert scenario.duration_s == 6400
    assert scenario.output.dump_interval_s == 60 and not scenario.output.per_particle
    assert scenario.shadow is ShadowMode.IGNORE


def test_model_and_wave_keys_map_to_physics_and_the_published_controller(tmp_path: Path) -> None:
    text = (
        "nCells\n10\nnDead\n0\nspring\n900\nfriction\n0.3\nconstraint\n0.4\n"
        "constrained_contraction\n1\nmin_radius\n0.08\ntimestep\n0.005\n"
        "rise_period\n1.5\nNx\n3\nphase_std\n0.3\nphase_update_interval\n18\n"
        "config\nCONFIG_HEX\n"
    )

    scenario = read_published_cfg(write(tmp_path, text))

    p = scenario.physics
    assert (p.spring, p.mu, p.torque_limit, p.r_min, p.dt) == (900, 0.3, 0.4, 0.08, 0.005)
    assert p.constrain_contraction is True
    wave = scenario.controller.published
    assert (wave.rise_s, wave.nx) == (1.5, 3)
    assert wave.phase_noise == pytest.approx(0.2)  # 0.3 s of 1.5 s rise periods
    assert wave.update_cycles == 3  # 18 s of 6 s cycles
    assert scenario.swarm.placement is PlacementKind.HEX and scenario.swarm.at == (0.0, 0.0)


def test_a_line_is_centred_on_the_origin_as_the_published_line(tmp_path: Path) -> None:
    scenario = read_published_cfg(write(tmp_path, "nCells\n5\nnDead\n0\nconfig\nCONFIG_LINE\n"))

    assert scenario.swarm.placement is PlacementKind.LINE
    assert scenario.swarm.at == pytest.approx((-4 * 0.0775, 0.0))


def test_the_repository_example_reads(tmp_path: Path) -> None:
    scenario = read_published_cfg(REPO / "scenarios" / "published-obstacles.cfg")

    assert scenario.swarm.particles == 400 and len(scenario.circles) == 3


def test_published_files_are_told_from_toml() -> None:
    assert looks_like_published_cfg(GAP)
    assert not looks_like_published_cfg("# x\nname = 'a'\n")
    assert not looks_like_published_cfg("[swarm]\nparticles = 3\n")


BAD = [
    ("nCells\n10\nlight_z\n3\n", 3, "light_z: unknown key (did you mean 'light_"),
    ("ncells\n10\n", 1, "ncells: unknown key (did you mean 'nCells'?)"),
    ("nCells\n10\nmax_time\n", 3, "max_time: a key without a value line"),
    ("nCells 10\n", 1, "'nCells' is not a key on a line of its own"),
    ("nCells\n10\nnCells\n20\n", 3, "nCells: given twice (first on line 1)"),
    ("nCells\nten\n", 1, "nCells: must be a whole number, not 'ten'"),
    ("nCells\n0\n", 1, "nCells: must be >= 1, not 0"),
    ("nCells\n10\nnDead\n-2\n", 3, "nDead: must be >= -1, not -2"),
    ("nCells\n10\nnDead\n11\n", 3, "nDead: 11 dead of 10 cells"),
    ("nCells\n1\nnDead\n-1\n", 1, "nCells: nDead -1 makes the last cell the object"),
    ("nCells\n10\nlight_x\nnan\n", 3, "light_x: must be a finite number, not nan"),
    ("nCells\n10\nmax_time\ninf\n", 3, "max_time: must be a finite number, not inf"),
    ("nCells\n10\nmax_time\n1 2\n", 3, "max_time: one value, not 2"),
    ("nobstacles\n2\nx1obs\n1 2 3\n", 3, "x1obs: nobstacles is 2, so 2 value(s), not 3"),
    ("nobstacles\n1\nx1obs\n1\nx2obs\n2\ny1obs\n0\n", 1, "nobstacles: 1 obstacles but no y2obs"),
    (
        "nobstacles\n1\nx1obs\n2\nx2obs\n1\ny1obs\n0\ny2obs\n1\n",
        3,
        "x1obs: rectangle 1 needs x1obs < x2obs",
    ),
    ("n_cir_obstacles\n1\nx_cir_obs\n0\ny_cir_obs\n0\nr_cir_obs\n0\n", 7, "needs a radius > 0"),
    ("nCells\n10\nlight_shadow\n3\n", 3, "light_shadow: must be 0, 1 or 2, not 3"),
    ("nCells\n10\ntesting\n2\n", 3, "testing: must be 0 or 1, not 2"),
    ("nCells\n10\nconfig\nCONFIG_GRID\n", 3, "config: must be one of CONFIG_RANDOM"),
    ("nCells\n10\nboundaryDamping\n-0.5\n", 3, "boundaryDamping: only -1"),
    ("nCells\n10\nphase_update_interval\n7\n", 3, "must be a whole number of cycles"),
    ("nCells\n10\ncsv_filename\nout.txt\n", 3, "csv_filename: must end in .csv"),
    ("nCells\n10\nmin_radius\n0.2\n", 3, "min_radius: need 0 < r_min <= r_max"),
]


@pytest.mark.parametrize(("text", "line", "message"), BAD)
def test_a_bad_file_is_one_line_with_file_line_and_key(
    tmp_path: Path, text: str, line: int, message: str
) -> None:
    path = write(tmp_path, text)

    with pytest.raises(ScenarioError) as caught:
        read_published_cfg(path)

    error = str(caught.value)
    assert "\n" not in error
    assert error.startswith(f"{path}:{line}: "), error
    assert message in error
