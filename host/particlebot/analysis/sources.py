"""Where a swarm's centroid over time comes from: a TRACK.csv, a simulator's CSV in the published
format (ours writes the same into its run folders), or a folder holding either. Each reader
returns CentroidSeries in centimetres with what the source says about the lamp and the cycle.

Session logs of a simulated radio will carry world positions (another issue); their reader
belongs in `read_session_log`, registered in READERS like the others.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import numpy.typing as npt

from particlebot.analysis import simcsv, trackfile

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]

# The published simulator's cycle: rise 2 s + fall 2 s + pause 8 s = (Nx + 1) x rise_period with
# Nx = 5 (our notes on its model); Tables S3 and S4 use it.
PUBLISHED_CYCLE_S = 12.0

# Files in a run folder that may be a published-format config: small text files.
_CONFIG_MAX_BYTES = 200_000


class SourceError(ValueError):
    """A source the statistics cannot use, said in one line."""


@dataclass
class CentroidSeries:
    """A centroid over time in centimetres, as the source gives it."""

    name: str
    path: Path
    kind: str
    """'track' or 'simulator' (later: 'log')."""
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


def read_session_log(path: Path) -> list[CentroidSeries]:
    """Session logs carry no world positions yet; the simulated-radio world will add them."""
    raise SourceError(
        f"{path.name}: session logs carry no positions yet (they will once the simulated "
        "world logs them); track the run's video or give the simulator's CSV"
    )


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
        for candidate in sorted(path.glob("*.csv")):
            reader = _reader_for(candidate, accept)
            if reader is not None:
                found.extend(reader(candidate))
        if not found:
            raise SourceError(f"{path} holds no TRACK.csv and no simulator CSV")
        return found
    reader = _reader_for(path, accept)
    if reader is None:
        raise SourceError(
            f"{path} is neither a TRACK.csv, a simulator CSV ('Seed, N' first line) nor a "
            "session log"
        )
    return reader(path)


def median_spacing_s(series: CentroidSeries) -> float:
    t = series.t_s[series.valid]
    return float(np.median(np.diff(t))) if len(t) > 1 else math.nan
