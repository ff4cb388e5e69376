"""Our scenario file: TOML (see scenarios/README in the repository's README, "Simulating a
swarm"), read into a Scenario with every mistake reported as file:line: key: what."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path
from typing import Any

from particlebot.options import REACH_M
from particlebot.sim.particles.model.firmware import FirmwareSettings
from particlebot.sim.particles.model.published import PublishedSettings
from particlebot.sim.scenarios.fields import Fields
from particlebot.sim.scenarios.scenario import (
    MAX_DURATION_S,
    MAX_SEED,
    ControllerKind,
    ControllerSpec,
    DeadSpec,
    FreeSpec,
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
from particlebot.toml_lines import key_lines

TOP_KEYS = (
    "name",
    "seed",
    "duration_s",
    "shadow",
    "precision",
    "swarm",
    "lamp",
    "rectangle",
    "circle",
    "object",
    "dead",
    "free",
    "controller",
    "physics",
    "output",
)
SHADOW_NAMES = {"ignore": ShadowMode.IGNORE, "last": ShadowMode.LAST, "still": ShadowMode.STILL}


def read_scenario(path: Path) -> Scenario:
    """Reads our TOML scenario file; ScenarioError (one line) on any mistake."""
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise ScenarioError(f"cannot read {path}: {exc}") from None
    return parse_scenario(text, path)


def parse_scenario(text: str, path: Path | None = None) -> Scenario:
    """A scenario from TOML text; relative file names in it are relative to path's folder."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        message = str(exc)
        found = re.search(r"\(at line (\d+), column \d+\)", message)
        where = f"{path}:{found.group(1)}" if path and found else str(path or "scenario")
        raise ScenarioError(f"{where}: not valid TOML: {message}") from None
    if not data:
        # Every key has a default, so an empty file would run; it is almost surely the wrong
        # file (or one cut short), and a run of the defaults would hide that.
        raise ScenarioError(
            f"{path or 'scenario'}: holds no keys (empty, or only comments): for a run of the "
            'defaults give no scenario, or at least one key such as name = "run"'
        )
    source = SourceMap(path, tuple(sorted(key_lines(text).items())))
    return _Reader(source, path.parent if path else Path(".")).scenario(data)


class _Reader:
    def __init__(self, source: SourceMap, folder: Path) -> None:
        self.source = source
        self.f = Fields(source)
        self.folder = folder

    def scenario(self, data: dict[str, Any]) -> Scenario:
        f = self.f
        f.only(data, "", TOP_KEYS)
        physics = self.physics(f.table(data, "physics"))
        shadow = self.shadow(data)
        precision = f.string(data, "precision", "", "float64")
        if precision not in ("float64", "float32"):
            raise f.fail("precision", f"must be 'float64' or 'float32', not {precision!r}")
        scenario = Scenario(
            name=self.name(data),
            swarm=self.swarm(f.table(data, "swarm")),
            lamp=self.lamp(f.table(data, "lamp")),
            rects=tuple(self.rectangles(data)),
            circles=tuple(self.circles(data)),
            objects=tuple(self.objects(data)),
            dead=self.dead(f.table(data, "dead")),
            free=self.free(f.table(data, "free")),
            controller=self.controller(f.table(data, "controller")),
            physics=physics,
            shadow=shadow,
            duration_s=f.number(data, "duration_s", "", 600.0, above=0, maximum=MAX_DURATION_S),
            seed=f.integer(data, "seed", "", 0, maximum=MAX_SEED),
            precision="float32" if precision == "float32" else "float64",
            output=self.output(f.table(data, "output")),
            source=self.source,
        )
        placed_here = scenario.swarm.placement is not PlacementKind.FILE  # else: when built
        if (
            placed_here
            and scenario.dead.resolve(scenario.swarm.particles) > scenario.swarm.particles
        ):
            key = "dead.fraction" if scenario.dead.fraction is not None else "dead.count"
            raise f.fail(key, f"more dead particles than the swarm's {scenario.swarm.particles}")
        return scenario

    def name(self, data: dict[str, Any]) -> str:
        name = self.f.string(data, "name", "", "run")
        if not re.fullmatch(r"[A-Za-z0-9][A-Za-z0-9_.\-]*", name):
            raise self.f.fail("name", f"must be letters, digits, '.', '_' or '-', not {name!r}")
        return name

    def shadow(self, data: dict[str, Any]) -> ShadowMode:
        if "shadow" not in data:
            return ShadowMode.IGNORE
        value = data["shadow"]
        if isinstance(value, str) and value in SHADOW_NAMES:
            return SHADOW_NAMES[value]
        if isinstance(value, int) and not isinstance(value, bool) and value in (0, 1, 2):
            return ShadowMode(value)
        raise self.f.fail(
            "shadow", f"must be 'ignore', 'last', 'still' (or 0, 1, 2), not {value!r}"
        )

    def swarm(self, table: dict[str, Any]) -> SwarmSpec:
        f, p = self.f, "swarm"
        f.only(table, p, ("particles", "placement", "at", "spacing", "direction_deg", "file"))
        placement = f.choice(table, "placement", p, PlacementKind, PlacementKind.ALGORITHM5)
        at = f.numbers(table, "at", p, 2)
        spacing = (
            f.number(table, "spacing", p, 0.0, above=0, maximum=REACH_M)
            if "spacing" in table
            else None
        )
        file = None
        if placement is PlacementKind.FILE:
            if "file" not in table:
                raise f.fail("swarm.placement", "placement 'file' needs `file = \"...\"`")
            file = self.folder / f.string(table, "file", p, "")
            if not file.is_file():
                raise f.fail("swarm.file", f"no such file: {file}")
        elif "file" in table:
            raise f.fail("swarm.file", "is only for placement = 'file'")
        particles = f.integer(table, "particles", p, 10, minimum=1)
        if placement is PlacementKind.FILE and "particles" in table:
            raise f.fail("swarm.particles", "comes from the file with placement = 'file'")
        return SwarmSpec(
            particles=particles,
            placement=placement,
            at=(at[0], at[1]) if at else (0.0, 0.0),
            spacing=spacing,
            direction_deg=f.number(table, "direction_deg", p, 0.0, minimum=-360, maximum=360),
            file=file,
        )

    def lamp(self, table: dict[str, Any]) -> LampSpec:
        f, p = self.f, "lamp"
        f.only(table, p, ("x", "y", "height"))
        height = (
            f.number(table, "height", p, 0.0, above=0, maximum=REACH_M)
            if "height" in table
            else None
        )
        return LampSpec(f.place(table, "x", p, 0.0), f.place(table, "y", p, 0.0), height)

    def _array(self, data: dict[str, Any], key: str) -> list[tuple[str, dict[str, Any]]]:
        """The [[key]] tables with their paths (key[1], key[2], ...)."""
        value = data.get(key, [])
        if isinstance(value, dict):
            value = [value]
        if not isinstance(value, list) or not all(isinstance(v, dict) for v in value):
            raise self.f.fail(key, f"must be [[{key}]] tables")
        return [(f"{key}[{i}]", table) for i, table in enumerate(value, start=1)]

    def rectangles(self, data: dict[str, Any]) -> list[Rect]:
        rects = []
        for p, table in self._array(data, "rectangle"):
            self.f.only(table, p, ("x", "y"))
            x, y = self._span(table, "x", p), self._span(table, "y", p)
            rects.append(Rect(x[0], x[1], y[0], y[1]))
        return rects

    def _span(self, table: dict[str, Any], key: str, prefix: str) -> tuple[float, float]:
        span = self.f.numbers(table, key, prefix, 2)
        if span is None:
            raise self.f.fail(prefix, f"needs {key} = [min, max]")
        if not span[0] < span[1]:
            raise self.f.fail(f"{prefix}.{key}", f"needs min < max, not {list(span)}")
        return span[0], span[1]

    def circles(self, data: dict[str, Any]) -> list[Circle]:
        circles = []
        for p, table in self._array(data, "circle"):
            f = self.f
            f.only(table, p, ("x", "y", "radius"))
            if "radius" not in table:
                raise f.fail(p, "needs radius = ...")
            circles.append(
                Circle(
                    f.place(table, "x", p, 0.0),
                    f.place(table, "y", p, 0.0),
                    f.number(table, "radius", p, 1.0, above=0, maximum=REACH_M),
                )
            )
        return circles

    def objects(self, data: dict[str, Any]) -> list[ObjectSpec]:
        objects = []
        for p, table in self._array(data, "object"):
            f = self.f
            f.only(
                table,
                p,
                (
                    "x",
                    "y",
                    "radius",
                    "radius_factor",
                    "mass_factor",
                    "friction_factor",
                    "attraction_factor",
                ),
            )
            if ("x" in table) != ("y" in table):
                raise f.fail(p, "give both x and y, or neither (in front of the swarm)")
            if "radius" in table and "radius_factor" in table:
                raise f.fail(f"{p}.radius", "give radius or radius_factor, not both")
            objects.append(
                ObjectSpec(
                    x=f.place(table, "x", p, 0.0) if "x" in table else None,
                    y=f.place(table, "y", p, 0.0) if "y" in table else None,
                    radius=f.number(table, "radius", p, 0.0, above=0, maximum=REACH_M)
                    if "radius" in table
                    else None,
                    radius_factor=f.number(table, "radius_factor", p, 2.0, above=0, maximum=1e3),
                    mass_factor=f.number(table, "mass_factor", p, 1.0, above=1e-6, maximum=1e6),
                    friction_factor=f.number(
                        table, "friction_factor", p, 1.0, minimum=0, maximum=1e3
                    ),
                    attraction_factor=f.number(
                        table, "attraction_factor", p, 0.0, minimum=0, maximum=1e3
                    ),
                )
            )
        return objects

    def dead(self, table: dict[str, Any]) -> DeadSpec:
        f, p = self.f, "dead"
        f.only(table, p, ("count", "fraction", "at_s", "detach"))
        if "count" in table and "fraction" in table:
            raise f.fail("dead.fraction", "give count or fraction, not both")
        fraction = None
        if "fraction" in table:
            fraction = f.number(table, "fraction", p, 0.0, minimum=0)
            if fraction > 1:
                raise f.fail("dead.fraction", f"must be 0..1, not {fraction:g}")
        return DeadSpec(
            count=f.integer(table, "count", p, 0),
            fraction=fraction,
            at_s=f.number(table, "at_s", p, 0.0, minimum=0, maximum=MAX_DURATION_S),
            detach=f.boolean(table, "detach", p, False),
        )

    def free(self, table: dict[str, Any]) -> FreeSpec:
        f, p = self.f, "free"
        f.only(table, p, ("count", "x", "y"))
        count = f.integer(table, "count", p, 0)
        if count == 0:
            return FreeSpec()
        x, y = self._span(table, "x", p), self._span(table, "y", p)
        return FreeSpec(count, Rect(x[0], x[1], y[0], y[1]))

    def controller(self, table: dict[str, Any]) -> ControllerSpec:
        f, p = self.f, "controller"
        f.only(table, p, ("kind", "published", "firmware"))
        published = f.settings(
            PublishedSettings, f.table(table, "published", p), "controller.published",
            PublishedSettings(),
        )  # fmt: skip
        firmware = f.settings(
            FirmwareSettings, f.table(table, "firmware", p), "controller.firmware",
            FirmwareSettings(),
        )  # fmt: skip
        kind = f.choice(table, "kind", p, ControllerKind, ControllerKind.PUBLISHED)
        return ControllerSpec(kind, published, firmware)

    def physics(self, table: dict[str, Any]) -> PhysicsParams:
        return self.f.settings(PhysicsParams, table, "physics", PhysicsParams())

    def output(self, table: dict[str, Any]) -> OutputSpec:
        f, p = self.f, "output"
        f.only(
            table,
            p,
            (
                "dump_interval_s",
                "per_particle",
                "csv",
                "snapshot_interval_s",
                "video",
                "video_frames",
            ),
        )
        names = {}
        for key, default in (("csv", "run.csv"), ("video", "run.mp4")):
            name = f.string(table, key, p, default)
            if Path(name).name != name or name.startswith("."):
                raise f.fail(f"output.{key}", f"must be a file name without a folder: {name!r}")
            names[key] = name
        if not names["csv"].lower().endswith(".csv"):
            raise f.fail("output.csv", f"must end in .csv: {names['csv']!r}")
        if not names["video"].lower().endswith((".mp4", ".gif")):
            raise f.fail("output.video", f"must end in .mp4 or .gif: {names['video']!r}")
        return OutputSpec(
            dump_interval_s=f.number(
                table, "dump_interval_s", p, 60.0, above=0, maximum=MAX_DURATION_S
            ),
            per_particle=f.boolean(table, "per_particle", p, False),
            csv_name=names["csv"],
            snapshot_interval_s=f.number(
                table, "snapshot_interval_s", p, 600.0, above=0, maximum=MAX_DURATION_S
            ),
            video_name=names["video"],
            video_frames=f.integer(table, "video_frames", p, 200, minimum=1, maximum=100_000),
        )
