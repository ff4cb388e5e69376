"""The World: a swarm of discs, its arena, lamp and passive objects, stepped by compiled kernels."""

from __future__ import annotations

import copy
import math
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal

import numba
import numpy as np
import numpy.typing as npt

from particlebot.sim.particles.model.controller import (
    BoolArray,
    Controller,
    CycleCommands,
    FloatArray,
)
from particlebot.sim.world import kernels as k
from particlebot.sim.world.arena import Arena
from particlebot.sim.world.bodies import BodyState, DeadParticles, PassiveObject
from particlebot.sim.world.light import Lamp, LightField, ShadowMode
from particlebot.sim.world.params import NeighbourSearch, PhysicsParams
from particlebot.sim.world.snapshot import Snapshot
from particlebot.sim.world.threads import ThreadGovernor

if TYPE_CHECKING:
    from particlebot.sim.world.cuda.swarms import DeviceSwarms

Precision = Literal["float64", "float32"]
Observer = Callable[["World"], None]

PARALLEL_FROM = 2048
"""Swarms from this size up step in parallel chunks; smaller ones in one inline chunk (a parallel
region costs microseconds to start, more than a small swarm's whole step)."""
CHUNKS = 16
"""Chunks of a parallel step. Fixed, not the thread count, so that results (the passive objects'
force sums, added chunk by chunk) do not depend on the machine."""
TARGET_BUDGET = 1 << 16
"""Commanded radii buffered ahead (floats): ~6,500 steps of 10 particles per compiled call."""
TARGET_BUDGET_CUDA = 1 << 22
"""The same on the GPU (32 MB): a block of steps is one upload of commands and then only kernel
launches, so the longer the better (400 steps of a 10,000-particle swarm)."""
TOUCH_GAP = 0.9e-3
"""A free particle joins the robot when its gap to a member closes below this (m): the magnets'
clamp gap, where they lock."""


@contextmanager
def _numba_threads(threads: int) -> Iterator[None]:
    """numba's thread count for this (calling) thread set to `threads` for a block."""
    previous = numba.get_num_threads()
    if previous == threads:
        yield
        return
    numba.set_num_threads(threads)
    try:
        yield
    finally:
        numba.set_num_threads(previous)


@dataclass
class _Observation:
    callback: Observer
    every: int


class World:
    """A 2-D world of disc-shaped particles, run by a vectorised controller.

    Particles start at rest (or with `velocity`: vx, vy arrays, as a published CSV resumes),
    contracted (or with `radius`). Particles keep the index the caller gave them (x[i], y[i]) in
    everything the World shows; internally the kernels keep them sorted by space. Time advances
    in steps of params.dt with step(n); observers added with add_observer() are called every so
    many steps (outputs live there, never in the loop). The published model's order within a
    step: dead particles are chosen when their time comes; the controller commands radii; the
    servo moves them (stall limit); positions advance by the old velocities and walls reflect;
    forces from the new positions and old velocities (contacts, magnets, obstacles, passive
    objects); velocities with ground friction; t += dt.

    device: "cpu" (the compiled CPU kernels), "cuda" (the GPU: particlebot.sim.world.cuda,
    which says what runs where and what differs) or "auto" (CUDA when a real GPU is present).
    """

    _nbr: npt.NDArray[np.int32]
    _ncount: npt.NDArray[np.int32]

    def __init__(
        self,
        x: npt.ArrayLike,
        y: npt.ArrayLike,
        *,
        controller: Controller,
        params: PhysicsParams | None = None,
        arena: Arena | None = None,
        lamp: Lamp | None = None,
        shadow: ShadowMode = ShadowMode.IGNORE,
        objects: Sequence[PassiveObject] = (),
        free: npt.ArrayLike | None = None,
        dead: DeadParticles | None = None,
        radius: npt.ArrayLike | None = None,
        velocity: tuple[npt.ArrayLike, npt.ArrayLike] | None = None,
        seed: int = 0,
        precision: Precision = "float64",
        device: str = "cpu",
    ) -> None:
        self.params = params if params is not None else PhysicsParams()
        self.arena = arena if arena is not None else Arena()
        self.lamp = lamp if lamp is not None else Lamp()
        self.shadow = ShadowMode(shadow)
        self.objects = tuple(objects)
        self.dead = dead if dead is not None else DeadParticles()
        self.seed = seed
        self.precision: Precision = precision
        self.controller = controller
        xs = np.array(x, dtype=np.float64).ravel()
        ys = np.array(y, dtype=np.float64).ravel()
        n = xs.shape[0]
        if n < 1 or ys.shape != xs.shape:
            raise ValueError("x and y must give at least one particle, as many x as y")
        radii = (
            np.full(n, self.params.r_min)
            if radius is None
            else np.array(radius, dtype=np.float64).ravel()
        )
        free_mask = (
            np.zeros(n, dtype=np.bool_) if free is None else np.array(free, dtype=np.bool_).ravel()
        )
        self._check_setup(xs, ys, radii, free_mask)
        ftype = np.dtype(precision)
        self._pos = np.stack([xs, ys])
        self._ref = self._pos.copy()
        self._vel = np.zeros((2, n), dtype=ftype)
        if velocity is not None:
            vx = np.array(velocity[0], dtype=np.float64).ravel()
            vy = np.array(velocity[1], dtype=np.float64).ravel()
            finite = bool(np.isfinite(vx).all() and np.isfinite(vy).all())
            if vx.shape != (n,) or vy.shape != (n,) or not finite:
                raise ValueError("velocity must give finite vx and vy for every particle")
            self._vel[0] = vx
            self._vel[1] = vy
        self._body = np.zeros((k.BODY_ROWS, n), dtype=ftype)
        self._body[k.B_R] = radii
        self._body[k.B_MAG] = 1.0
        self._flags = np.zeros((k.FLAG_ROWS, n), dtype=np.uint8)
        self._flags[k.F_KIND] = np.where(free_mask, k.FREE, k.MEMBER)
        self._flags[k.F_ALIVE] = 1
        self._ext = np.arange(n, dtype=np.int64)
        self._objects = np.zeros((len(self.objects), k.OBJECT_COLS))
        for m, o in enumerate(self.objects):
            self._objects[m, [k.O_X, k.O_Y, k.O_R]] = (o.x, o.y, o.radius)
            self._objects[m, k.O_INV_MASS] = 1.0 / o.mass_factor
            slide = self.params.mu * o.friction_factor * self.params.gravity * o.mass_factor
            self._objects[m, k.O_FRICTION] = slide
            self._objects[m, k.O_STATIC] = self.params.static_factor * slide
            self._objects[m, k.O_MAG] = o.attraction_factor
        sequence = np.random.SeedSequence(seed)
        world_seed, controller_seed = sequence.spawn(2)
        self._rng = np.random.default_rng(world_seed)
        self._steps = 0
        self._dead_done = self.dead.count == 0
        self._setup_derived(n)
        self._nbr = k.build_lists(
            self._pos, self._ref, self._vel, self._body, self._flags, self._ext,
            self._nbr, self._ncount, self._bounds, self._prm, True, self.threads,
        )  # fmt: skip
        self._gpu: DeviceSwarms | None = None
        self._cycle: CycleCommands | None = None  # the GPU's commands for this block, if any
        self._refresh_shadows()
        controller.bind(n, np.random.default_rng(controller_seed))
        self._place_on(device)

    # ---- construction helpers ----------------------------------------------------------------

    def _check_setup(
        self, xs: FloatArray, ys: FloatArray, radii: FloatArray, free: BoolArray
    ) -> None:
        p = self.params
        n = xs.shape[0]
        if radii.shape != (n,) or free.shape != (n,):
            raise ValueError("radius and free must have one entry per particle")
        if not (np.all(np.isfinite(xs)) and np.all(np.isfinite(ys))):
            raise ValueError("particle positions must be finite")
        if np.any(radii < p.r_min) or np.any(radii > p.r_max) or not np.all(np.isfinite(radii)):
            raise ValueError(f"radii must lie in [{p.r_min}, {p.r_max}] m")
        if np.any(np.abs(xs) > p.half_width - radii) or np.any(np.abs(ys) > p.half_width - radii):
            raise ValueError(f"particles must lie inside the walls at +-{p.half_width} m")
        inside = self.arena.overlapping(xs, ys, radii)
        if inside.any():
            first = int(np.flatnonzero(inside)[0])
            raise ValueError(
                f"{int(inside.sum())} particle(s) cut into an obstacle (particle {first} at "
                f"{xs[first]:.3f}, {ys[first]:.3f})"
            )
        for m, o in enumerate(self.objects):
            if self.arena.overlapping(np.array([o.x]), np.array([o.y]), np.array([o.radius]))[0]:
                raise ValueError(f"passive object {m} cuts into an obstacle")
            if max(abs(o.x), abs(o.y)) > p.half_width - o.radius:
                raise ValueError(f"passive object {m} must lie inside the walls")
        robot = int(np.count_nonzero(~free))
        if self.dead.count > robot:
            raise ValueError(f"{self.dead.count} dead particles of a robot of {robot}")

    def _setup_derived(self, n: int) -> None:
        """Kernel inputs that follow from the setup (rebuilt on restore)."""
        p = self.params
        chunks = 1 if n < PARALLEL_FROM else CHUNKS
        self._bounds = np.linspace(0, n, chunks + 1).astype(np.int64)
        self.thread_count: int | None = getattr(self, "thread_count", None)
        """Threads for the parallel step, or None: chosen from measured step times (threads.py)."""
        self._governor: ThreadGovernor | None = None
        self._used_threads: int | None = None
        self._acc = np.zeros((chunks, len(self.objects), k.ACC_COLS))
        self._pair_index = np.zeros((chunks, k.PAIR_INDEX_ROWS, 2 * k.PAIR_BLOCK), dtype=np.int64)
        self._pair_values = np.zeros((chunks, k.PAIR_VALUE_ROWS, k.PAIR_BLOCK))
        self._rects = self.arena.rect_array()
        self._circles = self.arena.circle_array()
        self._light = LightField(self.lamp)
        prm = np.zeros(k.PARAM_COUNT)
        prm[k.P_DT] = p.dt
        prm[k.P_RMIN] = p.r_min
        prm[k.P_RMAX] = p.r_max
        prm[k.P_SPRING] = p.spring
        prm[k.P_DAMPING] = p.damping
        prm[k.P_SHEAR] = p.shear
        prm[k.P_OBSTACLE_SPRING] = p.obstacle_spring_factor
        prm[k.P_ATTRACTION] = p.attraction
        prm[k.P_CLAMP_FORCE] = p.magnet_clamp_force
        prm[k.P_CLAMP_GAP] = p.clamp_gap
        prm[k.P_BLEND_GAP] = p.blend_gap
        prm[k.P_CUTOFF] = p.magnet_cutoff
        prm[k.P_FRICTION] = p.mu * p.gravity
        prm[k.P_STATIC] = p.static_force
        prm[k.P_REST_SPEED] = p.rest_speed
        prm[k.P_MAX_SPEED] = p.max_speed
        prm[k.P_TORQUE] = p.torque_limit
        prm[k.P_CONSTRAINED] = float(p.constrain_contraction)
        prm[k.P_CONTRACTION] = p.contraction_coefficient
        prm[k.P_HALF_WIDTH] = p.half_width
        prm[k.P_SKIN] = p.skin
        prm[k.P_LIST_RADIUS] = p.list_radius
        prm[k.P_TOUCH_GAP] = TOUCH_GAP
        self._prm = prm
        # Room for hexagonally packed contracted discs within the list radius, and some more;
        # build_lists widens it if ever needed.
        width = int(math.pi * (p.list_radius + p.r_min) ** 2 / (2 * math.sqrt(3) * p.r_min**2))
        self._nbr = np.zeros((n, max(width, 8)), dtype=np.int32)
        self._ncount = np.zeros(n, dtype=np.int32)
        self._listed = True  # whether _nbr holds the last build's lists (see kernels.advance)
        self._unsorted = 0  # list builds since the particles were last put in cell order (same)
        rows = max(1, min(TARGET_BUDGET // n, 8192))
        self._targets = np.full((rows, n), np.nan)
        self._observers: list[_Observation] = []
        self._view = _View(self)
        self.rebuilds = 0
        # The published code's search (PUBLISHED_STALE_GRID): each particle's listed cell, and
        # the listing cell by cell; listed at the first step (t = 0) and every sort_interval.
        self._stale = p.neighbour_search == NeighbourSearch.PUBLISHED_STALE_GRID
        self._stale_hashes = np.zeros(n if self._stale else 0, dtype=np.int64)
        self._stale_members = np.arange(n if self._stale else 0, dtype=np.int64)
        self._stale_start = np.zeros(k.STALE_GRID**2 + 1 if self._stale else 1, dtype=np.int64)

    def _place_on(self, device: str) -> None:
        """Puts the world on its device: on "cuda", its state goes to the GPU (DeviceError when
        there is none, or for what the GPU backend has not got)."""
        from particlebot.sim.world.cuda.device import DeviceError, resolve

        self.device = resolve(device)
        self._gpu_index = 0
        if self.device == "cpu":
            return
        if self._stale:
            raise DeviceError("the published stale grid (neighbour_search) runs on the CPU only")
        from particlebot.sim.world.cuda.swarms import DeviceSwarms

        rows = max(1, min(TARGET_BUDGET_CUDA // self.count, 8192))
        self._targets = np.full((rows, self.count), np.nan)
        self._gpu = DeviceSwarms([self])

    def _host(self) -> None:
        """Brings the host arrays up to date with the GPU (a CUDA world: the device state moves
        on between reads, and is copied back only when something reads it)."""
        if self._gpu is not None:
            self._gpu.pull(self._gpu_index)

    def _changed(self) -> None:
        """The host changed the state: a CUDA world copies it to the GPU before stepping on."""
        if self._gpu is not None:
            self._gpu.dirty[self._gpu_index] = True

    # ---- what the world is now ---------------------------------------------------------------

    @property
    def count(self) -> int:
        """Particles (passive objects are not particles)."""
        return int(self._pos.shape[1])

    @property
    def threads(self) -> int:
        """Threads this world's last step ran on (1 for a swarm below PARALLEL_FROM); before
        any, what the next would start on."""
        if self._bounds.shape[0] == 2:
            return 1
        if self._used_threads is not None:
            return self._used_threads
        return self.thread_count or numba.get_num_threads()

    def _threads_for_call(self) -> tuple[int, bool]:
        """Threads for the next compiled step call: 1 for a small swarm; thread_count when set;
        the caller's numba.set_num_threads when it lowered numba's count; otherwise the faster
        of one thread and all of numba's, as measured on this machine now (threads.py). And
        whether that last, measured choice made it."""
        if self._bounds.shape[0] == 2:
            return 1, False
        most: int = numba.config.NUMBA_NUM_THREADS  # type: ignore[attr-defined]  # set at import
        if self.thread_count is not None:
            return max(1, min(self.thread_count, most)), False
        current = numba.get_num_threads()
        if current < most:
            return current, False
        if self._governor is None:
            self._governor = ThreadGovernor(most)
        return self._governor.choose(), True

    @property
    def steps(self) -> int:
        """Steps taken since the run began."""
        return self._steps

    @property
    def t(self) -> float:
        """Simulated seconds since the run began (steps x dt)."""
        return self._steps * self.params.dt

    @property
    def view(self) -> _View:
        """What a controller senses now (the WorldView contract)."""
        return self._view

    def positions(self) -> tuple[FloatArray, FloatArray]:
        """Particle centres x, y (m), in the caller's order (copies)."""
        return self._external(self._pos[0]), self._external(self._pos[1])

    def radii(self) -> FloatArray:
        """Particle radii (m), in the caller's order."""
        return self._external(self._body[k.B_R])

    def state(self) -> BodyState:
        """Every body now, in the caller's order (copies)."""
        kind = self._external(self._flags[k.F_KIND])
        return BodyState(
            t=self.t,
            x=self._external(self._pos[0]),
            y=self._external(self._pos[1]),
            vx=self._external(self._vel[0]),
            vy=self._external(self._vel[1]),
            radius=self._external(self._body[k.B_R]),
            alive=self._external(self._flags[k.F_ALIVE]).astype(np.bool_),
            member=kind == k.MEMBER,
            free=kind == k.FREE,
            acting=self._external(self._flags[k.F_ACTING]).astype(np.bool_),
            objects=self._objects[:, [k.O_X, k.O_Y, k.O_VX, k.O_VY, k.O_R]].copy(),
        )

    def finite(self) -> bool:
        """Whether every position, velocity and radius is a finite number. Not checked inside
        the step loop (it costs a pass over the swarm); a caller checks it now and then, and
        stops a world that has blown up before a NaN reaches the grid's cell arithmetic."""
        return bool(
            np.isfinite(self._pos).all()
            and np.isfinite(self._vel).all()
            and np.isfinite(self._body[k.B_R]).all()
        )

    def centroid(self, members_only: bool = False) -> tuple[float, float]:
        """Mean centre of every body, passive objects included, as the published CSV has it;
        members_only: of the robot's particles alone (no free, detached or object bodies)."""
        self._host()
        if members_only:
            members = self._flags[k.F_KIND] == k.MEMBER
            return float(self._pos[0, members].mean()), float(self._pos[1, members].mean())
        total = self.count + len(self.objects)
        cx = (self._pos[0].sum() + self._objects[:, k.O_X].sum()) / total
        cy = (self._pos[1].sum() + self._objects[:, k.O_Y].sum()) / total
        return float(cx), float(cy)

    def light_distance(self, members_only: bool = False) -> float:
        """Ground distance (m) from the centroid to the lamp's foot (the published Distance)."""
        cx, cy = self.centroid(members_only)
        return math.hypot(cx - self.lamp.x, cy - self.lamp.y)

    def phase(self) -> FloatArray:
        """Each particle's place in its cycle (0..1, NaN when not cycling), for pictures."""
        return self.controller.phase(self._view)

    # ---- running -------------------------------------------------------------------------------

    def add_observer(self, callback: Observer, every: int) -> Observer:
        """Calls callback(world) after every `every`-th step (counted from the run's start);
        returns it for remove_observer()."""
        if every < 1:
            raise ValueError("an observer's interval must be at least one step")
        self._observers.append(_Observation(callback, every))
        return callback

    def remove_observer(self, callback: Observer) -> None:
        self._observers = [o for o in self._observers if o.callback is not callback]

    def run(self, seconds: float) -> None:
        """Steps the world for `seconds` of simulated time (rounded to whole steps)."""
        self.step(round(seconds / self.params.dt))

    def step(self, n: int = 1) -> None:
        """Advances n steps, in as few compiled calls as the controller and observers allow."""
        if self._gpu is not None and self._gpu.swarms > 1:
            raise RuntimeError("this world is one of an ensemble's: step the Ensemble")
        end = self._steps + n
        while self._steps < end:
            threads, governed = (
                (1, False) if self._stale or self._gpu is not None else self._threads_for_call()
            )
            # A try of the other thread count is kept short (threads.py, TRIAL_S).
            cap = self._governor.steps_cap() if governed and self._governor is not None else None
            rows = self._begin_block(end, cap)
            if self._gpu is not None:
                self._gpu.advance(rows, self._targets, (self._cycle,))
                rebuilds = rows  # (the GPU bins the particles afresh at every step)
            elif self._stale:
                rebuilds = k.advance_stale(
                    rows, self._steps, max(1, round(self.params.sort_interval / self.params.dt)),
                    self._targets, self._ext, self._pos, self._ref, self._vel, self._body,
                    self._flags, self._rects, self._circles, self._objects, self._acc,
                    self._stale_hashes, self._stale_members, self._stale_start,
                    -self.params.half_width, 2 * self.params.r_max, self._prm,
                )  # fmt: skip
            else:
                began = time.perf_counter()
                with _numba_threads(threads):
                    self._nbr, self._listed, self._unsorted, rebuilds = k.advance(
                        rows, self._targets, self._ext, self._pos, self._ref, self._vel,
                        self._body, self._flags, self._nbr, self._ncount, self._listed,
                        self._unsorted, self._rects, self._circles, self._objects, self._acc,
                        self._bounds, self._pair_index, self._pair_values, self._prm, threads,
                    )  # fmt: skip
                self._used_threads = threads
                if governed and self._governor is not None:
                    self._governor.record(threads, rows, time.perf_counter() - began)
            self._end_block(rows, rebuilds)

    def _begin_block(self, end: int, cap: int | None = None) -> int:
        """Kills the dead when due and commands the next block of steps (before `end`, and at
        most `cap` when given); returns how many steps the targets buffer holds."""
        if not self._dead_done and self._steps >= self._dead_step():
            self._kill()
        block = end - self._steps
        for o in self._observers:
            block = min(block, o.every - self._steps % o.every)
        if not self._dead_done:
            block = min(block, max(self._dead_step() - self._steps, 1))
        if cap:
            block = min(block, cap)
        return self._command(block)

    def _end_block(self, rows: int, rebuilds: int) -> None:
        """Counts a block of `rows` steps done and calls the observers that are due."""
        self.rebuilds += rebuilds
        self._steps += rows
        self._view.invalidate()
        for o in list(self._observers):
            if self._steps % o.every == 0:
                o.callback(self)

    def _command(self, block: int) -> int:
        """Fills the targets buffer for up to `block` steps; returns how many rows it holds. On
        the GPU, a controller that can (cycle_ahead) leaves the commands to the GPU instead."""
        if self._gpu is not None:
            self._cycle = self.controller.cycle_ahead(self._view, self.params.dt, block)
            if self._cycle is not None:
                return min(self._cycle.rows, block)
        rows = min(block, self._targets.shape[0])
        done = self.controller.command_ahead(self._view, self.params.dt, self._targets[:rows])
        if done <= 0:
            self.controller.command(self._view, self._targets[0])
            done = 1
        return min(done, rows)

    def place(self, index: int, x: float, y: float) -> None:
        """Puts particle `index` at (x, y) at rest, as a hand puts it down (calibration moves
        simulated particles this way). ValueError, and nothing moved, for a place outside the
        walls or inside an obstacle; overlapping other particles is the caller's business (the
        contact forces push them apart on the next step)."""
        if not 0 <= index < self.count:
            raise ValueError(f"no particle {index} (0..{self.count - 1})")
        if not (math.isfinite(x) and math.isfinite(y)):
            raise ValueError("a particle's place must be finite")
        self._host()
        slot = int(self._internal_slots(np.array([index]))[0])
        radius = float(self._body[k.B_R, slot])
        limit = self.params.half_width - radius
        if abs(x) > limit or abs(y) > limit:
            raise ValueError(f"particles must lie inside the walls at +-{self.params.half_width} m")
        if self.arena.overlapping(np.array([x]), np.array([y]), np.array([radius]))[0]:
            raise ValueError(f"({x:.3f}, {y:.3f}) cuts into an obstacle")
        self._pos[:, slot] = (x, y)
        self._vel[:, slot] = 0.0
        self._nbr = k.build_lists(
            self._pos, self._ref, self._vel, self._body, self._flags, self._ext,
            self._nbr, self._ncount, self._bounds, self._prm, True, self.threads,
        )  # fmt: skip
        self._listed = True
        self._unsorted = 0
        if self._stale:
            # The rebuild re-ordered the particles the listing refers to: list them again.
            k.stale_list(
                self._pos, -self.params.half_width, 2 * self.params.r_max, self._stale_hashes,
                self._stale_members, self._stale_start,
            )  # fmt: skip
        self._changed()
        self._view.invalidate()

    def _dead_step(self) -> int:
        return math.ceil(self.dead.at_s / self.params.dt - 1e-9)

    def _kill(self) -> None:
        """Chooses the dead particles (from the run's seed, among the robot's living members) and
        stops them; detached ones lose their magnets and leave the robot."""
        self._dead_done = True
        self._host()
        flags = self._flags
        eligible = np.flatnonzero(
            self._external(flags[k.F_ALIVE]).astype(np.bool_)
            & (self._external(flags[k.F_KIND]) == k.MEMBER)
        )
        chosen = self._rng.choice(eligible, min(self.dead.count, eligible.size), replace=False)
        slots = self._internal_slots(chosen)
        flags[k.F_ALIVE, slots] = 0
        flags[k.F_ACTING, slots] = 0
        if self.dead.detach:
            flags[k.F_KIND, slots] = k.DETACHED
            self._body[k.B_MAG, slots] = 0.0
        self._changed()
        self._view.invalidate()

    def _refresh_shadows(self) -> BoolArray:
        """Which particles the obstacles shadow now (caller's order); under mode STILL they are
        held, and particles that came out of the shadow may actuate again."""
        self._host()
        shadowed = np.zeros(self.count, dtype=np.bool_)
        if self.shadow != ShadowMode.IGNORE and (self.arena.rects or self.arena.circles):
            x, y = self.positions()
            shadowed = self.arena.shadowed(x, y, self.lamp.x, self.lamp.y)
        flags = self._flags
        if self.shadow == ShadowMode.STILL:
            flags[k.F_HELD] = shadowed[self._ext]
        flags[k.F_ACTING] = (
            (flags[k.F_KIND] == k.MEMBER) & (flags[k.F_ALIVE] == 1) & (flags[k.F_HELD] == 0)
        )
        self._changed()
        return shadowed

    def _external(self, row: npt.NDArray[Any]) -> npt.NDArray[Any]:
        """A per-particle row in the caller's order."""
        self._host()
        out = np.empty(row.shape, dtype=row.dtype)
        out[self._ext] = row
        return out

    def _internal_slots(self, ids: npt.NDArray[np.int64]) -> npt.NDArray[np.int64]:
        slot = np.empty_like(self._ext)
        slot[self._ext] = np.arange(self.count)
        return slot[ids]

    # ---- snapshots -----------------------------------------------------------------------------

    def snapshot(self) -> Snapshot:
        """Everything needed to continue this run exactly (observers are not included)."""
        self._host()
        setup = {
            "params": self.params,
            "arena": self.arena,
            "lamp": self.lamp,
            "shadow": int(self.shadow),
            "objects": self.objects,
            "dead": self.dead,
            "seed": self.seed,
            "precision": self.precision,
            "steps": self._steps,
            "dead_done": self._dead_done,
            "unsorted": self._unsorted,
            "rng": self._rng.bit_generator.state,
            "controller": self.controller,
        }
        arrays = {
            "pos": self._pos.copy(),
            "ref": self._ref.copy(),
            "vel": self._vel.copy(),
            "body": self._body.copy(),
            "flags": self._flags.copy(),
            "ext": self._ext.copy(),
            "objects": self._objects.copy(),
        }
        if self._stale:
            arrays["stale_hashes"] = self._stale_hashes.copy()
        return Snapshot(copy.deepcopy(setup), arrays)

    @classmethod
    def from_snapshot(cls, snapshot: Snapshot, device: str = "cpu") -> World:
        """The world a snapshot was taken of, ready to step on as if it had never stopped (on
        `device`, as World's)."""
        s = snapshot.setup
        a = snapshot.arrays
        _check_snapshot(s, a)
        world = cls.__new__(cls)
        world.params = s["params"]
        world.arena = s["arena"]
        world.lamp = s["lamp"]
        world.shadow = ShadowMode(s["shadow"])
        world.objects = s["objects"]
        world.dead = s["dead"]
        world.seed = s["seed"]
        world.precision = s["precision"]
        world.controller = s["controller"]
        world._steps = s["steps"]
        world._dead_done = s["dead_done"]
        world._rng = np.random.default_rng()
        world._rng.bit_generator.state = s["rng"]
        world._pos = a["pos"].copy()
        world._ref = a["ref"].copy()
        world._vel = a["vel"].copy()
        world._body = a["body"].copy()
        world._body[k.B_FX :] = 0.0  # (older snapshots hold the last step's forces)
        world._flags = a["flags"].copy()
        world._ext = a["ext"].copy()
        world._objects = a["objects"].copy()
        world._setup_derived(world._pos.shape[1])
        # The last build exactly as it was, from the reference positions.
        world._unsorted = s.get("unsorted", 0)
        world._nbr, world._listed = k.restore_lists(
            world._ref, world._vel, world._body, world._flags, world._ext,
            world._nbr, world._ncount, world._bounds, world._prm, world._unsorted, world.threads,
        )  # fmt: skip
        if world._stale and "stale_hashes" in a:
            world._stale_hashes = a["stale_hashes"].copy()
            k.stale_index(world._stale_hashes, world._stale_members, world._stale_start)
        world._gpu = None
        world._cycle = None
        world._place_on(device)
        return world


def _check_snapshot(setup: dict[str, Any], arrays: dict[str, npt.NDArray[Any]]) -> None:
    """ValueError, saying what, for a snapshot whose arrays do not fit one another or its set-up
    (cut short, of another type, not finite): the kernels index them without bounds checks."""
    expected = {
        "pos": (2, np.floating), "ref": (2, np.floating), "vel": (2, np.floating),
        "body": (k.BODY_ROWS, np.floating), "flags": (k.FLAG_ROWS, np.uint8),
        "ext": (None, np.int64),
    }  # fmt: skip
    missing = [name for name in (*expected, "objects") if name not in arrays]
    if missing:
        raise ValueError(f"no {', '.join(missing)} array")
    n = arrays["ext"].shape[0] if arrays["ext"].ndim == 1 else -1
    for name, (rows, kind) in expected.items():
        array = arrays[name]
        shape = (n,) if rows is None else (rows, n)
        if array.shape != shape or not np.issubdtype(array.dtype, kind):
            raise ValueError(f"{name} is {array.dtype}{list(array.shape)}, not {shape}")
        if kind is np.floating and not np.isfinite(array).all():
            raise ValueError(f"{name} holds numbers that are not finite")
    if n < 1 or not np.array_equal(np.sort(arrays["ext"]), np.arange(n)):
        raise ValueError("ext is not an order of the particles")
    objects = arrays["objects"]
    count = len(setup.get("objects", ()))
    if objects.shape != (count, k.OBJECT_COLS) or not np.isfinite(objects).all():
        raise ValueError(f"objects is {list(objects.shape)}, not {count} finite rows")
    if not isinstance(setup.get("params"), PhysicsParams):
        raise ValueError("its set-up lacks the physics")
    if not isinstance(setup.get("steps"), int) or setup["steps"] < 0:
        raise ValueError("its set-up lacks the step count")


class _View:
    """The WorldView a controller senses through, computed lazily and cached for the step."""

    def __init__(self, world: World) -> None:
        self._world = world
        self._cache: dict[str, npt.NDArray[Any]] = {}

    def invalidate(self) -> None:
        self._cache.clear()

    @property
    def count(self) -> int:
        return self._world.count

    @property
    def t(self) -> float:
        return self._world.t

    @property
    def r_min(self) -> float:
        return self._world.params.r_min

    @property
    def r_max(self) -> float:
        return self._world.params.r_max

    @property
    def x(self) -> FloatArray:
        if "x" not in self._cache:
            self._cache["x"], self._cache["y"] = self._world.positions()
        return self._cache["x"]

    @property
    def y(self) -> FloatArray:
        if "y" not in self._cache:
            self._cache["x"], self._cache["y"] = self._world.positions()
        return self._cache["y"]

    def _shadowed(self) -> BoolArray:
        if "shadowed" not in self._cache:
            self._cache["shadowed"] = self._world._refresh_shadows()
        return self._cache["shadowed"]

    def light_distance(self) -> FloatArray:
        lamp = self._world.lamp
        distance = np.hypot(self.x - lamp.x, self.y - lamp.y)
        if self._world.shadow == ShadowMode.LAST:
            shadowed = self._shadowed()
            if shadowed.any():
                lit = distance[~shadowed]
                beyond = lit.max() if lit.size else 0.0
                distance[shadowed] += beyond
        return distance

    def light_readings(self) -> FloatArray:
        readings = self._world._light.readings(self.x, self.y)
        if self._world.shadow != ShadowMode.IGNORE:
            readings[self._shadowed()] = 0.0
        return readings

    def acting(self) -> BoolArray:
        if "acting" not in self._cache:
            self._shadowed()
            world = self._world
            self._cache["acting"] = world._external(world._flags[k.F_ACTING]).astype(np.bool_)
        return self._cache["acting"]
