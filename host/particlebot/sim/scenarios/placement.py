"""Where a swarm starts: SI Algorithm 5 (seeded, on a spatial hash), a line, a hexagonal blob, or
positions given in a file."""

from __future__ import annotations

import csv
import math
import tomllib
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numba
import numpy as np
import numpy.typing as npt
from scipy.spatial import cKDTree

from particlebot.errors import ParticlebotError

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
BoolArray = npt.NDArray[np.bool_]

# Angular margin (rad) added to every blocked arc of Algorithm 5's sweep, so that a particle swept
# to the end of an arc clears the blocking one by ~0.15 nm instead of touching it to the last bit.
_ARC_MARGIN_RAD = 1e-9
# What the sweep adds when it jumps to an arc's end, so that it never stalls on rounding.
_STEP_PAST_RAD = 1e-12
# Non-overlapping discs of radius R whose centres lie within 4R of a centre: at most ~25 by area;
# the sweep's buffer holds more than that.
_ARC_BUFFER = 64
# Two discs closer than their radii by more than this overlap (m); placements never do.
OVERLAP_TOLERANCE_M = 1e-9

# Algorithm 5 as the published simulator's code runs it (its CONFIG_RANDOM placement), two numbers
# read from that code: the pivot turns the new disc round the chosen one in steps of this many
# degrees and stops one step short of the first overlap, so it rarely touches a second disc ...
PUBLISHED_PIVOT_STEP_DEG = 10.0
# ... and a draw whose first position overlaps counts as a failure; failures are counted over the
# whole placement, never per disc, and each time the count reaches this many the disc being placed
# is set a diameter further out from its chosen disc (its centre 4R away instead of 2R, then 6R
# ...), leaving a gap of a diameter. In a large blob most draws fail (the chosen disc is inside),
# so the gaps grow with the swarm: 4 % of discs touch none placed before them at 100, 13 % at
# 1,000, a third at 10,000 (5 seeds each; Algorithm 5 as we run it: none).
PUBLISHED_PATIENCE = 200
# The published code tests a new position against every placed disc, the chosen one included,
# with a strict "closer than a diameter": the chosen disc's distance comes out a rounding error
# above or below 2R, so many draws fail against it and many pivots stop at their first step. How
# many depends on how far from the origin the arithmetic happens (float32 as published and
# float64 as here give the same shares: 20, 38 and 46 % of tests for coordinates within 0.5, 2
# and 8 m), so we grow the blob where the published code does, from a first disc at (5, 0), and
# move it to `at` afterwards.
PUBLISHED_FIRST_DISC_M = (5.0, 0.0)


class PlacementError(ParticlebotError, ValueError):
    """Positions that cannot be used: overlapping discs, a damaged file, impossible sizes."""


@dataclass(frozen=True)
class Placement:
    """Centres (m) of every particle and, when the source gives them, their starting radii."""

    xy: FloatArray
    """(N, 2)"""
    radii: FloatArray | None = None
    """(N,), or None: every particle starts contracted."""

    @property
    def count(self) -> int:
        return int(self.xy.shape[0])


# ---- SI Algorithm 5 -------------------------------------------------------------------------


@numba.njit(cache=True, inline="always")
def _bucket(ix: int, iy: int, mask: int) -> int:
    """The hash table's slot of grid cell (ix, iy): the swarm's extent is unbounded, the table
    is not; cells sharing a slot only add candidates that the distance test then rejects."""
    return int(((np.int64(ix) * 73856093) ^ (np.int64(iy) * 19349663)) & mask)


@numba.njit(cache=True, inline="always")
def _hash_table(count: int) -> tuple[IntArray, IntArray, int]:
    """An empty hashed grid for `count` discs: each slot's first disc, each disc's next in its
    slot (-1 ends a chain), and the mask that turns a cell's hash into a slot."""
    size = 1024
    while size < 2 * count:
        size *= 2
    return np.full(size, -1, dtype=np.int64), np.full(count, -1, dtype=np.int64), size - 1


@numba.njit(cache=True, inline="always")
def _file(
    i: int,
    x: float,
    y: float,
    x0: float,
    y0: float,
    diameter: float,
    head: IntArray,
    chain: IntArray,
    mask: int,
) -> None:
    """Files disc i, at (x, y), under its cell (cells one diameter wide from (x0, y0))."""
    key = _bucket(math.floor((x - x0) / diameter), math.floor((y - y0) / diameter), mask)
    chain[i] = head[key]
    head[key] = i


@numba.njit(cache=True, inline="always")
def _second_or_third(
    i: int, xy: FloatArray, radius: float, rng: np.random.Generator
) -> tuple[float, float]:
    """Both Algorithm 5s' second disc (tangent to the first in a random direction) and third
    (tangent to both, on a random side)."""
    diameter = 2.0 * radius
    if i == 1:
        theta = 2.0 * math.pi * rng.random()
        return xy[0, 0] + diameter * math.cos(theta), xy[0, 1] + diameter * math.sin(theta)
    # On the perpendicular bisector of the first two, on a random side.
    side = 1.0 if rng.random() < 0.5 else -1.0
    ux = (xy[1, 0] - xy[0, 0]) / diameter
    uy = (xy[1, 1] - xy[0, 1]) / diameter
    height = math.sqrt(3.0) * radius
    return (
        0.5 * (xy[0, 0] + xy[1, 0]) - side * uy * height,
        0.5 * (xy[0, 1] + xy[1, 1]) + side * ux * height,
    )


@numba.njit(cache=True)
def _algorithm5(
    count: int, radius: float, x0: float, y0: float, rng: np.random.Generator
) -> FloatArray:
    """Algorithm 5 with an infinitely fine sweep, on a hashed grid of cells one diameter wide.

    A chosen particle's free directions are found exactly: each placed neighbour closer than 4R
    to it blocks an arc of directions (a new disc there would overlap that neighbour); the sweep
    starts at the random angle and, while it sits inside a blocked arc, jumps to that arc's end.
    A particle whose whole circle is blocked stays blocked (discs are only ever added), so it is
    dropped from the list the next choice is drawn from: a uniform draw among the rest is what
    the algorithm's "select again" loop amounts to, without drawing blocked particles again and
    again inside a large swarm.
    """
    xy = np.empty((count, 2))
    if count == 0:
        return xy
    two_pi = 2.0 * math.pi
    diameter = 2.0 * radius
    head, chain, mask = _hash_table(count)
    active = np.empty(count, dtype=np.int64)
    n_active = 0
    arc_start = np.empty(_ARC_BUFFER)
    arc_width = np.empty(_ARC_BUFFER)

    placed = 0
    x, y = x0, y0
    while placed < count:
        if placed in (1, 2):
            x, y = _second_or_third(placed, xy, radius, rng)
        elif placed > 2:
            found = False
            while not found:
                pick = int(rng.random() * n_active)
                k = active[pick]
                theta = two_pi * rng.random()
                cx, cy = xy[k, 0], xy[k, 1]
                # Arcs blocked by the neighbours within 4R (cells of 2R: two rings around k's).
                arcs = 0
                ix = math.floor((cx - x0) / diameter)
                iy = math.floor((cy - y0) / diameter)
                for dx in range(-2, 3):
                    for dy in range(-2, 3):
                        j = head[_bucket(ix + dx, iy + dy, mask)]
                        while j >= 0:
                            if j != k:
                                rx = xy[j, 0] - cx
                                ry = xy[j, 1] - cy
                                d = math.sqrt(rx * rx + ry * ry)
                                if d < 2.0 * diameter:
                                    half = math.acos(d / (2.0 * diameter)) + _ARC_MARGIN_RAD
                                    arc_start[arcs] = math.atan2(ry, rx) - half
                                    arc_width[arcs] = 2.0 * half
                                    arcs += 1
                            j = chain[j]
                # Sweep counterclockwise from theta to the first direction no arc blocks.
                swept = 0.0
                moved = True
                while moved and swept < two_pi:
                    moved = False
                    for a in range(arcs):
                        into = (theta - arc_start[a]) % two_pi
                        if into < arc_width[a]:
                            # Just past the arc's end: landing on it exactly could leave theta
                            # a rounding error inside, and the next pass would step by nothing.
                            step = arc_width[a] - into + _STEP_PAST_RAD
                            theta += step
                            swept += step
                            moved = True
                if swept < two_pi:
                    found = True
                    x = cx + diameter * math.cos(theta)
                    y = cy + diameter * math.sin(theta)
                else:
                    n_active -= 1
                    active[pick] = active[n_active]
        xy[placed, 0] = x
        xy[placed, 1] = y
        _file(placed, x, y, x0, y0, diameter, head, chain, mask)
        active[n_active] = placed
        n_active += 1
        placed += 1
    return xy


def algorithm5(
    count: int, radius: float, rng: np.random.Generator, at: tuple[float, float] = (0.0, 0.0)
) -> Placement:
    """SI Algorithm 5: the first disc at `at`, the second tangent to it in a random direction,
    the third tangent to both, then each next one tangent to a randomly chosen placed disc, at
    the first direction from a random start angle (swept counterclockwise) where it overlaps no
    placed disc. Discs of `radius` (the contracted radius); reproducible from the generator."""
    _check_count(count)
    _check_positive("radius", radius)
    _check_point("at", at)
    return Placement(_algorithm5(count, float(radius), float(at[0]), float(at[1]), rng))


def algorithm5_published(
    count: int,
    radius: float,
    rng: np.random.Generator,
    at: tuple[float, float] = (0.0, 0.0),
    *,
    first_disc_seen: bool = True,
) -> Placement:
    """Algorithm 5 as the published simulator's code runs it: the first three discs as in
    `algorithm5`; then a placed disc and an angle are drawn, and a first position that overlaps
    is a failed draw; otherwise the new disc pivots round the chosen one in steps of
    PUBLISHED_PIVOT_STEP_DEG until the next step would overlap. Every PUBLISHED_PATIENCE failed
    draws (counted over the whole placement) the disc being placed goes a diameter further out.
    The chosen disc takes part in the overlap test, rounding and all, as in the published code.
    Sparser than `algorithm5`, and the more so the larger the swarm: the SI's "more sparse
    configurations that don't reconfigure as quickly" at 1,000 and 10,000 particles (S8).

    first_disc_seen=False files the first disc nowhere the overlap test looks, as the published
    code does (it files it in the grid cell of (0, 0) while it sits at (5, 0)), so later discs
    may be put down on top of it; the default leaves that out (research/first_disc.py measures
    what it changes)."""
    _check_count(count)
    _check_positive("radius", radius)
    _check_point("at", at)
    first_x, first_y = PUBLISHED_FIRST_DISC_M
    xy = _algorithm5_published(
        count,
        float(radius),
        first_x,
        first_y,
        math.radians(PUBLISHED_PIVOT_STEP_DEG),
        PUBLISHED_PATIENCE,
        rng,
        first_disc_seen,
    )
    xy[:, 0] += float(at[0]) - first_x
    xy[:, 1] += float(at[1]) - first_y
    xy[0] = at
    return Placement(xy)


@numba.njit(cache=True, inline="always")
def _clear(
    x: float,
    y: float,
    xy: FloatArray,
    head: IntArray,
    chain: IntArray,
    mask: int,
    x0: float,
    y0: float,
    diameter: float,
) -> bool:
    """No placed disc's centre lies closer than a diameter to (x, y) (touching is clear)."""
    ix = math.floor((x - x0) / diameter)
    iy = math.floor((y - y0) / diameter)
    for dx in range(-1, 2):
        for dy in range(-1, 2):
            j = head[_bucket(ix + dx, iy + dy, mask)]
            while j >= 0:
                rx = xy[j, 0] - x
                ry = xy[j, 1] - y
                if rx * rx + ry * ry < diameter * diameter:
                    return False
                j = chain[j]
    return True


@numba.njit(cache=True)
def _algorithm5_published(
    count: int,
    radius: float,
    x0: float,
    y0: float,
    pivot_step: float,
    patience: int,
    rng: np.random.Generator,
    first_disc_seen: bool,
) -> FloatArray:
    """algorithm5_published on a hashed grid of cells one diameter wide (the overlap test's
    reach, so the 3 x 3 cells round a position hold every disc it could overlap)."""
    xy = np.empty((count, 2))
    two_pi = 2.0 * math.pi
    diameter = 2.0 * radius
    head, chain, mask = _hash_table(count)
    failures = 0
    x, y = x0, y0
    for i in range(count):
        if i in (1, 2):
            x, y = _second_or_third(i, xy, radius, rng)
        elif i > 2:
            reach = diameter  # centre to centre from the chosen disc
            while True:
                k = int(rng.random() * i)
                if failures == patience:
                    failures = 0
                    reach += diameter
                theta = two_pi * rng.random()
                cx, cy = xy[k, 0], xy[k, 1]
                if not _clear(
                    cx + reach * math.cos(theta),
                    cy + reach * math.sin(theta),
                    xy,
                    head,
                    chain,
                    mask,
                    x0,
                    y0,
                    diameter,
                ):
                    failures += 1
                    continue
                # Pivot until the next step would overlap (a whole turn if nothing is near).
                turned = 0.0
                while turned < two_pi:
                    nx = cx + reach * math.cos(theta + pivot_step)
                    ny = cy + reach * math.sin(theta + pivot_step)
                    if not _clear(nx, ny, xy, head, chain, mask, x0, y0, diameter):
                        break
                    theta += pivot_step
                    turned += pivot_step
                x = cx + reach * math.cos(theta)
                y = cy + reach * math.sin(theta)
                break
        xy[i, 0] = x
        xy[i, 1] = y
        if i > 0 or first_disc_seen:
            _file(i, x, y, x0, y0, diameter, head, chain, mask)
    return xy


# ---- regular placements ---------------------------------------------------------------------


def line(
    count: int,
    spacing: float,
    direction_deg: float = 0.0,
    at: tuple[float, float] = (0.0, 0.0),
) -> Placement:
    """A straight line: the first centre at `at`, the next ones `spacing` apart along
    `direction_deg` (counterclockwise from +x)."""
    _check_count(count)
    _check_positive("spacing", spacing)
    _check_point("at", at)
    if not math.isfinite(direction_deg):
        raise PlacementError(f"direction must be a finite angle, not {direction_deg}")
    angle = math.radians(direction_deg)
    steps = np.arange(count, dtype=np.float64) * spacing
    xy = np.column_stack((at[0] + steps * math.cos(angle), at[1] + steps * math.sin(angle)))
    return Placement(xy)


def hexagonal(count: int, spacing: float, at: tuple[float, float] = (0.0, 0.0)) -> Placement:
    """A hexagonal blob: the first centre at `at`, then ring after ring around it (ring n holds
    6n centres `spacing` apart, starting on +x and going counterclockwise, as the published
    simulator's hex grid fills them); the last ring may be partly filled."""
    _check_count(count)
    _check_positive("spacing", spacing)
    _check_point("at", at)
    corners = np.array([[math.cos(k * math.pi / 3), math.sin(k * math.pi / 3)] for k in range(7)])
    points = [np.zeros((1, 2))]
    total, ring = 1, 1
    while total < count:
        # Side k of ring n walks from corner k (n steps out) toward corner k + 1.
        j = np.arange(ring, dtype=np.float64)[:, None]
        sides = [corners[k] * (ring - j) + corners[k + 1] * j for k in range(6)]
        points.append(np.concatenate(sides) * spacing)
        total += 6 * ring
        ring += 1
    xy = np.concatenate(points)[:count] + np.asarray(at, dtype=np.float64)
    return Placement(xy)


def scatter(
    count: int,
    radius: float,
    region: tuple[float, float, float, float],
    rng: np.random.Generator,
    avoid_xy: FloatArray,
    avoid_r: FloatArray,
    blocked: Callable[[FloatArray, FloatArray], BoolArray] | None = None,
) -> Placement:
    """`count` discs dropped at uniformly random spots of the rectangle (x_min, x_max, y_min,
    y_max), wholly inside it, each kept only where it overlaps no disc kept before, none of
    the discs to avoid (centres avoid_xy, radii avoid_r) and nothing `blocked` (centres, radii)
    reports: random sequential addition, the loose particles of Fig. S21."""
    _check_count(count)
    _check_positive("radius", radius)
    x_min, x_max, y_min, y_max = region
    if x_max - x_min < 2 * radius or y_max - y_min < 2 * radius:
        raise PlacementError(f"a region of {x_max - x_min:g} x {y_max - y_min:g} m holds no disc")
    tree = cKDTree(avoid_xy) if len(avoid_xy) else None
    reach = 2.0 * max(float(np.max(avoid_r, initial=radius)), radius)
    cell = 2.0 * radius
    kept: list[tuple[float, float]] = []
    grid: dict[tuple[int, int], list[int]] = {}
    tries = 0
    while len(kept) < count:
        if tries > 200 * count + 1000:
            raise PlacementError(
                f"only {len(kept)} of {count} loose particles fit in the region "
                f"x {x_min:g}..{x_max:g}, y {y_min:g}..{y_max:g}"
            )
        batch = 256
        tries += batch
        xy = np.column_stack(
            (
                rng.uniform(x_min + radius, x_max - radius, batch),
                rng.uniform(y_min + radius, y_max - radius, batch),
            )
        )
        free = np.ones(batch, dtype=np.bool_)
        if tree is not None:
            for i, near in enumerate(tree.query_ball_point(xy, reach)):
                if near:
                    gaps = np.hypot(*(avoid_xy[near] - xy[i]).T) - avoid_r[near] - radius
                    free[i] = bool((gaps >= 0).all())
        if blocked is not None:
            free &= ~blocked(xy, np.full(batch, radius))
        for x, y in xy[free]:
            ix, iy = math.floor(x / cell), math.floor(y / cell)
            clear = all(
                math.hypot(x - kept[j][0], y - kept[j][1]) >= 2 * radius
                for dx in (-1, 0, 1)
                for dy in (-1, 0, 1)
                for j in grid.get((ix + dx, iy + dy), ())
            )
            if clear:
                grid.setdefault((ix, iy), []).append(len(kept))
                kept.append((float(x), float(y)))
                if len(kept) == count:
                    break
    return Placement(np.array(kept, dtype=np.float64).reshape(count, 2))


# ---- positions from a file ------------------------------------------------------------------


def from_file(path: Path) -> Placement:
    """Centres (and optionally radii) from a CSV (columns x, y[, r], a header line optional) or
    a TOML file (`particles = [[x, y], [x, y, r], ...]`), in metres."""
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise PlacementError(f"cannot read {path}: {exc}") from None
    rows = _toml_rows(path, text) if path.suffix.lower() == ".toml" else _csv_rows(path, text)
    if not rows:
        raise PlacementError(f"{path}: no positions")
    widths = {len(row) for row in rows}
    if len(widths) != 1:
        raise PlacementError(f"{path}: every position needs the same columns (x, y or x, y, r)")
    table = np.asarray(rows, dtype=np.float64)
    radii = table[:, 2].copy() if table.shape[1] == 3 else None
    if radii is not None and not (radii > 0).all():
        raise PlacementError(f"{path}: radius {radii[~(radii > 0)][0]:g} is not positive")
    return Placement(np.ascontiguousarray(table[:, :2]), radii)


def _csv_rows(path: Path, text: str) -> list[list[float]]:
    rows: list[list[float]] = []
    for line_no, cells in enumerate(csv.reader(text.splitlines()), start=1):
        cells = [c.strip() for c in cells]
        if not cells or not any(cells) or cells[0].startswith("#"):
            continue
        if line_no == 1 and not _is_number(cells[0]):
            if [c.lower() for c in cells] not in (["x", "y"], ["x", "y", "r"]):
                raise PlacementError(f"{path}:1: the header must be 'x, y' or 'x, y, r'")
            continue
        rows.append(_position(path, line_no, cells))
    return rows


def _toml_rows(path: Path, text: str) -> list[list[float]]:
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise PlacementError(f"{path}: {exc}") from None
    entries = data.get("particles")
    if not isinstance(entries, list):
        raise PlacementError(f"{path}: needs `particles = [[x, y], ...]`")
    rows = []
    for number, entry in enumerate(entries, start=1):
        if not isinstance(entry, list):
            raise PlacementError(f"{path}: particle {number} is not a list [x, y] or [x, y, r]")
        rows.append(_position(path, None, [str(v) for v in entry], number))
    return rows


def _position(path: Path, line_no: int | None, cells: list[str], number: int = 0) -> list[float]:
    where = f"{path}:{line_no}" if line_no is not None else f"{path}: particle {number}"
    if len(cells) not in (2, 3):
        raise PlacementError(f"{where}: needs x, y or x, y, r, not {len(cells)} values")
    values = []
    for cell in cells:
        try:
            value = float(cell)
        except ValueError:
            value = math.nan
        if not math.isfinite(value):
            raise PlacementError(f"{where}: {cell!r} is not a finite number")
        values.append(value)
    return values


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


# ---- checks ---------------------------------------------------------------------------------


def overlaps(xy: FloatArray, radii: FloatArray | float) -> tuple[int, int] | None:
    """The first pair of discs that overlap by more than OVERLAP_TOLERANCE_M, or None."""
    count = len(xy)
    if count < 2:
        return None
    r = np.broadcast_to(np.asarray(radii, dtype=np.float64), (count,))
    tree = cKDTree(xy)
    pairs = tree.query_pairs(2.0 * float(r.max()), output_type="ndarray")
    if len(pairs) == 0:
        return None
    i, j = pairs[:, 0], pairs[:, 1]
    gap = np.hypot(*(xy[i] - xy[j]).T) - r[i] - r[j]
    bad = np.flatnonzero(gap < -OVERLAP_TOLERANCE_M)
    if len(bad) == 0:
        return None
    first = bad[np.lexsort((j[bad], i[bad]))[0]]
    return int(i[first]), int(j[first])


def _check_count(count: int) -> None:
    if isinstance(count, bool) or not isinstance(count, int | np.integer) or count < 1:
        raise PlacementError(f"a placement needs a whole number of particles >= 1, not {count}")


def _check_positive(name: str, value: float) -> None:
    if not (math.isfinite(value) and value > 0):
        raise PlacementError(f"{name} must be a number > 0, not {value}")


def _check_point(name: str, point: tuple[float, float]) -> None:
    if len(point) != 2 or not all(math.isfinite(v) for v in point):
        raise PlacementError(f"{name} must be two finite numbers (x, y), not {point}")
