"""TRACK.csv, the tracker's output and the statistics' input: `# key: value` lines saying where
it came from, then t_s, x_cm, y_cm, area_cm2, quality, frame.

x_cm and y_cm are floor centimetres from the field's top-left corner, y down the image; quality
is `ok` or flags joined by `+` (QUALITY_FLAGS says what each means); a lost frame, and one whose
flags say it was dropped (DROPPED), has empty coordinates.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import numpy.typing as npt

from particlebot.errors import ParticlebotError
from particlebot.fileio import atomic_open

FloatArray = npt.NDArray[np.float64]

COLUMNS = ("t_s", "x_cm", "y_cm", "area_cm2", "quality", "frame")
MAGIC = "# particlebot track"

OK = "ok"
QUALITY_FLAGS = {
    "lost": "no swarm region found",
    "edge": "the region touches the image border: part of the swarm may be out of view",
    "lamp": "the region touches the lamp's mask: its outline may be cut there",
    "area": "the region's area jumped against the recent frames (merged or lost a part): dropped",
    "jump": "the centroid moved further since the last good frame than a swarm can: dropped",
    "spike": "the centroid stood apart from its neighbours' median for one frame: dropped",
}
# Flags whose frame is not believed: its row keeps the flags and leaves the coordinates empty.
DROPPED = frozenset({"area", "jump", "spike"})


class TrackFormatError(ParticlebotError, ValueError):
    """Not a TRACK.csv, or a damaged one."""


@dataclass(frozen=True)
class TrackRow:
    t_s: float
    x_cm: float
    y_cm: float
    area_cm2: float
    quality: str
    frame: int

    @property
    def ok(self) -> bool:
        return self.quality == OK


@dataclass
class Track:
    """A TRACK.csv read back: its header and columns as arrays (NaN where lost)."""

    path: Path
    meta: dict[str, str]
    t_s: FloatArray
    x_cm: FloatArray
    y_cm: FloatArray
    area_cm2: FloatArray
    quality: list[str] = field(default_factory=list)

    @property
    def ok(self) -> npt.NDArray[np.bool_]:
        return np.array([q == OK for q in self.quality], dtype=bool)

    def lamp_cm(self) -> tuple[float, float] | None:
        text = self.meta.get("lamp_cm", "none")
        try:
            x, y = (float(v) for v in text.split(","))
        except ValueError:
            return None
        return (x, y) if math.isfinite(x) and math.isfinite(y) else None


def _number(value: float, digits: int) -> str:
    return "" if not math.isfinite(value) else f"{value:.{digits}f}"


def write_track(path: Path, rows: Iterable[TrackRow], meta: dict[str, str]) -> int:
    """Writes the header lines and rows; returns how many rows."""
    count = 0
    with atomic_open(path, newline="") as stream:  # whole or absent
        stream.write(f"{MAGIC}\n")
        for key, value in meta.items():
            stream.write(f"# {key}: {value}\n")
        writer = csv.writer(stream)
        writer.writerow(COLUMNS)
        for row in rows:
            writer.writerow(
                [
                    f"{row.t_s:.3f}",
                    _number(row.x_cm, 2),
                    _number(row.y_cm, 2),
                    _number(row.area_cm2, 1),
                    row.quality,
                    row.frame,
                ]
            )
            count += 1
    return count


def looks_like_track(path: Path) -> bool:
    try:
        with path.open("r", encoding="utf-8", errors="replace") as stream:
            return stream.readline().strip() == MAGIC
    except OSError:
        return False


def read_track(path: Path) -> Track:
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except (OSError, UnicodeDecodeError) as exc:
        raise TrackFormatError(f"cannot read {path}: {exc}") from None
    meta: dict[str, str] = {}
    body_start = 0
    for body_start, line in enumerate(lines):  # noqa: B007 - the index is used below
        if not line.startswith("#"):
            break
        key, _, value = line[1:].partition(":")
        if value:
            meta[key.strip()] = value.strip()
    else:
        body_start = len(lines)
    rows = list(csv.reader(lines[body_start:]))
    if not rows or tuple(cell.strip() for cell in rows[0][:5]) != COLUMNS[:5]:
        raise TrackFormatError(f"{path}: no '{','.join(COLUMNS)}' header")
    t, x, y, area, quality = [], [], [], [], []
    for line_no, row in enumerate(rows[1:], start=body_start + 2):
        if not row:
            continue
        try:
            t.append(float(row[0]))
            x.append(float(row[1]) if row[1] else math.nan)
            y.append(float(row[2]) if row[2] else math.nan)
            area.append(float(row[3]) if row[3] else math.nan)
            quality.append(row[4].strip())
        except (ValueError, IndexError):
            raise TrackFormatError(f"{path}:{line_no}: not a track row") from None
    return Track(path, meta, np.array(t), np.array(x), np.array(y), np.array(area), quality)
