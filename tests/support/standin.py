"""A cheap, deterministic stand-in for the simulator behind the Runner interface of studies."""

from __future__ import annotations

import math
import os
import time
import zlib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from particlebot.studies.packing import densest_packing_diameter_m
from particlebot.studies.published import R_MIN_M
from particlebot.studies.spec import RunSpec, ShareDone, SimOutcome, Track


@dataclass(frozen=True)
class StandInRunner:
    """Pretends to simulate: a made-up but smooth function of the spec and its seed (speed falls
    with size, dead fraction and noise; narrow gaps hold the swarm back), with the outcome's
    shape the real simulator gives. Its numbers mean nothing about particle robots.

    For the engine's tests it can also misbehave on purpose: crash_once names runs whose first
    attempt kills the worker process (os._exit) and leaves a marker in marker_dir, so the retry
    finds it and runs normally; raise_for names runs that raise every time; delay_s makes every
    run take that long; warm_dir receives one file per process that warmed up, and warm_up_fails
    makes warming up raise (a worker without the simulator, say). hold_after N with ticket_dir
    lets the first N runs (in the order they start, across processes) finish and holds every
    later one until the file ticket_dir/"go" exists: a test can interrupt a study that cannot
    have finished, however slow the machine. reports_share: before its delay or hold, a run
    tells its progress it is this far.
    """

    crash_once: frozenset[str] = field(default_factory=frozenset)
    raise_for: frozenset[str] = field(default_factory=frozenset)
    marker_dir: Path | None = None
    delay_s: float = 0.0
    warm_dir: Path | None = None
    warm_up_fails: bool = False
    hold_after: int | None = None
    ticket_dir: Path | None = None
    reports_share: float | None = None

    @property
    def name(self) -> str:
        return "stand-in"

    def warm_up(self) -> None:
        if self.warm_up_fails:
            raise ImportError("no simulator here (the stand-in pretends)")
        if self.warm_dir is not None:
            (self.warm_dir / str(os.getpid())).touch()

    def __call__(self, spec: RunSpec, progress: ShareDone | None = None) -> SimOutcome:
        if spec.run_id in self.crash_once and self.marker_dir is not None:
            marker = self.marker_dir / f"{spec.run_id}.crashed"
            if not marker.exists():
                marker.write_text(str(os.getpid()))
                os._exit(70)  # a worker dying mid-run, as an out-of-memory kill would
        if spec.run_id in self.raise_for:
            raise RuntimeError(f"the stand-in fails {spec.run_id} on purpose")
        if self.reports_share is not None and progress is not None:
            progress(self.reports_share)
        if self.delay_s > 0:
            time.sleep(self.delay_s)
        if self.hold_after is not None and self.ticket_dir is not None:
            _hold_beyond(self.hold_after, self.ticket_dir)
        return _pretend(spec)


def _hold_beyond(allowed: int, folder: Path) -> None:
    """Returns at once for the first `allowed` callers; later ones wait for folder/"go"."""
    if _take_ticket(folder) >= allowed:
        while not (folder / "go").exists():
            time.sleep(0.05)  # held until the test lets go, or the worker is stopped


def _take_ticket(folder: Path) -> int:
    """The next number not yet taken in folder (atomic across processes: O_EXCL)."""
    number = 0
    while True:
        try:
            os.close(os.open(folder / f"ticket-{number}", os.O_CREAT | os.O_EXCL | os.O_WRONLY))
        except FileExistsError:
            number += 1
        else:
            return number


def _pretend(spec: RunSpec) -> SimOutcome:
    setup = spec.setup
    rng = np.random.default_rng(zlib.crc32(spec.run_id.encode()))
    n = setup.particles
    alive = 1.0 - setup.dead / n
    speed = 1.3e-3 * n**-0.2 * max(0.0, alive - 0.3) / 0.7 * max(0.0, 1 - setup.noise_diameters / 2)
    speed *= 1 + rng.normal(0.0, 0.3 / math.sqrt(n))
    dpd = densest_packing_diameter_m(n)
    travel = speed * setup.duration_s
    if setup.rects:  # a wall with a gap: a gap narrower than the swarm holds part of it back
        gap = min(r.y_min for r in setup.rects if r.y_min > 0) * 2
        travel = min(travel, setup.rects[0].x_max + dpd * min(1.0, gap / dpd + rng.normal(0, 0.05)))
    time_s = np.arange(0.0, setup.duration_s + 1e-9, setup.dump_interval_s)
    progress = time_s / setup.duration_s * travel
    cx = progress + rng.normal(0.0, 0.002, len(time_s))
    cy = rng.normal(0.0, 0.002, len(time_s))
    distance = np.hypot(setup.lamp_x - cx, setup.lamp_y - cy)
    bodies = n + setup.free_particles
    angle = rng.uniform(0.0, 2 * math.pi, bodies)
    radius = dpd / 2 * np.sqrt(rng.uniform(0.0, 1.0, bodies))
    final_xy = np.stack([cx[-1] + radius * np.cos(angle), cy[-1] + radius * np.sin(angle)], axis=1)
    obj = setup.passive_object
    start = None if obj is None else (obj.x, obj.y)
    end = None
    if obj is not None:
        pushed = travel if n >= 1000 else 0.0
        end = (obj.x + pushed, obj.y)
        final_xy[0] = (end[0] - obj.radius_factor * R_MIN_M - 0.1, end[1])
    return SimOutcome(
        track=Track(time_s, cx, cy, distance),
        final_xy=final_xy,
        object_start=start,
        object_end=end,
        summary={"steps": float(round(setup.duration_s / 0.01)), "wall_s": 0.0},
    )
