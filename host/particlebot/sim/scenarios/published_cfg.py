"""The published simulator's configuration file, read as is into a Scenario.

The format (shared notes, simulation parameters): `#` lines are comments, blank lines are
skipped, the rest alternate between a key and its value(s) separated by spaces. A key the file
leaves out takes the published main's default (nCells 501, nDead -1 with an object of radFactor
2, light at (-5, 0), 6400 s, ...), as the published simulator would run it; a missing seed is
drawn at random (the published main seeds from the clock) and written into the run's outputs.

Where the published simulator is lax, this reader says what is wrong instead of guessing: keys
must match exactly (it compares only a prefix), a list must have as many values as its count, a
key may appear once, and numbers must be finite.
"""

from __future__ import annotations

import math
import re
import secrets
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from particlebot.sim.particles.model.published import PublishedSettings
from particlebot.sim.scenarios.fields import suggestion
from particlebot.sim.scenarios.placement import PUBLISHED_FIRST_DISC_M
from particlebot.sim.scenarios.scenario import (
    ControllerSpec,
    DeadSpec,
    LampSpec,
    ObjectSpec,
    OutputSpec,
    PlacementKind,
    Scenario,
    ScenarioError,
    SourceMap,
    SwarmSpec,
)
from particlebot.sim.world.arena import Circle, Rect
from particlebot.sim.world.light import ShadowMode
from particlebot.sim.world.params import PhysicsParams

PUBLISHED_START = PUBLISHED_FIRST_DISC_M
"""The published random placement puts its first particle here (m), its lamp by default at
(-5, 0)."""

# The published main's values for keys a file leaves out.
DEFAULTS: dict[str, Any] = {
    "nCells": 501,
    "nDead": -1,
    "radFactor": 2.0,
    "massFactor": 1.0,
    "frictionFactor": 1.0,
    "attractionFactor": 0.0,
    "time_to_dead": 0.0,
    "max_time": 6400.0,
    "light_x": -5.0,
    "light_y": 0.0,
    "light_shadow": 0,
    "dump_interval": 60.0,
    "testing": 0,
    "csv_filename": "particle_bot_output_data.csv",
    "video_filename": "particle_bot_output_video.avi",
    "config": "CONFIG_RANDOM",
}

# Key -> (kind, minimum). Kinds: int, float, list (one float per obstacle), name, flag (0/1).
_KEYS: dict[str, tuple[str, float | None]] = {
    "nCells": ("int", 1),
    "nDead": ("int", -1),
    "radFactor": ("float", 0),
    "massFactor": ("float", 0),
    "frictionFactor": ("float", 0),
    "attractionFactor": ("float", 0),
    "time_to_dead": ("float", 0),
    "max_time": ("float", 0),
    "seed": ("int", 0),
    "light_x": ("float", None),
    "light_y": ("float", None),
    "light_shadow": ("int", 0),
    "nobstacles": ("int", 0),
    "x1obs": ("list", None),
    "x2obs": ("list", None),
    "y1obs": ("list", None),
    "y2obs": ("list", None),
    "n_cir_obstacles": ("int", 0),
    "x_cir_obs": ("list", None),
    "y_cir_obs": ("list", None),
    "r_cir_obs": ("list", None),
    "dump_interval": ("float", 0),
    "testing": ("flag", 0),
    "csv_filename": ("name", None),
    "video_filename": ("name", None),
    "config": ("name", None),
    # The published model's numbers (PhysicsParams).
    "timestep": ("float", 0),
    "min_radius": ("float", 0),
    "max_radius": ("float", 0),
    "friction": ("float", 0),
    "spring": ("float", 0),
    "damping": ("float", 0),
    "shear": ("float", 0),
    "constraint": ("float", 0),
    "constrained_contraction": ("flag", 0),
    "constraint_contraction": ("float", 0),
    "attraction": ("float", 0),
    "gravity": ("float", 0),
    "boundaryDamping": ("float", None),
    # The light wave (PublishedSettings).
    "rise_period": ("float", 0),
    "phase_std": ("float", 0),
    "phase_update_interval": ("float", 0),
    "Nx": ("int", 1),
    # The published display: checked, then ignored (a headless run has no window).
    "camera_x": ("float", None),
    "camera_y": ("float", None),
    "light_radius": ("float", 0),
    "display_shadow": ("flag", 0),
    "DISPLAY_INTERVAL": ("int", 1),
    "VIDEO_INTERVAL": ("int", 1),
    "centroid_int": ("float", 0),
    "centroid_radius": ("float", 0),
    "centroid_steps": ("int", 0),
    "sort_interval": ("float", 0),
}

_PHYSICS = {
    "timestep": "dt",
    "min_radius": "r_min",
    "max_radius": "r_max",
    "friction": "mu",
    "spring": "spring",
    "damping": "damping",
    "shear": "shear",
    "constraint": "torque_limit",
    "constrained_contraction": "constrain_contraction",
    "constraint_contraction": "contraction_coefficient",
    "attraction": "attraction",
    "gravity": "gravity",
}

_PLACEMENTS = {
    "CONFIG_RANDOM": PlacementKind.ALGORITHM5_PUBLISHED,
    "CONFIG_HEX": PlacementKind.HEX,
    "CONFIG_LINE": PlacementKind.LINE,
}

# Keys whose count key sets their length.
_COUNTED = {
    "x1obs": "nobstacles",
    "x2obs": "nobstacles",
    "y1obs": "nobstacles",
    "y2obs": "nobstacles",
    "x_cir_obs": "n_cir_obstacles",
    "y_cir_obs": "n_cir_obstacles",
    "r_cir_obs": "n_cir_obstacles",
}


@dataclass(frozen=True)
class _Entry:
    key: str
    values: list[str]
    line: int


def looks_like_published_cfg(text: str) -> bool:
    """True when the first meaningful line is a bare key of the published format (TOML's
    first line would be `key = value` or a [table])."""
    for line in text.splitlines():
        stripped = line.strip()
        if not stripped or stripped.startswith("#"):
            continue
        return "=" not in stripped and not stripped.startswith("[") and " " not in stripped
    return False


def read_published_cfg(path: Path) -> Scenario:
    """A published configuration file as a Scenario; ScenarioError (one line) on any mistake."""
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise ScenarioError(f"cannot read {path}: {exc}") from None
    return parse_published_cfg(text, path)


def parse_published_cfg(text: str, path: Path) -> Scenario:
    entries = _entries(text, path)
    values = {e.key: _value(e, path) for e in entries}
    lines = {e.key: e.line for e in entries}
    for key, value in values.items():
        count_key = _COUNTED.get(key)
        if count_key is None:
            continue
        expected = int(values.get(count_key, 0))
        assert isinstance(value, list)
        if len(value) != expected:
            raise ScenarioError(
                f"{path}:{lines[key]}: {key}: {count_key} is {expected}, so {expected} "
                f"value(s), not {len(value)}"
            )
    for count_key, keys in (
        ("nobstacles", ("x1obs", "x2obs", "y1obs", "y2obs")),
        ("n_cir_obstacles", ("x_cir_obs", "y_cir_obs", "r_cir_obs")),
    ):
        if int(values.get(count_key, 0)) > 0:
            for key in keys:
                if key not in values:
                    raise ScenarioError(
                        f"{path}:{lines[count_key]}: {count_key}: {values[count_key]} obstacles "
                        f"but no {key} line"
                    )
    return _scenario(values, lines, path)


def _entries(text: str, path: Path) -> list[_Entry]:
    entries: list[_Entry] = []
    seen: dict[str, int] = {}
    pending: tuple[str, int] | None = None
    for number, raw in enumerate(text.splitlines(), start=1):
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        if pending is None:
            if " " in line or "\t" in line or "=" in line:
                raise ScenarioError(
                    f"{path}:{number}: {line.split()[0]!r} is not a key on a line of its own "
                    "(the format alternates a key line and a value line)"
                )
            if line not in _KEYS:
                raise ScenarioError(
                    f"{path}:{number}: {line}: unknown key{suggestion(line, _KEYS)}"
                )
            if line in seen:
                raise ScenarioError(
                    f"{path}:{number}: {line}: given twice (first on line {seen[line]})"
                )
            seen[line] = number
            pending = (line, number)
        else:
            key, key_line = pending
            entries.append(_Entry(key, line.split(), key_line))
            pending = None
    if pending is not None:
        raise ScenarioError(f"{path}:{pending[1]}: {pending[0]}: a key without a value line")
    return entries


def _value(entry: _Entry, path: Path) -> Any:
    kind, minimum = _KEYS[entry.key]
    where = f"{path}:{entry.line}: {entry.key}"
    if kind == "name":
        if len(entry.values) != 1:
            raise ScenarioError(f"{where}: one name without spaces, not {' '.join(entry.values)}")
        return entry.values[0]
    if kind == "list":
        return [_number(v, where, minimum) for v in entry.values]
    if len(entry.values) != 1:
        raise ScenarioError(f"{where}: one value, not {len(entry.values)}")
    text = entry.values[0]
    if kind == "float":
        return _number(text, where, minimum)
    try:
        value = int(text)
    except ValueError:
        raise ScenarioError(f"{where}: must be a whole number, not {text!r}") from None
    if minimum is not None and value < minimum:
        raise ScenarioError(f"{where}: must be >= {minimum:g}, not {value}")
    if kind == "flag" and value not in (0, 1):
        raise ScenarioError(f"{where}: must be 0 or 1, not {value}")
    return value


def _number(text: str, where: str, minimum: float | None) -> float:
    try:
        value = float(text)
    except ValueError:
        raise ScenarioError(f"{where}: must be a number, not {text!r}") from None
    if not math.isfinite(value):
        raise ScenarioError(f"{where}: must be a finite number, not {text}")
    if minimum is not None and value < minimum:
        raise ScenarioError(f"{where}: must be >= {minimum:g}, not {text}")
    return value


def _scenario(values: dict[str, Any], lines: dict[str, int], path: Path) -> Scenario:
    def get(key: str) -> Any:
        return values.get(key, DEFAULTS.get(key))

    def fail(key: str, message: str) -> ScenarioError:
        line = f":{lines[key]}" if key in lines else ""
        return ScenarioError(f"{path}{line}: {key}: {message}")

    physics = _physics(values, fail)
    if get("boundaryDamping") not in (None, -1.0):
        raise fail("boundaryDamping", "only -1 (reflective walls) is supported")
    n_cells, n_dead = int(get("nCells")), int(get("nDead"))
    objects: tuple[ObjectSpec, ...] = ()
    if n_dead == -1:
        # The last of nCells is the passive object.
        if n_cells < 2:
            raise fail("nCells", "nDead -1 makes the last cell the object: needs nCells >= 2")
        if get("radFactor") <= 0 or get("massFactor") <= 0:
            raise fail("radFactor" if get("radFactor") <= 0 else "massFactor", "must be > 0")
        objects = (
            ObjectSpec(
                radius_factor=float(get("radFactor")),
                mass_factor=float(get("massFactor")),
                friction_factor=float(get("frictionFactor")),
                attraction_factor=float(get("attractionFactor")),
            ),
        )
        particles, dead = n_cells - 1, 0
    else:
        particles, dead = n_cells, n_dead
        if dead > particles:
            raise fail("nDead", f"{dead} dead of {particles} cells")
    if get("max_time") <= 0:
        raise fail("max_time", "must be > 0")
    if get("dump_interval") <= 0:
        raise fail("dump_interval", "must be > 0")
    if int(get("light_shadow")) not in (0, 1, 2):
        raise fail("light_shadow", f"must be 0, 1 or 2, not {get('light_shadow')}")
    config = str(get("config"))
    if config not in _PLACEMENTS:
        raise fail("config", f"must be one of {', '.join(_PLACEMENTS)}, not {config!r}")
    placement = _PLACEMENTS[config]
    # Where the published placements put their first particle.
    if placement is PlacementKind.ALGORITHM5_PUBLISHED:
        at = PUBLISHED_START
    elif placement is PlacementKind.LINE:
        at = ((1 - particles) * physics.r_min, 0.0)  # a line centred on the origin
    else:
        at = (0.0, 0.0)
    csv_name = Path(str(get("csv_filename"))).name
    if not csv_name.lower().endswith(".csv"):
        raise fail("csv_filename", f"must end in .csv: {csv_name!r}")
    video_stem = Path(str(get("video_filename"))).stem or "run"
    rects, circles = _obstacles(values, lines, path)
    names = _names(lines, len(rects), len(circles))
    return Scenario(
        name=re.sub(r"[^A-Za-z0-9_.\-]", "-", Path(path).stem).lstrip(".-_") or "run",
        swarm=SwarmSpec(particles=particles, placement=placement, at=at),
        lamp=LampSpec(float(get("light_x")), float(get("light_y"))),
        rects=rects,
        circles=circles,
        objects=objects,
        dead=DeadSpec(count=dead, at_s=float(get("time_to_dead"))),
        controller=ControllerSpec(published=_published(values, fail)),
        physics=physics,
        shadow=ShadowMode(int(get("light_shadow"))),
        duration_s=float(get("max_time")),
        seed=int(values["seed"]) if "seed" in values else secrets.randbits(31),
        output=OutputSpec(
            dump_interval_s=float(get("dump_interval")),
            per_particle=bool(get("testing")),
            csv_name=csv_name,
            video_name=f"{video_stem}.mp4",
        ),
        source=SourceMap(path, tuple(sorted(names[0].items())), tuple(sorted(names[1].items()))),
    )


def _physics(values: dict[str, Any], fail: Any) -> PhysicsParams:
    overrides: dict[str, Any] = {}
    for key, field_name in _PHYSICS.items():
        if key in values:
            value = values[key]
            overrides[field_name] = bool(value) if key == "constrained_contraction" else value
    try:
        return PhysicsParams(**overrides)
    except ValueError as exc:
        message = str(exc)
        keys = [k for k, name in _PHYSICS.items() if name in message and k in values]
        raise fail(keys[0] if keys else "timestep", message) from None


def _published(values: dict[str, Any], fail: Any) -> PublishedSettings:
    base = PublishedSettings()
    rise = float(values.get("rise_period", base.rise_s))
    nx = int(values.get("Nx", base.nx))
    if rise <= 0:
        raise fail("rise_period", "must be > 0")
    # The published noise and update interval are in seconds; ours in rise periods and cycles.
    noise = float(values.get("phase_std", base.phase_noise * rise)) / rise
    cycle = (nx + 1) * rise
    interval = float(values.get("phase_update_interval", base.update_cycles * cycle))
    cycles = round(interval / cycle)
    if cycles < 1 or abs(cycles * cycle - interval) > 1e-9 * cycle:
        raise fail(
            "phase_update_interval",
            f"must be a whole number of cycles ((Nx + 1) x rise_period = {cycle:g} s), "
            f"not {interval:g}",
        )
    try:
        return PublishedSettings(rise_s=rise, nx=nx, update_cycles=cycles, phase_noise=noise)
    except ValueError as exc:
        key = {"rise_s": "rise_period", "nx": "Nx", "phase_noise": "phase_std"}
        name = str(exc).split(" ", 1)[0]
        raise fail(key.get(name, "phase_update_interval"), str(exc)) from None


def _obstacles(
    values: dict[str, Any], lines: dict[str, int], path: Path
) -> tuple[tuple[Rect, ...], tuple[Circle, ...]]:
    rects = []
    for i in range(int(values.get("nobstacles", 0))):
        x1, x2 = values["x1obs"][i], values["x2obs"][i]
        y1, y2 = values["y1obs"][i], values["y2obs"][i]
        if not (x1 < x2 and y1 < y2):
            key = "x1obs" if not x1 < x2 else "y1obs"
            raise ScenarioError(
                f"{path}:{lines[key]}: {key}: rectangle {i + 1} needs x1obs < x2obs and "
                f"y1obs < y2obs, not x {x1:g}..{x2:g}, y {y1:g}..{y2:g}"
            )
        rects.append(Rect(x1, x2, y1, y2))
    circles = []
    for i in range(int(values.get("n_cir_obstacles", 0))):
        radius = values["r_cir_obs"][i]
        if radius <= 0:
            raise ScenarioError(
                f"{path}:{lines['r_cir_obs']}: r_cir_obs: circle {i + 1} needs a radius > 0"
            )
        circles.append(Circle(values["x_cir_obs"][i], values["y_cir_obs"][i], radius))
    return tuple(rects), tuple(circles)


def _names(
    lines: dict[str, int], rects: int, circles: int
) -> tuple[dict[str, int], dict[str, str]]:
    """The scenario's keys at the published keys' lines, and how to call them in a message."""
    at: dict[str, int] = {}
    shown: dict[str, str] = {}

    def alias(ours: str, theirs: str, label: str | None = None) -> None:
        if theirs in lines:
            at[ours] = lines[theirs]
            shown[ours] = label if label is not None else theirs

    alias("swarm", "nCells")
    alias("swarm.particles", "nCells")
    alias("dead", "nDead")
    alias("dead.count", "nDead")
    alias("object[1]", "nDead", "the object (nDead -1)")
    alias("lamp", "light_x", "light_x, light_y")
    alias("duration_s", "max_time")
    alias("seed", "seed")
    for i in range(1, rects + 1):
        alias(f"rectangle[{i}]", "x1obs", f"rectangle {i} (x1obs x2obs y1obs y2obs)")
    for i in range(1, circles + 1):
        alias(f"circle[{i}]", "x_cir_obs", f"circle {i} (x_cir_obs y_cir_obs r_cir_obs)")
    for key, field_name in _PHYSICS.items():
        alias(f"physics.{field_name}", key)
    return at, shown
