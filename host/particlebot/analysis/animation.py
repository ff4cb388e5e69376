"""A session log of a simulated radio as a film of its top view: the world's truth it recorded
(bodies twice a second, commanded radii ten times) drawn as the simulator draws its runs
(particlebot.sim.runs: phase colours, the lamp, obstacles) and encoded by ffmpeg."""

from __future__ import annotations

import tempfile
from collections.abc import Callable
from functools import partial
from pathlib import Path

import numpy as np

from particlebot.errors import ParticlebotError
from particlebot.plots import PlotInputError, read_records
from particlebot.sim.runs.pictures import Frame, View
from particlebot.sim.runs.video import VideoError, encode, write_frame
from particlebot.sim.swarm.records import WorldRecordError, WorldTrack, read_world
from particlebot.sim.world.arena import Arena, Circle, Rect

FRAME_EVERY_S = 2.0
"""A frame every 2 s of simulated time: 10 s of film per 100 s of run at 5 frames a second."""
FPS = 5
CYCLING_M = 0.0005
"""A commanded radius this far above the contracted one is a cycle under way."""


class AnimationError(ParticlebotError, RuntimeError):
    """The log holds no world to film, or ffmpeg failed; said in one line."""


def phases(track: WorldTrack, at: float) -> np.ndarray:
    """Each particle's place in its cycle at time `at` (0..1; NaN when resting), from the
    commanded radii: the fraction of its current expansion-contraction already done."""
    t, radii = track.radius_t, track.commanded
    out = np.full(len(track.ids), np.nan)
    if len(t) < 2:
        return out
    now = int(np.searchsorted(t, at, side="right")) - 1
    if now < 0:
        return out
    moving = radii > track.r_min + CYCLING_M
    for column in range(len(track.ids)):
        if not moving[now, column]:
            continue
        start = now
        while start > 0 and moving[start - 1, column]:
            start -= 1
        end = now
        while end + 1 < len(t) and moving[end + 1, column]:
            end += 1
        length = max(t[end] - t[start], 1e-9)
        out[column] = float(np.clip((at - t[start]) / length, 0.0, 1.0))
    return out


def write_animation(
    log: Path,
    output: Path,
    every_s: float = FRAME_EVERY_S,
    progress: Callable[[str, int, int], None] | None = None,
) -> Path:
    """Films the log's world into output (.mp4 or .gif); progress(stage, done, total) while the
    frames are drawn (stage "drawing") and while they are encoded ("encoding")."""
    try:
        track = read_world(read_records(log).records)
    except (PlotInputError, WorldRecordError) as exc:
        raise AnimationError(str(exc)) from None
    if track is None or len(track.body_t) < 2:
        raise AnimationError(f"{log.name} holds no world to film (a simulated radio's log does)")
    t = track.body_t
    times = np.arange(t[0], t[-1] + 1e-9, every_s)
    count = len(track.ids)
    arena = Arena(
        rects=tuple(Rect(*r) for r in track.rects),
        circles=tuple(Circle(*c) for c in track.circles),
    )
    objects = np.array([[o[0], o[1], 0.0, 0.0, o[2]] for o in track.objects]).reshape(-1, 5)
    first = _frame(track, 0, t[0], objects, count)
    view = View.around(
        _union(track, objects, count), (track.lamp[0], track.lamp[1]), arena, log.stem
    )
    with tempfile.TemporaryDirectory(prefix="particlebot-film-") as scratch:
        folder = Path(scratch)
        for index, at in enumerate(times):
            row = min(int(np.searchsorted(t, at)), len(t) - 1)
            frame = _frame(track, row, float(at - t[0]), objects, count) if index else first
            frame = Frame(
                frame.t, frame.x, frame.y, frame.radius, phases(track, float(at)), frame.alive,
                frame.loose, frame.objects,
            )  # fmt: skip
            write_frame(folder, index, frame, view)
            if progress is not None:
                progress("drawing", index + 1, len(times))
        encoded = None if progress is None else partial(progress, "encoding")
        try:
            return encode(folder, output, FPS, progress=encoded)
        except VideoError as exc:
            raise AnimationError(str(exc)) from None


def _frame(track: WorldTrack, row: int, t: float, objects: np.ndarray, count: int) -> Frame:
    return Frame(
        t=t,
        x=track.x[row],
        y=track.y[row],
        radius=track.r[row],
        phase=np.full(count, np.nan),
        alive=np.ones(count, dtype=np.bool_),
        loose=np.zeros(count, dtype=np.bool_),
        objects=objects,
    )


def _union(track: WorldTrack, objects: np.ndarray, count: int) -> Frame:
    """One frame holding every place a body ever was, so the view frames the whole run."""
    return Frame(
        t=0.0,
        x=track.x.ravel(),
        y=track.y.ravel(),
        radius=track.r.ravel(),
        phase=np.full(track.x.size, np.nan),
        alive=np.ones(track.x.size, dtype=np.bool_),
        loose=np.zeros(track.x.size, dtype=np.bool_),
        objects=objects,
    )
