"""A Scenario written back out: as our TOML (the run folder's scenario.toml, which reads back to
the same Scenario) and as the published configuration format, as far as that format goes."""

from __future__ import annotations

import math
from dataclasses import fields
from enum import Enum
from typing import Any

import tomlkit

from particlebot.sim.particles.model.firmware import FirmwareSettings
from particlebot.sim.particles.model.published import PublishedSettings
from particlebot.sim.scenarios.scenario import (
    ObjectSpec,
    PlacementKind,
    Scenario,
    physics_overrides,
)
from particlebot.sim.world.light import ShadowMode

_SHADOW_NAMES = {ShadowMode.IGNORE: "ignore", ShadowMode.LAST: "last", ShadowMode.STILL: "still"}


def to_toml(scenario: Scenario, placement_file: str | None = None) -> str:
    """Our TOML for a scenario; `placement_file` replaces the positions file's path (a run folder
    keeps its own copy)."""
    s = scenario
    out = [
        "# The scenario as run: `particlebot simulate` reads this file (and --resume uses it).",
        f"name = {_value(s.name)}",
        f"seed = {s.seed}",
        f"duration_s = {_value(s.duration_s)}",
        f"shadow = {_value(_SHADOW_NAMES[s.shadow])}",
        f"precision = {_value(s.precision)}",
        "",
        "[swarm]",
    ]
    swarm = s.swarm
    if swarm.placement is not PlacementKind.FILE:
        out.append(f"particles = {swarm.particles}")
    out.append(f"placement = {_value(swarm.placement.value)}")
    out.append(f"at = {_value(list(swarm.at))}")
    if swarm.spacing is not None:
        out.append(f"spacing = {_value(swarm.spacing)}")
    if swarm.placement is PlacementKind.LINE:
        out.append(f"direction_deg = {_value(swarm.direction_deg)}")
    if swarm.placement is PlacementKind.FILE:
        name = placement_file if placement_file is not None else str(swarm.file)
        out.append(f"file = {_value(name)}")
    out += ["", "[lamp]", f"x = {_value(s.lamp.x)}", f"y = {_value(s.lamp.y)}"]
    if s.lamp.height is not None:
        out.append(f"height = {_value(s.lamp.height)}")
    for rect in s.rects:
        out += [
            "",
            "[[rectangle]]",
            f"x = {_value([rect.x_min, rect.x_max])}",
            f"y = {_value([rect.y_min, rect.y_max])}",
        ]
    for circle in s.circles:
        out += [
            "",
            "[[circle]]",
            f"x = {_value(circle.x)}",
            f"y = {_value(circle.y)}",
            f"radius = {_value(circle.radius)}",
        ]
    for obj in s.objects:
        out += ["", "[[object]]", *_object_lines(obj)]
    dead = s.dead
    out += ["", "[dead]"]
    out.append(
        f"fraction = {_value(dead.fraction)}"
        if dead.fraction is not None
        else f"count = {dead.count}"
    )
    out += [f"at_s = {_value(dead.at_s)}", f"detach = {_value(dead.detach)}"]
    if s.free.count > 0 and s.free.region is not None:
        region = s.free.region
        out += [
            "",
            "[free]",
            f"count = {s.free.count}",
            f"x = {_value([region.x_min, region.x_max])}",
            f"y = {_value([region.y_min, region.y_max])}",
        ]
    out += ["", "[controller]", f"kind = {_value(s.controller.kind.value)}"]
    out += _settings_lines("controller.published", s.controller.published, PublishedSettings())
    out += _settings_lines("controller.firmware", s.controller.firmware, FirmwareSettings())
    overrides = physics_overrides(s.physics)
    if overrides:
        out += ["", "[physics]"]
        out += [f"{name} = {_value(value)}" for name, value in overrides.items()]
    o = s.output
    out += [
        "",
        "[output]",
        f"dump_interval_s = {_value(o.dump_interval_s)}",
        f"per_particle = {_value(o.per_particle)}",
        f"csv = {_value(o.csv_name)}",
        f"snapshot_interval_s = {_value(o.snapshot_interval_s)}",
        f"video = {_value(o.video_name)}",
        f"video_frames = {o.video_frames}",
    ]
    return "\n".join(out) + "\n"


def _object_lines(obj: ObjectSpec) -> list[str]:
    lines = []
    if obj.x is not None and obj.y is not None:
        lines += [f"x = {_value(obj.x)}", f"y = {_value(obj.y)}"]
    if obj.radius is not None:
        lines.append(f"radius = {_value(obj.radius)}")
    else:
        lines.append(f"radius_factor = {_value(obj.radius_factor)}")
    lines += [
        f"mass_factor = {_value(obj.mass_factor)}",
        f"friction_factor = {_value(obj.friction_factor)}",
        f"attraction_factor = {_value(obj.attraction_factor)}",
    ]
    return lines


def _settings_lines(table: str, settings: Any, default: Any) -> list[str]:
    """[table] with the fields that differ from the defaults (nested settings as subtables)."""
    plain: list[str] = []
    nested: list[str] = []
    for f in fields(settings):
        value, base = getattr(settings, f.name), getattr(default, f.name)
        if value == base:
            continue
        if hasattr(value, "__dataclass_fields__"):
            nested += _settings_lines(f"{table}.{f.name}", value, base)
        else:
            plain.append(f"{f.name} = {_value(value)}")
    if not plain and not nested:
        return []
    return (["", f"[{table}]", *plain] if plain else []) + nested


def _value(value: Any) -> str:
    """A TOML value: floats written so they read back exactly (repr), enums by name."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, Enum):
        return _value(value.name)
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if not math.isfinite(value):
            raise ValueError(f"TOML scenarios hold finite numbers only, not {value}")
        return repr(value)
    if isinstance(value, str):  # tomlkit escapes what TOML needs escaped (quotes, controls)
        return tomlkit.string(value).as_string()
    if isinstance(value, list | tuple):
        return "[" + ", ".join(_value(v) for v in value) + "]"
    raise TypeError(f"no TOML for {value!r}")


def to_published_cfg(scenario: Scenario, particles: int) -> str:
    """The published configuration format for what it can say of a scenario (the swarm's size,
    dead particles or the object, the lamp, duration, seed, obstacles, outputs); `stats` finds
    the lamp in it. Our TOML beside it is the complete description."""
    s = scenario
    lines = ["# The same run in the published simulator's format (scenario.toml says it all)."]

    def put(key: str, *values: Any) -> None:
        lines.extend([key, " ".join(_cfg(v) for v in values)])

    if s.objects:
        obj = s.objects[0]
        put("nCells", particles + 1)
        put("nDead", -1)
        radius_factor = (
            obj.radius / s.physics.r_min if obj.radius is not None else obj.radius_factor
        )
        put("radFactor", radius_factor)
        put("massFactor", obj.mass_factor)
        put("frictionFactor", obj.friction_factor)
        put("attractionFactor", obj.attraction_factor)
    else:
        put("nCells", particles)
        put("nDead", s.dead.resolve(particles))
        put("time_to_dead", s.dead.at_s)
    put("light_x", s.lamp.x)
    put("light_y", s.lamp.y)
    put("max_time", s.duration_s)
    put("seed", s.seed)
    put("light_shadow", int(s.shadow))
    put("dump_interval", s.output.dump_interval_s)
    put("testing", int(s.output.per_particle))
    if s.rects:
        put("nobstacles", len(s.rects))
        put("x1obs", *(r.x_min for r in s.rects))
        put("x2obs", *(r.x_max for r in s.rects))
        put("y1obs", *(r.y_min for r in s.rects))
        put("y2obs", *(r.y_max for r in s.rects))
    if s.circles:
        put("n_cir_obstacles", len(s.circles))
        put("x_cir_obs", *(c.x for c in s.circles))
        put("y_cir_obs", *(c.y for c in s.circles))
        put("r_cir_obs", *(c.radius for c in s.circles))
    put("csv_filename", s.output.csv_name)
    return "\n".join(lines) + "\n"


def _cfg(value: Any) -> str:
    if isinstance(value, float):
        return repr(value)
    return str(value)
