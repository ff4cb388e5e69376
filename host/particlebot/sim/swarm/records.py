"""The world's truth in a session log of a simulated radio: the scene once, then every particle's
position and radius (2 Hz) and commanded radius (10 Hz). Written by the simulated swarm, read by
`particlebot plot` and `particlebot stats`.

    {"t": ..., "kind": "scene", "level": "native", "scenario": "blob", "ids": [1, ...],
     "lamp": [x, y, height], "rects": [[x_min, x_max, y_min, y_max], ...],
     "circles": [[x, y, radius], ...], "objects": [[x, y, radius], ...],
     "r_min": 0.0775, "r_max": 0.1175}
    {"t": ..., "kind": "bodies", "x": [...], "y": [...], "r": [...]}    (metres, ids' order)
    {"t": ..., "kind": "radii", "r": [...]}                            (commanded, metres)
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt

from particlebot.errors import ParticlebotError

FloatArray = npt.NDArray[np.float64]
Record = dict[str, Any]

SCENE = "scene"
BODIES = "bodies"
RADII = "radii"
KINDS = (SCENE, BODIES, RADII)
DECIMALS = 5
"""Metres to 10 micrometres: far below anything a swarm's motion shows, short lines."""


def _metres(values: Iterable[float]) -> list[float]:
    return [round(float(v), DECIMALS) for v in values]


def scene_record(
    *,
    level: str,
    scenario: str,
    ids: Sequence[int],
    lamp: tuple[float, float, float],
    rects: Sequence[tuple[float, float, float, float]],
    circles: Sequence[tuple[float, float, float]],
    objects: Sequence[tuple[float, float, float]],
    r_min: float,
    r_max: float,
) -> Record:
    return {
        "kind": SCENE,
        "level": level,
        "scenario": scenario,
        "ids": list(ids),
        "lamp": _metres(lamp),
        "rects": [_metres(r) for r in rects],
        "circles": [_metres(c) for c in circles],
        "objects": [_metres(o) for o in objects],
        "r_min": r_min,
        "r_max": r_max,
    }


def bodies_record(x: FloatArray, y: FloatArray, r: FloatArray) -> Record:
    return {"kind": BODIES, "x": _metres(x), "y": _metres(y), "r": _metres(r)}


def radii_record(r: FloatArray) -> Record:
    return {"kind": RADII, "r": _metres(r)}


@dataclass
class WorldTrack:
    """The truth of a log: what the scene was and how the bodies moved (times in the log's
    seconds, as the records carry them)."""

    ids: list[int]
    lamp: tuple[float, float, float]
    rects: list[tuple[float, float, float, float]] = field(default_factory=list)
    circles: list[tuple[float, float, float]] = field(default_factory=list)
    objects: list[tuple[float, float, float]] = field(default_factory=list)
    r_min: float = math.nan
    r_max: float = math.nan
    level: str = ""
    scenario: str = ""
    body_t: FloatArray = field(default_factory=lambda: np.zeros(0))
    x: FloatArray = field(default_factory=lambda: np.zeros((0, 0)))
    """(samples, particles)"""
    y: FloatArray = field(default_factory=lambda: np.zeros((0, 0)))
    r: FloatArray = field(default_factory=lambda: np.zeros((0, 0)))
    radius_t: FloatArray = field(default_factory=lambda: np.zeros(0))
    commanded: FloatArray = field(default_factory=lambda: np.zeros((0, 0)))
    """(samples, particles): commanded radius."""

    @property
    def centroid(self) -> tuple[FloatArray, FloatArray]:
        """Mean of the particle centres at each body sample (m)."""
        return self.x.mean(axis=1), self.y.mean(axis=1)


class WorldRecordError(ParticlebotError, ValueError):
    """World records that do not fit together (a damaged log)."""


def _numbers(record: Record, key: str, count: int | None) -> list[float]:
    values = record.get(key)
    if not isinstance(values, list) or not all(
        isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v) for v in values
    ):
        raise WorldRecordError(f"'{key}' of a {record.get('kind')} record must be numbers")
    if count is not None and len(values) != count:
        raise WorldRecordError(
            f"a {record.get('kind')} record has {len(values)} values of '{key}' for {count} "
            "particles"
        )
    return [float(v) for v in values]


def read_world(records: Iterable[Record]) -> WorldTrack | None:
    """The world track of a log's records (None when it has no scene: a real radio's log).
    WorldRecordError for records that contradict the scene."""
    track: WorldTrack | None = None
    body_t: list[float] = []
    xs: list[list[float]] = []
    ys: list[list[float]] = []
    rs: list[list[float]] = []
    radius_t: list[float] = []
    commanded: list[list[float]] = []
    for record in records:
        kind = record.get("kind")
        if kind not in KINDS:
            continue
        t = record.get("t")
        if not isinstance(t, int | float) or isinstance(t, bool) or not math.isfinite(t):
            raise WorldRecordError(f"a {kind} record without a time")
        if kind == SCENE:
            if track is not None:
                continue  # one scene per session
            ids = record.get("ids")
            if not isinstance(ids, list) or not all(isinstance(i, int) for i in ids):
                raise WorldRecordError("the scene record's 'ids' must be whole numbers")
            lamp = _numbers(record, "lamp", 3)
            track = WorldTrack(
                ids=ids,
                lamp=(lamp[0], lamp[1], lamp[2]),
                rects=[_box(v, 4) for v in record.get("rects", [])],
                circles=[_box(v, 3) for v in record.get("circles", [])],
                objects=[_box(v, 3) for v in record.get("objects", [])],
                r_min=float(record.get("r_min", math.nan)),
                r_max=float(record.get("r_max", math.nan)),
                level=str(record.get("level", "")),
                scenario=str(record.get("scenario", "")),
            )
            continue
        if track is None:
            raise WorldRecordError(f"a {kind} record before the scene record")
        count = len(track.ids)
        if kind == BODIES:
            body_t.append(float(t))
            xs.append(_numbers(record, "x", count))
            ys.append(_numbers(record, "y", count))
            rs.append(_numbers(record, "r", count))
        else:
            radius_t.append(float(t))
            commanded.append(_numbers(record, "r", count))
    if track is None:
        return None
    count = len(track.ids)
    track.body_t = np.array(body_t)
    track.x = np.array(xs).reshape(len(xs), count)
    track.y = np.array(ys).reshape(len(ys), count)
    track.r = np.array(rs).reshape(len(rs), count)
    track.radius_t = np.array(radius_t)
    track.commanded = np.array(commanded).reshape(len(commanded), count)
    return track


def _box(values: Any, size: int) -> Any:
    if (
        not isinstance(values, list)
        or len(values) != size
        or not all(isinstance(v, int | float) and math.isfinite(v) for v in values)
    ):
        raise WorldRecordError(f"an obstacle of the scene must be {size} numbers")
    return tuple(float(v) for v in values)
