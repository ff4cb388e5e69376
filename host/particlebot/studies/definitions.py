"""The paper's S9 studies as data: what each sweeps, its defaults, quick presets, and its runs."""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass, fields, replace

from particlebot.errors import ParticlebotError
from particlebot.machine import TooBigError, check_memory
from particlebot.options import LONGEST_S
from particlebot.studies import published as paper
from particlebot.studies.measures import GapPassage, ObjectCarry, RobotAdvance, SpeedTowardLight
from particlebot.studies.packing import densest_packing_diameter_m
from particlebot.studies.published import CYCLE_S, D_MIN_M, R_MIN_M, Published
from particlebot.studies.spec import CellValue, Measure, PassiveObject, Rect, RunSpec, WorldSetup

PLACEMENTS = ("blob", "published-blob", "hex", "line")
FAR_LAMP_M = 20.0
"""Where the speed studies put the lamp: this far beyond the swarm's densest-packing edge, so that
no swarm reaches it within 2 h (10 particles cover about 9 m) and its wavefront is nearly flat."""
WALL_HALF_SPAN_DPD = 3.0
"""The gap study's wall reaches this far either side of the swarm's path: beyond anything the
swarm can reach by going round, so the gap is the only way through."""


GAP_SHADOW = "last"
"""SI S9: particles the obstacle hides from the light "oscillate at the end of the cycle, as if
defining the lowest end of the signal gradient": the simulator's shadow mode LAST."""


class StudyOptionError(ParticlebotError, ValueError):
    """A study option the user gave is wrong; the message is one line, naming the option."""


@dataclass(frozen=True)
class Sweep:
    """The quantity a study varies besides the swarm size."""

    key: str
    """The cell coordinate's name (in run ids, CSV columns)."""
    flag: str
    """Its command-line option."""
    label: str
    """Axis and column title."""
    scale: float
    """Axis value = value x scale (fractions shown as %)."""
    low: float
    high: float | None
    low_inclusive: bool
    what: str
    """The error's description of a valid value."""

    def column(self, value: float) -> str:
        shown = value * self.scale
        return f"{shown:g} %" if self.scale == 100 else f"{shown:g}"

    def check(self, value: float) -> None:
        too_low = value < self.low if self.low_inclusive else value <= self.low
        if not math.isfinite(value) or too_low or (self.high is not None and value > self.high):
            raise StudyOptionError(f"{self.flag}: {value:g} is not {self.what}")


@dataclass(frozen=True)
class Preset:
    """A complete choice of the options a user can set."""

    sizes: tuple[int, ...]
    values: tuple[float, ...]
    seeds: int
    duration_s: float
    skip_s: float = 0.0


@dataclass(frozen=True)
class StudyOptions:
    """What one invocation of a study runs."""

    sizes: tuple[int, ...]
    values: tuple[float, ...]
    seeds: int
    first_seed: int
    duration_s: float
    skip_s: float
    placement: str
    quick: bool
    overrides: tuple[tuple[str, float], ...] = ()
    """Published numbers changed in every run (`--set`)."""


@dataclass(frozen=True)
class Metric:
    key: str
    label: str
    decimals: int
    derived_from: str | None = None
    """Read from another metric of the same run instead of measured: that metric's key..."""
    factor: Callable[[int], float] | None = None
    """...times this factor of the swarm's size. Derived at report time, so runs finished
    before the metric existed have it too."""


@dataclass(frozen=True)
class PublishedTable:
    """A table of the headline metric with the paper's values beside ours: the metric converted
    to the table's unit by `convert`, and the paper's (particles, sweep value) -> value."""

    title: str
    unit: str
    values: Mapping[tuple[int, float], Published]
    convert: Callable[[float], float] = float
    decimals: int = 2
    metric: str | None = None
    """The metric the table shows: None for the study's headline."""


@dataclass(frozen=True)
class Study:
    """One of the paper's studies. Rows of its tables are swarm sizes; columns are the sweep's
    values (a single column where there is no sweep)."""

    name: str
    title: str
    source: str
    """Where in the SI it comes from."""
    sweep: Sweep | None
    metrics: tuple[Metric, ...]
    """The first is the study's headline (tables, plots); the others go to the CSV."""
    default: Preset
    quick: Preset
    world: Callable[[Study, int, float, int, StudyOptions], tuple[WorldSetup, Measure]]
    """(particles, sweep value, seed, options) -> the run's world and measure."""
    tables: tuple[PublishedTable, ...]
    """The report's tables of the headline metric, each with the paper's values where it has
    them (Table S3 in mm/s and Table S4 in % of a diameter per cycle for the dead study)."""
    finding: str
    """What the paper says the study shows (for the report)."""
    uses_skip: bool = False

    @property
    def metric(self) -> Metric:
        return self.metrics[0]

    def specs(self, options: StudyOptions) -> list[RunSpec]:
        """Every run of the study, cell by cell, seed by seed."""
        runs = []
        for n in options.sizes:
            for value in options.values:
                cell: tuple[tuple[str, CellValue], ...] = (("particles", n),)
                if self.sweep is not None:
                    cell += ((self.sweep.key, value),)
                for seed in range(options.first_seed, options.first_seed + options.seeds):
                    setup, measure = self.world(self, n, value, seed, options)
                    if options.overrides:
                        setup = replace(setup, overrides=options.overrides)
                    runs.append(RunSpec(self.name, cell, seed, setup, measure))
        return runs


# ---- the worlds of each study ---------------------------------------------------------------


def _open_floor(
    n: int, seed: int, options: StudyOptions, dead: int = 0, noise: float = 0.0
) -> tuple[WorldSetup, Measure]:
    """A swarm alone on the floor with the lamp far ahead, measured by its speed."""
    setup = WorldSetup(
        particles=n,
        seed=seed,
        duration_s=options.duration_s,
        lamp_x=densest_packing_diameter_m(n) / 2 + FAR_LAMP_M,
        placement=options.placement,
        dead=dead,
        noise_diameters=noise,
    )
    return setup, SpeedTowardLight(skip_s=options.skip_s)


def _dead_world(
    study: Study, n: int, fraction: float, seed: int, options: StudyOptions
) -> tuple[WorldSetup, Measure]:
    return _open_floor(n, seed, options, dead=round(fraction * n))


def _noise_world(
    study: Study, n: int, noise: float, seed: int, options: StudyOptions
) -> tuple[WorldSetup, Measure]:
    return _open_floor(n, seed, options, noise=noise)


def _speed_world(
    study: Study, n: int, unused: float, seed: int, options: StudyOptions
) -> tuple[WorldSetup, Measure]:
    return _open_floor(n, seed, options)


def gap_geometry(n: int, gap_fraction: float) -> tuple[float, tuple[Rect, Rect], float]:
    """The gap study's world for n particles (study frame, metres): the lamp's x, the wall's two
    rectangles, and the x of the wall's far face. The lamp is 2.5 DPD ahead of the initial
    centroid; the wall's near face 0.75 DPD ahead, one minimum diameter thick, across the whole
    path but for a gap of gap_fraction x DPD centred on the line to the lamp."""
    dpd = densest_packing_diameter_m(n)
    near = paper.GAP_OBSTACLE_DPD * dpd
    far = near + D_MIN_M
    half_gap = gap_fraction * dpd / 2
    span = WALL_HALF_SPAN_DPD * dpd
    wall = (Rect(near, far, half_gap, span), Rect(near, far, -span, -half_gap))
    return paper.GAP_LIGHT_DPD * dpd, wall, far


def _gap_world(
    study: Study, n: int, gap_fraction: float, seed: int, options: StudyOptions
) -> tuple[WorldSetup, Measure]:
    lamp_x, wall, far = gap_geometry(n, gap_fraction)
    setup = WorldSetup(
        particles=n,
        seed=seed,
        duration_s=options.duration_s,
        lamp_x=lamp_x,
        placement=options.placement,
        rects=wall,
        shadow=GAP_SHADOW,
    )
    return setup, GapPassage(wall_far_x=far)


def carry_geometry(n: int, radius_fraction: float) -> tuple[float, PassiveObject]:
    """The carry study's world: the object (radius radius_fraction x DPD, the mass and friction of
    one particle, no attraction: Fig. S19's caption) with its near edge 0.75 DPD ahead of the
    initial centroid, as the gap study's obstacle; the lamp FAR_LAMP_M beyond its far edge, so
    that no swarm reaches it in the 3,000 cycles (10 h at 0.5 mm/s is 18 m). With the lamp
    nearer, a swarm that reaches it closes round the object from all sides, and the published
    model's explicit dashpot, 50 x dt per contact on a body of one particle's mass, is unstable
    with that many contacts: measured, the object flew off at 500 m/s and scattered the swarm to
    the walls (100 particles, 40 % DPD, the lamp one DPD beyond the object, after 3 h)."""
    dpd = densest_packing_diameter_m(n)
    radius = radius_fraction * dpd
    near = paper.GAP_OBSTACLE_DPD * dpd
    obj = PassiveObject(x=near + radius, y=0.0, radius_factor=radius / R_MIN_M)
    return near + 2 * radius + FAR_LAMP_M, obj


def _carry_world(
    study: Study, n: int, radius_fraction: float, seed: int, options: StudyOptions
) -> tuple[WorldSetup, Measure]:
    lamp_x, obj = carry_geometry(n, radius_fraction)
    setup = WorldSetup(
        particles=n,
        seed=seed,
        duration_s=options.duration_s,
        lamp_x=lamp_x,
        placement=options.placement,
        passive_object=obj,
    )
    return setup, ObjectCarry()


ANNEX_DEAD_FRACTION = 0.1
ANNEX_DEAD_AT_S = 600.0


def _annex_world(
    study: Study, n: int, free_ratio: float, seed: int, options: StudyOptions
) -> tuple[WorldSetup, Measure]:
    """Fig. S21: a tenth of the robot dies after 10 min and lets go; free_ratio x n loose
    particles lie in a band ahead of it, on its way to the lamp (0 is the control)."""
    dpd = densest_packing_diameter_m(n)
    near = paper.GAP_OBSTACLE_DPD * dpd
    setup = WorldSetup(
        particles=n,
        seed=seed,
        duration_s=options.duration_s,
        lamp_x=dpd / 2 + FAR_LAMP_M,
        placement=options.placement,
        dead=round(ANNEX_DEAD_FRACTION * n),
        dead_at_s=ANNEX_DEAD_AT_S,
        detach_dead=True,
        free_particles=round(free_ratio * n),
        free_region=Rect(near, near + 2.5 * dpd, -near, near) if free_ratio > 0 else None,
    )
    return setup, RobotAdvance()


# ---- the studies ------------------------------------------------------------------------------


def _flatten(table: Mapping[int, Mapping[float, Published]]) -> dict[tuple[int, float], Published]:
    return {(n, value): cell for n, row in table.items() for value, cell in row.items()}


def _fraction_sweep(key: str, flag: str, label: str, high: float, what: str) -> Sweep:
    return Sweep(key, flag, label, 100.0, 0.0, high, True, what)


_SPEED = Metric("speed_mm_s", "speed toward the light (mm/s)", 2)
_SPEED_PAPER_CAMERA = Metric(
    "speed_paper_camera_mm_s",
    "speed toward the light through the paper's camera (mm/s)",
    2,
    derived_from="speed_mm_s",
    factor=paper.paper_camera_factor,
)
"""The speed as the paper would have read it from the published simulator's videos with one
pixel scale for every swarm size (studies.published.paper_camera_factor; docs/studies-camera.md)."""


def _paper_camera_table(
    title: str, values: Mapping[tuple[int, float], Published]
) -> PublishedTable:
    return PublishedTable(
        f"{title} through the paper's camera (one pixel scale, the 1,000-particle camera's)",
        "mm/s",
        values,
        metric=_SPEED_PAPER_CAMERA.key,
    )


_TWO_HOURS = 7200.0
_HALF_HOUR = 1800.0

STUDIES: dict[str, Study] = {
    study.name: study
    for study in (
        Study(
            name="dead",
            title="Speed against the fraction of dead particles",
            source="SI S9, Tables S3 and S4",
            sweep=_fraction_sweep(
                "dead_fraction", "--fractions", "dead particles (%)", 0.99, "a fraction in [0, 1)"
            ),
            metrics=(_SPEED, _SPEED_PAPER_CAMERA),
            default=Preset(
                paper.DEAD_SIZES, paper.DEAD_FRACTIONS, 11, _TWO_HOURS, _HALF_HOUR
            ),
            quick=Preset((10, 100), (0.0, 0.2, 0.4), 3, _HALF_HOUR, 600.0),
            world=_dead_world,
            tables=(
                PublishedTable("Table S3", "mm/s", _flatten(paper.TABLE_S3_MM_S)),
                PublishedTable(
                    "Table S4", "% of the minimum diameter per 12 s cycle",
                    _flatten(paper.TABLE_S4_PERCENT), paper.speed_to_percent_diameter_per_cycle,
                ),
                _paper_camera_table("Table S3", _flatten(paper.TABLE_S3_MM_S)),
            ),
            finding="speed falls as particles die, to a standstill by 60-80 % dead",
            uses_skip=True,
        ),
        Study(
            name="gap",
            title="Passing a narrow gap",
            source="SI S9, Fig. S18, Tables S5 and S6",
            sweep=Sweep(
                "gap_fraction", "--gaps", "gap (% of DPD)", 100.0, 0.0, 2.0, False,
                "a gap in (0, 2] DPD",
            ),
            metrics=(Metric("success", "particles through the gap (fraction)", 2),),
            default=Preset(
                paper.DEAD_SIZES, paper.GAP_FRACTIONS, paper.GAP_RUNS,
                paper.GAP_CYCLES * CYCLE_S,
            ),
            quick=Preset((10, 100), (0.3, 0.5, 0.8), 2, 300 * CYCLE_S),
            world=_gap_world,
            tables=(PublishedTable("Fig. S18 (a figure: no published values)", "fraction", {}),),
            finding=paper.FIG_S18_FINDING,
        ),
        Study(
            name="carry",
            title="Carrying an object",
            source="SI S9, Fig. S19",
            sweep=Sweep(
                "radius_fraction", "--radii", "object radius (% of DPD)", 100.0, 0.0, 2.0, False,
                "a radius in (0, 2] DPD",
            ),
            metrics=(
                Metric("object_advance_m", "object moved toward the light (m)", 2),
                Metric("object_carried", "object still touching the swarm (fraction)", 2),
                Metric("swarm_advance_m", "swarm moved toward the light (m)", 2),
            ),
            default=Preset(
                (1000,), paper.CARRY_RADIUS_FRACTIONS, 5, paper.FIG_S19_CYCLES * CYCLE_S
            ),
            quick=Preset((100,), (0.2, 0.4), 2, _HALF_HOUR),
            world=_carry_world,
            tables=(PublishedTable("Fig. S19 (a figure: no published values)", "m", {}),),
            finding=paper.FIG_S19_FINDING,
        ),
        Study(
            name="noise",
            title="Speed against sensor noise",
            source="SI S9, Fig. S20",
            sweep=Sweep(
                "noise_diameters", "--noise", "distance-estimation error (sd, particle diameters)",
                1.0, 0.0, None, True, "a standard deviation >= 0 in particle diameters",
            ),
            metrics=(_SPEED,),
            default=Preset(
                (paper.NOISE_SIZE,), (0.0, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0), paper.NOISE_SEEDS,
                _TWO_HOURS, _HALF_HOUR,
            ),
            quick=Preset((100,), (0.0, 1.0, 2.0), 3, _HALF_HOUR, 600.0),
            world=_noise_world,
            tables=(
                PublishedTable(
                    "Fig. S20 (noise-free value from Table S3)", "mm/s",
                    {(10000, 0.0): paper.TABLE_S3_MM_S[10000][0.0]},
                ),
            ),
            finding=(
                "an error of one particle diameter costs 33 % of the speed; beyond two the robot "
                "stands still"
            ),
            uses_skip=True,
        ),
        Study(
            name="annex",
            title="Detaching dead particles and annexing free ones",
            source="SI S9, Fig. S21",
            sweep=Sweep(
                "free_ratio", "--free", "free particles (per particle of the robot)", 1.0, 0.0,
                None, True, "a ratio >= 0 of free particles to the robot's",
            ),
            metrics=(
                Metric("robot_speed_mm_s", "robot speed toward the light (mm/s)", 2),
                Metric("heading_error_deg", "heading off the light (degrees)", 1),
                Metric("robot_size_ratio", "robot size at the end / at the start", 2),
            ),
            default=Preset((100,), (0.0, 0.5, 1.0), 11, _TWO_HOURS),
            quick=Preset((30,), (0.0, 1.0), 2, _HALF_HOUR),
            world=_annex_world,
            tables=(PublishedTable("Fig. S21 (a figure: no published values)", "mm/s", {}),),
            finding=paper.FIG_S21_FINDING,
        ),
        Study(
            name="speed",
            title="Speed against swarm size",
            source="SI S9, Table S3 (0 % dead)",
            sweep=None,
            metrics=(_SPEED, _SPEED_PAPER_CAMERA),
            default=Preset(
                (10, 30, 100, 300, 1000, 3000, 10000), (0.0,), 11, _TWO_HOURS, _HALF_HOUR
            ),
            quick=Preset((10, 30, 100), (0.0,), 3, _HALF_HOUR, 600.0),
            world=_speed_world,
            tables=(
                PublishedTable(
                    "Table S3, 0 % dead", "mm/s",
                    {(n, 0.0): row[0.0] for n, row in paper.TABLE_S3_MM_S.items()},
                ),
                _paper_camera_table(
                    "Table S3, 0 % dead",
                    {(n, 0.0): row[0.0] for n, row in paper.TABLE_S3_MM_S.items()},
                ),
            ),
            finding="larger robots are slower per particle but steadier",
            uses_skip=True,
        ),
    )
}  # fmt: skip


# ---- options from the command line -------------------------------------------------------------


@dataclass(frozen=True)
class RawOptions:
    """Options as typed, None where not given."""

    sizes: str | None = None
    values: str | None = None
    seeds: str | None = None
    first_seed: str | None = None
    duration: str | None = None
    skip: str | None = None
    placement: str | None = None
    quick: bool = False
    overrides: str | None = None


def resolve(study: Study, raw: RawOptions) -> StudyOptions:
    """The options a study runs with: the preset (--quick or the paper's), then what was given."""
    preset = study.quick if raw.quick else study.default
    sizes = preset.sizes if raw.sizes is None else _sizes(raw.sizes)
    values = preset.values
    if raw.values is not None:
        if study.sweep is None:
            raise StudyOptionError(f"study {study.name} sweeps nothing but the swarm size")
        values = _numbers(study.sweep.flag, raw.values)
        for value in values:
            study.sweep.check(value)
    seeds = preset.seeds if raw.seeds is None else _whole(raw.seeds, "--seeds", 1)
    first_seed = 1 if raw.first_seed is None else _whole(raw.first_seed, "--first-seed", 0)
    duration = preset.duration_s if raw.duration is None else _seconds(raw.duration, "--duration")
    if raw.skip is not None and not study.uses_skip:
        raise StudyOptionError(f"--skip: study {study.name} does not leave time out")
    skip = preset.skip_s if raw.skip is None else _seconds(raw.skip, "--skip", allow_zero=True)
    if study.uses_skip and skip >= duration:
        raise StudyOptionError(
            f"--skip: leaving out {skip:g} s of a {duration:g} s run leaves nothing to measure"
        )
    placement = raw.placement or "blob"
    if placement not in PLACEMENTS:
        raise StudyOptionError(f"--placement: {placement!r} is not one of {', '.join(PLACEMENTS)}")
    overrides = () if raw.overrides is None else parse_overrides(raw.overrides)
    runs = len(sizes) * max(1, len(values)) * seeds
    if runs > MOST_RUNS:
        raise StudyOptionError(
            f"{len(sizes)} sizes x {max(1, len(values))} values x {seeds:,} seeds is {runs:,} "
            f"runs; a study holds at most {MOST_RUNS:,}"
        )
    return StudyOptions(
        sizes, values, seeds, first_seed, duration, skip, placement, raw.quick, overrides
    )


MOST_RUNS = 1_000_000
"""Runs of one study: the paper's largest has 2,750; a million is weeks of a cluster's time and
as many result files, and listing more would itself take minutes."""
CONTROLLER_OVERRIDES = ("phase_noise", "update_cycles")
"""The published controller's numbers `--set` may change (the others shape the 12 s cycle the
studies' durations and Table S4 are counted in)."""
FIXED_PHYSICS = ("dt", "r_min", "r_max")
"""Numbers the studies' geometry and costs are defined in (DPD, gap sizes, particle-steps)."""


def parse_overrides(text: str) -> tuple[tuple[str, float], ...]:
    """'static_factor=1,phase_noise=0' -> (("phase_noise", 0.0), ("static_factor", 1.0)),
    sorted, each checked against the world's PhysicsParams and the published controller."""
    from particlebot.sim.world.params import PhysicsParams  # plain data, no numba

    # The numbers (a choice such as the neighbour search is not a number of the model).
    physics = {f.name: f.type for f in fields(PhysicsParams) if f.type in ("float", "int", "bool")}
    pairs: dict[str, float] = {}
    for item in _items("--set", text):
        name, sep, value_text = (part.strip() for part in item.partition("="))
        if not sep or not name or not value_text:
            raise StudyOptionError(f"--set: expected NAME=VALUE, got {item!r}")
        if name in FIXED_PHYSICS:
            raise StudyOptionError(f"--set: {name} is fixed in the studies (geometry uses it)")
        if name not in physics and name not in CONTROLLER_OVERRIDES:
            known = ", ".join(sorted(n for n in physics if n not in FIXED_PHYSICS))
            raise StudyOptionError(
                f"--set: {name!r} is not a number of the model ({known}; "
                f"{', '.join(CONTROLLER_OVERRIDES)})"
            )
        if name in pairs:
            raise StudyOptionError(f"--set: {name} given twice")
        try:
            value = float(value_text)
        except ValueError:
            raise StudyOptionError(f"--set: {name}={value_text!r} is not a number") from None
        pairs[name] = value
    try:
        PhysicsParams(**{k: v for k, v in pairs.items() if k in physics})  # type: ignore[arg-type]
    except ValueError as exc:
        raise StudyOptionError(f"--set: {exc}") from None
    for name in CONTROLLER_OVERRIDES:
        if name not in pairs:
            continue
        value = pairs[name]
        whole = name == "update_cycles"
        if not math.isfinite(value) or value < 0 or (whole and (value < 1 or value % 1)):
            what = "a whole number >= 1" if whole else "a number >= 0"
            raise StudyOptionError(f"--set: {name} must be {what}, not {value:g}")
    return tuple(sorted(pairs.items()))


def _items(flag: str, text: str) -> list[str]:
    items = [item.strip() for item in text.split(",")]
    if not text.strip() or any(not item for item in items):
        raise StudyOptionError(f"{flag}: expected a comma-separated list, got {text!r}")
    return items


def _sizes(text: str) -> tuple[int, ...]:
    """Swarm sizes, each one whose world fits in this machine's memory (the study lays out
    each size's geometry here before any worker sees it)."""
    from particlebot.sim.world.params import BYTES_FIXED, BYTES_PER_PARTICLE  # no numba

    sizes = tuple(_whole(item, "--sizes", 1) for item in _items("--sizes", text))
    if len(set(sizes)) != len(sizes):
        raise StudyOptionError(f"--sizes: {text!r} names a size twice")
    largest = max(sizes)
    try:
        check_memory(BYTES_FIXED + BYTES_PER_PARTICLE * largest, f"a swarm of {largest:,}")
    except TooBigError as exc:
        raise StudyOptionError(f"--sizes: {exc}") from None
    return sizes


def _numbers(flag: str, text: str) -> tuple[float, ...]:
    values = []
    for item in _items(flag, text):
        try:
            values.append(float(item))  # the sweep's own check says which are its values
        except ValueError:
            raise StudyOptionError(f"{flag}: {item!r} is not a number") from None
    if len(set(values)) != len(values):
        raise StudyOptionError(f"{flag}: {text!r} names a value twice")
    return tuple(values)


def _whole(text: str, flag: str, minimum: int) -> int:
    try:
        value = int(text.replace("_", ""))
    except ValueError:
        raise StudyOptionError(f"{flag}: {text!r} is not a whole number") from None
    if value < minimum:
        raise StudyOptionError(f"{flag}: {value} is below {minimum}")
    return value


_UNITS = {"": 1.0, "s": 1.0, "min": 60.0, "h": 3600.0, "cycles": CYCLE_S}


def _seconds(text: str, flag: str, allow_zero: bool = False) -> float:
    """Seconds from '7200', '7200s', '90min', '2h' or '4500cycles' (12 s published cycles)."""
    match = re.fullmatch(r"\s*([0-9]*\.?[0-9]+(?:e[+-]?[0-9]+)?)\s*(s|min|h|cycles)?\s*", text)
    if match is None:
        raise StudyOptionError(f"{flag}: {text!r} is not a time (like 7200, 90min, 2h, 4500cycles)")
    seconds = float(match.group(1)) * _UNITS[match.group(2) or ""]
    if seconds < 0 or (seconds == 0 and not allow_zero):
        raise StudyOptionError(f"{flag}: {text!r} must be more than zero")
    if not seconds <= LONGEST_S:
        raise StudyOptionError(f"{flag}: {text!r} is longer than {LONGEST_S:g} s, three years")
    return seconds
