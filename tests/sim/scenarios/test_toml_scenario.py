"""Our TOML scenario files: the examples read, a scenario written out reads back the same, and
every mistake is one line naming the file, the line and the key."""

from __future__ import annotations

import re
from dataclasses import replace
from pathlib import Path

import pytest

from particlebot.protocol import Method
from particlebot.sim.scenarios.scenario import (
    ControllerKind,
    PlacementKind,
    Scenario,
    ScenarioError,
)
from particlebot.sim.scenarios.toml_file import parse_scenario, read_scenario
from particlebot.sim.scenarios.write import to_toml
from particlebot.sim.world.light import ShadowMode
from particlebot.toml_lines import key_lines
from tests.support.repo import REPO_ROOT

REPO = REPO_ROOT
EXAMPLES = sorted((REPO / "scenarios").glob("*.toml"))


def test_the_repository_has_example_scenarios() -> None:
    assert len(EXAMPLES) >= 3


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.name)
def test_every_example_scenario_reads_and_round_trips(path: Path) -> None:
    scenario = read_scenario(path)

    again = parse_scenario(to_toml(scenario))

    assert again == scenario


def test_the_commented_example_sets_what_it_says() -> None:
    scenario = read_scenario(REPO / "scenarios" / "blob-to-lamp.toml")

    assert scenario.name == "blob-to-lamp"
    assert scenario.swarm.particles == 100
    assert scenario.swarm.placement is PlacementKind.ALGORITHM5
    assert (scenario.lamp.x, scenario.lamp.y, scenario.lamp.height) == (-4.0, 0.0, None)
    assert len(scenario.circles) == 1 and scenario.circles[0].radius == 0.4
    assert scenario.dead.resolve(100) == 10 and scenario.dead.at_s == 600
    assert scenario.controller.kind is ControllerKind.PUBLISHED
    assert scenario.steps == 360_000 and scenario.dump_every == 6000


def test_a_scenario_with_every_part_round_trips(tmp_path: Path) -> None:
    text = """
name = "all"
seed = 9
duration_s = 12.5
shadow = "still"
precision = "float32"
[swarm]
placement = "line"
particles = 4
at = [1.0, -2.0]
spacing = 0.2
direction_deg = 30
[lamp]
x = 3
y = 4
height = 0.5
[[rectangle]]
x = [-3, -2]
y = [-1, 1]
[[circle]]
x = 5
y = 5
radius = 0.3
[[object]]
x = 2
y = 2
radius = 0.3
mass_factor = 2
[dead]
count = 1
at_s = 5
detach = true
[free]
count = 3
x = [-1, 0]
y = [3, 4]
[controller]
kind = "firmware"
[controller.firmware]
method = "B"
wave_size = 4
[controller.firmware.estimation]
count_tolerance = 12
[controller.published]
nx = 3
[physics]
magnet_cutoff = 0.1
mu = 0.3
[output]
dump_interval_s = 2
per_particle = true
csv = "x.csv"
snapshot_interval_s = 5
video = "x.gif"
"""
    scenario = parse_scenario(text, tmp_path / "all.toml")

    assert scenario.shadow is ShadowMode.STILL
    assert scenario.controller.firmware.method is Method.LINEAR
    assert scenario.controller.firmware.estimation.count_tolerance == 12
    assert scenario.controller.published.nx == 3
    assert scenario.physics.mu == 0.3 and scenario.output.video_name == "x.gif"
    assert parse_scenario(to_toml(scenario)) == scenario


def test_key_lines_find_tables_arrays_of_tables_and_keys_after_multiline_values() -> None:
    text = """# comment
name = "x"   # = not a key
[swarm]
at = [
  1.0,
  [2.0],
]
particles = 3
[[circle]]
x = 1
[[circle]]
radius = 2
[controller.firmware]
method = "D"
"""
    lines = key_lines(text)

    assert lines["name"] == 2
    assert lines["swarm"] == 3 and lines["swarm.at"] == 4 and lines["swarm.particles"] == 8
    assert lines["circle[1].x"] == 10 and lines["circle[2].radius"] == 12
    assert lines["controller.firmware.method"] == 14
    assert "swarm.at[2.0]" not in lines and "[2.0]" not in "".join(lines)


BAD = [
    ("[swarm]\npartcles = 10\n", 2, "swarm.partcles: unknown key (did you mean 'particles'?)"),
    ("nmae = 'x'\n", 1, "nmae: unknown key (did you mean 'name'?)"),
    ("[swarm]\nparticles = -3\n", 2, "swarm.particles: must be a whole number >= 1, not -3"),
    ("[swarm]\nparticles = 2.5\n", 2, "swarm.particles: must be a whole number, not 2.5"),
    ("[lamp]\nx = nan\n", 2, "lamp.x: must be a number -10000..10000, not nan"),
    ("[lamp]\ny = inf\n", 2, "lamp.y: must be a number -10000..10000, not inf"),
    ("[lamp]\nx = '1'\n", 2, "lamp.x: must be a number, not '1'"),
    ("duration_s = 0\n", 1, "duration_s: must be a number > 0 and <= 1e+08, not 0"),
    ("[[rectangle]]\nx = [1, 2, 3]\ny = [0, 1]\n", 2, "rectangle[1].x: must be a list of 2"),
    ("[[rectangle]]\nx = [2, 1]\ny = [0, 1]\n", 2, "rectangle[1].x: needs min < max"),
    ("[[rectangle]]\nx = [1, 2]\n", 1, "rectangle[1]: needs y = [min, max]"),
    ("[[circle]]\nradius = 1\n\n[[circle]]\nradius = -1\n", 5, "circle[2].radius: must be a"),
    ("[dead]\ncount = -1\n", 2, "dead.count: must be a whole number >= 0, not -1"),
    ("[dead]\nfraction = 1.5\n", 2, "dead.fraction: must be 0..1, not 1.5"),
    ("[dead]\ncount = 20\n", 2, "dead.count: more dead particles than the swarm's 10"),
    ("shadow = 'dark'\n", 1, "shadow: must be 'ignore', 'last', 'still'"),
    ("[controller]\nkind = 'firmwre'\n", 2, "(did you mean 'firmware'?)"),
    ("[controller.published]\nnx = 0\n", 2, "controller.published.nx: must be a whole"),
    ("[controller.published]\nrise = 2\n", 2, "unknown key (did you mean 'rise_s'?)"),
    ("[controller.firmware]\nmethod = 'E'\n", 2, "controller.firmware.method: must be one of"),
    ("[physics]\ndt = -0.01\n", 2, "physics.dt: must be a number 1e-06..1, not -0.01"),
    ("[physics]\nspring = true\n", 2, "physics.spring: must be a number, not True"),
    ("[output]\ncsv = '../x.csv'\n", 2, "output.csv: must be a file name without a folder"),
    ("[swarm]\nplacement = 'file'\n", 2, "placement 'file' needs `file"),
    ("[swarm]\nplacement = 'file'\nfile = 'nope.csv'\n", 3, "swarm.file: no such file"),
    ("[swarm]\nplacement = 'grid'\n", 2, "swarm.placement: must be one of"),
    ("[[object]]\nx = 1\n", 1, "object[1]: give both x and y"),
    ("name = 'a b'\n", 1, "name: must be letters, digits"),
    ("[swarm\nparticles = 1\n", 1, "not valid TOML"),
]


@pytest.mark.parametrize(("text", "line", "message"), BAD)
def test_a_mistake_is_one_line_with_file_line_and_key(
    tmp_path: Path, text: str, line: int, message: str
) -> None:
    path = tmp_path / "bad.toml"
    path.write_text(text)

    with pytest.raises(ScenarioError) as caught:
        read_scenario(path)

    error = str(caught.value)
    assert "\n" not in error
    assert error.startswith(f"{path}:{line}: "), error
    assert message in error


def test_positions_file_is_relative_to_the_scenario(tmp_path: Path) -> None:
    (tmp_path / "swarm.csv").write_text("x, y\n0, 0\n0.155, 0\n")
    (tmp_path / "s.toml").write_text("[swarm]\nplacement = 'file'\nfile = 'swarm.csv'\n")

    scenario = read_scenario(tmp_path / "s.toml")

    assert scenario.swarm.file == tmp_path / "swarm.csv"


def test_defaults_are_the_published_model(tmp_path: Path) -> None:
    scenario = parse_scenario('name = "run"\n', tmp_path / "defaults.toml")

    assert replace(scenario, source=Scenario().source) == Scenario()
    assert re.fullmatch(r"run", scenario.name)
