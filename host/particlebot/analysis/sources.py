"""Where a swarm's centroid over time comes from: a TRACK.csv, a simulator's CSV in the published
format (ours writes the same into its run folders), a session log of a simulated radio (which
records the world's truth), or a folder holding any of them. Each reader returns CentroidSeries
in centimetres with what the source says about the lamp and the cycle.
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import numpy.typing as npt

from particlebot.analysis import trackfile
from particlebot.errors import ParticlebotError
from particlebot.fileio import finished_files
from particlebot.logs import jsonl
from particlebot.sim.runs import simcsv
from particlebot.sim.swarm import records as world

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]

# The published simulator's cycle: rise 2 s + fall 2 s + pause 8 s = (Nx + 1) x rise_period with
# Nx = 5 (our notes on its model); Tables S3 and S4 use it.
PUBLISHED_CYCLE_S = 12.0

# Files in a run folder that may be a published-format config: small text files.
_CONFIG_MAX_BYTES = 200_000


class SourceError(ParticlebotError, ValueError):
    """A source the statistics cannot use, said in one line."""


@dataclass
class CentroidSeries:
    """A centroid over time in centimetres, as the source gives it."""

    name: str
    path: Path
    kind: str
    """'track', 'simulator' or 'log'."""
    t_s: FloatArray
    x_cm: FloatArray
    y_cm: FloatArray
    valid: BoolArray
    """Rows to use (a track's good frames)."""
    y_down: bool
    """True for image-style coordinates (y grows down); the statistics turn them y-up first."""
    lamp_cm: tuple[float, float] | None = None
    lamp_from: str = ""
    cycle_s: float | None = None
    """The cycle the source ran at, when it knows."""
    cycle_from: str = ""
    notes: list[str] = field(default_factory=list)


def read_track_source(path: Path, accept: frozenset[str] = frozenset()) -> list[CentroidSeries]:
    """A TRACK.csv: rows whose quality is ok or only carries flags in `accept`."""
    try:
        track = trackfile.read_track(path)
    except trackfile.TrackFormatError as exc:
        raise SourceError(str(exc)) from None
    usable = np.array(
        [q == trackfile.OK or set(q.split("+")) <= accept for q in track.quality], dtype=bool
    )
    usable &= np.isfinite(track.x_cm) & np.isfinite(track.y_cm)
    series = CentroidSeries(
        name=path.name,
        path=path,
        kind="track",
        t_s=track.t_s,
        x_cm=track.x_cm,
        y_cm=track.y_cm,
        valid=usable,
        y_down=True,
    )
    lamp = track.lamp_cm()
    if lamp is not None:
        series.lamp_cm, series.lamp_from = lamp, "the track's header"
    dropped = int((~usable).sum())
    if dropped:
        series.notes.append(f"{dropped} of {len(usable)} frames flagged or lost, not used")
    return [series]


def _config_light(folder: Path) -> tuple[tuple[float, float], Path] | None:
    for candidate in sorted(folder.iterdir()):
        if (
            candidate.is_file()
            and candidate.suffix.lower() not in (".csv", ".avi", ".mp4", ".png", ".jsonl")
            and candidate.stat().st_size < _CONFIG_MAX_BYTES
        ):
            light = simcsv.light_from_config(candidate)
            if light is not None:
                return light, candidate
    return None


def trilaterate(points: FloatArray, distances: FloatArray) -> tuple[float, float] | None:
    """The point at the given distances from a path of points (least squares), or None when the
    path is too short or too straight to place it."""
    good = np.isfinite(points).all(axis=1) & np.isfinite(distances)
    p, d = points[good], distances[good]
    if len(p) < 3:
        return None
    # |p_k - L|^2 = d_k^2 minus the same for p_0 is linear in L:
    # 2 (p_k - p_0) . L = |p_k|^2 - |p_0|^2 - d_k^2 + d_0^2
    a = 2 * (p[1:] - p[0])
    b = (p[1:] ** 2).sum(axis=1) - (p[0] ** 2).sum() - d[1:] ** 2 + d[0] ** 2
    _, singular, axes = np.linalg.svd(a, full_matrices=False)
    if singular[0] < 1e-12:
        return None
    if singular[-1] >= 1e-3 * singular[0]:
        solution, *_ = np.linalg.lstsq(a, b, rcond=None)
    else:
        # A straight path fixes only how far along it the point lies; the point is placed only
        # when it lies on the path's line (a swarm heading straight for the lamp), where the
        # two mirror-image answers meet.
        direction = axes[0]
        along = float(np.linalg.lstsq(a @ direction[:, None], b, rcond=None)[0][0])
        foot = p[0] + (along - float(p[0] @ direction)) * direction
        off_line = d[0] ** 2 - float(np.sum((foot - p[0]) ** 2))
        if off_line > (0.01 * d[0]) ** 2:
            return None
        solution = foot
    residual = np.abs(np.hypot(*(p - solution).T) - d)
    if float(residual.max()) > 0.01 * max(float(d.max()), 1e-9) + 1e-6:
        return None
    return float(solution[0]), float(solution[1])


def read_simulator_source(path: Path) -> list[CentroidSeries]:
    """A published-format CSV: centroid in metres, y up; the lamp from a config file beside it
    or, failing that, placed from the Distance column."""
    try:
        run = simcsv.read_published_csv(path)
    except simcsv.SimFormatError as exc:
        raise SourceError(str(exc)) from None
    centroid_cm = run.centroid_m * 100
    series = CentroidSeries(
        name=path.name if path.parent.name in ("", ".") else f"{path.parent.name}/{path.name}",
        path=path,
        kind="simulator",
        t_s=run.time_s,
        x_cm=centroid_cm[:, 0],
        y_cm=centroid_cm[:, 1],
        valid=np.isfinite(centroid_cm).all(axis=1) & np.isfinite(run.time_s),
        y_down=False,
        cycle_s=PUBLISHED_CYCLE_S,
        cycle_from="the published simulator's cycle",
        notes=list(run.warnings),
    )
    config = _config_light(path.parent)
    if config is not None:
        (lx, ly), config_path = config
        series.lamp_cm, series.lamp_from = (lx * 100, ly * 100), f"{config_path.name}"
    elif run.distance_m is not None:
        light = trilaterate(run.centroid_m, run.distance_m)
        if light is not None:
            series.lamp_cm = (light[0] * 100, light[1] * 100)
            series.lamp_from = "placed from the Distance column"
    return [series]


CYCLE_START_M = 0.0005
"""A commanded radius this far above the contracted one marks a cycle under way."""


def read_session_log(path: Path) -> list[CentroidSeries]:
    """A session log of a simulated radio: the mean of the particles' centres (the world's
    truth, logged twice a second) from the run's first START to the STOP after it, the lamp from
    the scene, the cycle from the commanded radii (how often each particle starts a cycle)."""
    try:
        records = [record for _, record in jsonl.read_numbered(path)]
        track = world.read_world(records)
    except (jsonl.LogError, world.WorldRecordError) as exc:
        raise SourceError(f"{path.name}: {exc}") from None
    if track is None or len(track.body_t) < 2:
        raise SourceError(
            f"{path.name}: no positions in this log: only a simulated radio's session "
            "(virtual://, emulated://) records them; track the run's video instead"
        )
    start, stop = _run_span(records)
    inside = (track.body_t >= start) & (track.body_t <= stop)
    cx, cy = track.centroid
    series = CentroidSeries(
        name=path.name,
        path=path,
        kind="log",
        t_s=track.body_t[inside],
        x_cm=cx[inside] * 100,
        y_cm=cy[inside] * 100,
        valid=np.ones(int(inside.sum()), dtype=bool),
        y_down=False,
        lamp_cm=(track.lamp[0] * 100, track.lamp[1] * 100),
        lamp_from="the log's scene",
    )
    if math.isfinite(start):
        series.notes.append("from the run's START to its STOP")
    radii = (track.radius_t >= start) & (track.radius_t <= stop)
    cycle = cycle_period(track.radius_t[radii], track.commanded[radii], track.r_min)
    if cycle is not None:
        series.cycle_s, series.cycle_from = cycle, "the particles' commanded radii in the log"
    return [series]


def _run_span(records: list[dict[str, object]]) -> tuple[float, float]:
    """The times of the first START sent and of the first STOP after it (infinite: none)."""
    start, stop = -math.inf, math.inf
    for record in records:
        t = record.get("t")
        if record.get("kind") != "tx" or not isinstance(t, int | float):
            continue
        if record.get("type") == "START" and not math.isfinite(start):
            start = float(t)
        elif record.get("type") == "STOP" and math.isfinite(start) and t > start:
            stop = float(t)
            break
    return start, stop


def cycle_period(t_s: FloatArray, radii: FloatArray, r_min: float) -> float | None:
    """The median time between one cycle's start and the next of the same particle (the period
    of expansion, contraction and pause), from commanded radii sampled at t_s (rows) for each
    particle (columns); None when no particle started two cycles."""
    if radii.size == 0 or not math.isfinite(r_min):
        return None
    moving = radii > r_min + CYCLE_START_M
    gaps: list[float] = []
    for column in moving.T:
        starts = t_s[1:][column[1:] & ~column[:-1]]
        gaps.extend(np.diff(starts).tolist())
    return float(np.median(gaps)) if gaps else None


Reader = Callable[[Path], list[CentroidSeries]]


def _reader_for(path: Path, accept: frozenset[str]) -> Reader | None:
    if path.suffix.lower() == ".jsonl":
        return read_session_log
    if trackfile.looks_like_track(path):
        return lambda p: read_track_source(p, accept)
    if simcsv.looks_published(path):
        return read_simulator_source
    return None


def load_source(path: Path, accept: frozenset[str] = frozenset()) -> list[CentroidSeries]:
    """Every series a path holds: one for a file, one per usable CSV for a folder."""
    if not path.exists():
        raise SourceError(f"no such file or folder: {path}")
    if path.is_dir():
        found = []
        for candidate in sorted([*finished_files(path, "*.csv"), *finished_files(path, "*.jsonl")]):
            reader = _reader_for(candidate, accept)
            if reader is read_session_log:
                # A real radio's logs may lie beside a simulated one's: only those with
                # positions count.
                with contextlib.suppress(SourceError):
                    found.extend(reader(candidate))
            elif reader is not None:
                found.extend(reader(candidate))
        if not found:
            raise SourceError(f"{path} holds no TRACK.csv, simulator CSV or session log")
        return found
    reader = _reader_for(path, accept)
    if reader is None:
        raise SourceError(
            f"{path} is neither a TRACK.csv, a simulator CSV ('Seed, N' first line) nor a "
            "session log (.jsonl)"
        )
    return reader(path)


def median_spacing_s(series: CentroidSeries) -> float:
    t = series.t_s[series.valid]
    return float(np.median(np.diff(t))) if len(t) > 1 else math.nan
