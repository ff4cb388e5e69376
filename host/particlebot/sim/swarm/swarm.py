"""A simulated swarm of particles running our firmware: one clock stepping the world, the particles
(native logic or emulated image) and the air, with the base station's radio on that air.

Each step runs the particles to the next cycle where something must happen (a tick of the native
logic; a quantum of the emulated image, or sooner where the air acts), hands the bytes they wrote
to their radios, lets the air deliver what is due (to the particles, to the base station), and
every 10 ms of the world's time steps the world with the radius each servo gives: their bodies
move, and the photocells read the light where the bodies now are.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from particlebot.closing import ClosedOnExit
from particlebot.protocol import UNASSIGNED_ID, DecodeStats, Frame, StreamDecoder
from particlebot.sim.air.medium import BASE, NOISE, Medium, Reception
from particlebot.sim.clock import CPU_HZ, cycles, seconds
from particlebot.sim.particles.emulated.particles import EmulatedParticles
from particlebot.sim.particles.interface import FirmwareParticles
from particlebot.sim.particles.model.controller import Controller, FloatArray, WorldView
from particlebot.sim.particles.native.particles import (
    NativeParticles,
    ParticleFactory,
    native_factory,
)
from particlebot.sim.scenarios.build import build_world
from particlebot.sim.swarm.config import TRUTH_BODIES_S, TRUTH_RADII_S, Level, SwarmConfig
from particlebot.sim.swarm.pacing import Paced, PacedRunner
from particlebot.sim.swarm.records import bodies_record, radii_record, scene_record
from particlebot.sim.world.light import LightField, ShadowMode
from particlebot.sim.world.photocells import Photocells

MAX_ID = UNASSIGNED_ID - 1
"""The highest particle id (254 is the unassigned one, 255 broadcast)."""
PACED_STEP_S = 0.01
"""Simulated time one call of the wall-clock pacing covers, at most."""
LIGHT_MOVE_M = 0.0005
"""A particle's photocells are read again once its body moved this far (the light changes by
well under a count over half a millimetre)."""
HELD_RADIUS_M = 0.0005
"""A commanded radius this far above the contracted one means the particle moves by itself (the
first servo steps of a cycle, or of a servo hold, go further)."""

BaseListener = Callable[[int, bytes, float], None]
"""listener(source_index, data, time_s): a packet the base station's radio hands over."""
TruthListener = Callable[[dict[str, Any], float], None]
"""listener(record, time_s): the world's truth (particlebot.sim.swarm.records records) at time_s."""


@dataclass(frozen=True)
class ParticleSnapshot:
    """Where a particle's body is, as of the latest world step."""

    index: int
    id: int
    x: float
    y: float
    ground_distance: float
    """From the lamp's foot (m)."""
    radius_um: int
    """Its body's radius."""


class FirmwareRadii(Controller):
    """The World's controller when particles run the firmware: each world step the swarm writes
    the radius every particle's servo gives into `radii` (NaN: a body no servo drives, which
    holds its radius)."""

    def __init__(self) -> None:
        self.radii = np.zeros(0)

    def bind(self, count: int, rng: np.random.Generator) -> None:
        self.radii = np.full(count, np.nan)

    def command(self, view: WorldView, out: FloatArray) -> None:
        out[:] = self.radii


class SimSwarm(Paced, ClosedOnExit):
    """Particles running our firmware in the world of a scenario, on one 802.15.4 air.

    The scenario places the robot's particles (indices 0..K-1, ids first_id..), the lamp and the
    obstacles; SwarmConfig.level says whether each particle is the native logic or the emulated
    image. step()/run_for() advance it from the caller's thread; start(speed) runs it on a
    thread of its own, `speed` times faster than real time (math.inf: flat out).
    """

    def __init__(
        self, config: SwarmConfig | None = None, *, factory: ParticleFactory = native_factory
    ) -> None:
        """factory: makes each native particle (tests give one that misbehaves)."""
        config = config if config is not None else SwarmConfig()
        self.config = config
        self._drive = FirmwareRadii()
        built = build_world(config.resolved_scenario(), controller=self._drive)
        self.world = built.world
        self.scenario = built.scenario
        robot = built.particles
        if robot < 1:
            raise ValueError("a swarm needs at least one particle")
        if not 1 <= config.first_id <= MAX_ID:
            raise ValueError(f"the first particle id must be 1..{MAX_ID}")
        # Ids are one byte: a swarm of more than 253 particles repeats them (the base station
        # cannot tell such particles apart; the world and the air can).
        ids = [(config.first_id - 1 + i) % MAX_ID + 1 for i in range(robot)]
        self.particles = _particles(config, ids, factory)
        try:
            self.air = Medium(
                robot,
                self._deliver,
                loss=config.loss,
                delay_us=config.delay_us,
                seed=config.seed,
                base_baud=config.base_baud,
                buffer_bytes=config.buffer_bytes,
                keep_history=config.keep_history,
            )
            cells = None
            if config.photocell_spread:
                cells = Photocells.spread(robot, config.photocell_spread, config.seed)
            self.light = LightField(
                self.world.lamp, noise=config.noise, seed=config.seed, photocells=cells
            )
            self.cycle = 0
            self._robot = robot
            self._world_cycles = cycles(self.world.params.dt)
            if abs(self._world_cycles - self.world.params.dt * CPU_HZ) > 1e-6:
                raise ValueError("the world's time step must be a whole number of CPU cycles")
            self._next_world = self._world_cycles
            self._world_steps = 0
            self._bodies_every = max(1, round(TRUTH_BODIES_S / self.world.params.dt))
            self._radii_every = max(1, round(TRUTH_RADII_S / self.world.params.dt))
            self._hands_on = False
            self._lock = threading.Lock()
            self._inbox: list[bytes] = []
            self._base_listeners: list[BaseListener] = []
            self._truth_listeners: list[TruthListener] = []
            self._light_x = np.full(robot, np.nan)
            self._light_y = np.full(robot, np.nan)
            self._dark = np.zeros(robot, dtype=np.bool_)
            self._commanded = self.particles.radii_m()
            self._snapshot: list[ParticleSnapshot] = []
            self._update_light(force=True)
            self._take_snapshot()
            self._runner = PacedRunner(
                lambda: self.time_s,
                self._advance,
                name=f"{self.particles.level}-swarm",
                step_s=PACED_STEP_S,
                join_timeout_s=10.0,
            )
        except BaseException:
            self.particles.close()
            raise

    # ---- what is where -----------------------------------------------------------------------

    @property
    def ids(self) -> list[int]:
        return self.particles.ids

    @property
    def count(self) -> int:
        return self._robot

    @property
    def level(self) -> Level:
        return self.config.level

    @property
    def native(self) -> NativeParticles:
        """The particles, when they are the firmware logic (TypeError otherwise)."""
        if not isinstance(self.particles, NativeParticles):
            raise TypeError("these particles are not the native firmware logic")
        return self.particles

    @property
    def emulated(self) -> EmulatedParticles:
        """The particles, when they are the emulated image (TypeError otherwise)."""
        if not isinstance(self.particles, EmulatedParticles):
            raise TypeError("these particles are not the emulated image")
        return self.particles

    @property
    def time_s(self) -> float:
        """Simulated seconds since the particles were switched on."""
        return seconds(self.cycle)

    @property
    def t(self) -> float:
        return self.time_s

    def epoch(self, time_s: float | None = None) -> float:
        """Simulated time as seconds since the Unix epoch (what radio packets are stamped with)."""
        return self._runner.epoch(time_s)

    def node_name(self, index: int) -> str:
        return "noise" if index == NOISE else self.particles.node_name(index)

    def snapshot(self) -> list[ParticleSnapshot]:
        """Ids, positions and radii as of the latest world step; safe from any thread."""
        with self._lock:
            return list(self._snapshot)

    def place(self, index: int, x: float, y: float) -> None:
        """Puts particle index at (x, y), as a person would; its photocells see the light there
        from now on. A person's hands hold the swarm still (the world does not move the bodies,
        which may have been put down overlapping, as on a calibration's ring) until a particle
        moves by itself. Call it from the thread that steps the swarm, or while none does."""
        self.world.place(index, x, y)
        self._hands_on = True
        self._update_light(force=True)
        self._take_snapshot()

    # ---- the air -----------------------------------------------------------------------------

    def add_base_listener(self, listener: BaseListener) -> None:
        """Called (on the stepping thread) with each packet the base station's radio receives."""
        self._base_listeners.append(listener)

    def send_from_base(self, data: bytes) -> None:
        """The base station writes one frame to its radio; it goes out at the next step. Safe
        from any thread."""
        with self._lock:
            self._inbox.append(bytes(data))

    def inject(self, data: bytes, at_s: float | None = None) -> None:
        """Puts foreign bytes on the air (at at_s, default now), heard by every radio."""
        cycle = self.cycle if at_s is None else max(self.cycle, cycles(at_s))
        self.air.inject(data, cycle)

    def _deliver(self, copy: Reception) -> None:
        if copy.receiver == BASE:
            at = seconds(copy.last)
            for listener in self._base_listeners:
                listener(copy.source, copy.data, at)
        else:
            self.particles.receive(copy)

    def received(
        self, index: int, *, until_s: float | None = None, silence_s: float | None = None
    ) -> tuple[list[tuple[float, Frame]], DecodeStats]:
        """What particle index's serial port got (needs keep_history), decoded as one stream as
        its firmware does (a transparent radio gives no sender): every frame with the time its
        last byte was in, and the decoder's counters. A partial frame is dropped after silence_s
        without a byte (default: the firmware parser's own timeout)."""
        if silence_s is None:
            from particlebot.firmware.native import firmware_constants

            silence_s = firmware_constants().frame_timeout_ms / 1000
        decoder = StreamDecoder()
        frames: list[tuple[float, Frame]] = []
        end = math.inf if until_s is None else until_s * CPU_HZ
        copies = sorted(
            (r for r in self.air.receptions if r.receiver == index and r.delivered),
            key=lambda r: r.line_start,
        )
        last_byte: int | None = None
        for copy in copies:
            for i, value in enumerate(copy.data):
                at = copy.byte_end(i)
                if at > end:
                    return frames, decoder.stats
                if last_byte is not None and at - last_byte > silence_s * CPU_HZ:
                    frames += [(seconds(last_byte), f) for f in decoder.flush()]
                frames += [(seconds(at), f) for f in decoder.feed(bytes([value]))]
                last_byte = at
        return frames, decoder.stats

    # ---- the truth ---------------------------------------------------------------------------

    def add_truth_listener(self, listener: TruthListener) -> None:
        """Called (on the stepping thread) with the world's truth: the scene and the bodies now
        at once, then the bodies every TRUTH_BODIES_S and the commanded radii every
        TRUTH_RADII_S of simulated time."""
        with self._lock:
            snapshot = list(self._snapshot)
            self._truth_listeners.append(listener)
        now = self.time_s
        listener(self._scene(), now)
        if snapshot:
            listener(
                bodies_record(
                    np.array([p.x for p in snapshot]),
                    np.array([p.y for p in snapshot]),
                    np.array([p.radius_um * 1e-6 for p in snapshot]),
                ),
                now,
            )

    def _scene(self) -> dict[str, Any]:
        world = self.world
        lamp = world.lamp
        return scene_record(
            level=self.particles.level,
            scenario=self.scenario.name,
            ids=self.ids,
            lamp=(lamp.x, lamp.y, lamp.height),
            rects=[(r.x_min, r.x_max, r.y_min, r.y_max) for r in world.arena.rects],
            circles=[(c.x, c.y, c.radius) for c in world.arena.circles],
            objects=[(o.x, o.y, o.radius) for o in world.objects],
            r_min=world.params.r_min,
            r_max=world.params.r_max,
        )

    def _tell(self, record: dict[str, Any]) -> None:
        with self._lock:
            listeners = list(self._truth_listeners)
        now = self.time_s
        for listener in listeners:
            listener(record, now)

    # ---- stepping ----------------------------------------------------------------------------

    def step(self, limit: int | None = None) -> None:
        """Runs everything one step ahead: to the particles' next stop, never past the next world
        step, a moment the air acts on emulated particles, or limit (a cycle)."""
        particles = self.particles
        target = min(particles.next_stop(self.cycle), self._next_world)
        if particles.exact_air:
            due = self.air.next_event()
            if due is not None:
                target = min(target, due)
        if limit is not None:
            target = min(target, limit)
        target = max(target, self.cycle + 1)
        with self._lock:
            inbox, self._inbox = self._inbox, []
        for data in inbox:
            self.air.base_send(data, self.cycle)
        for byte in particles.run_until(target):
            self.air.uart_byte(byte.index, byte.cycle, byte.value)
        self.cycle = target
        self.air.advance(target)
        while self.cycle >= self._next_world:
            self._step_world()
            self._next_world += self._world_cycles

    def _step_world(self) -> None:
        commanded = self.particles.radii_m()
        self._commanded = commanded
        if self._hands_on and bool(np.any(commanded > self.world.params.r_min + HELD_RADIUS_M)):
            self._hands_on = False  # a particle moves by itself: the person let go
        if self.config.kinematics and not self._hands_on:
            self._drive.radii[: self._robot] = commanded
            self.world.step(1)
            self._update_light()
        self._world_steps += 1
        if self._world_steps % 5 == 0:
            self._take_snapshot()
        if not self._truth_listeners:
            return
        if self._world_steps % self._radii_every == 0:
            self._tell(radii_record(commanded))
        if self._world_steps % self._bodies_every == 0:
            x, y = self.world.positions()
            r = self.world.radii()
            n = self._robot
            self._tell(bodies_record(x[:n], y[:n], r[:n]))

    def _update_light(self, force: bool = False) -> None:
        """Gives the photocells of every particle that moved the light where it now is; a
        particle in an obstacle's shadow (a scenario whose shadows count) reads dark."""
        n = self._robot
        x, y = self.world.positions()
        x, y = x[:n], y[:n]
        dark = np.zeros(n, dtype=np.bool_)
        world = self.world
        if world.shadow != ShadowMode.IGNORE and (world.arena.rects or world.arena.circles):
            dark = world.arena.shadowed(x, y, world.lamp.x, world.lamp.y)
        moved = np.hypot(x - self._light_x, y - self._light_y) > LIGHT_MOVE_M
        moved |= dark != self._dark
        if force:
            moved[:] = True
        which = np.flatnonzero(moved)
        if which.size == 0:
            return
        readings = self.light.sensor_matrix(x[which], y[which], particles=which)
        readings[dark[which]] = 0
        for row, index in zip(readings, which, strict=True):
            self.particles.set_light(int(index), [int(v) for v in row])
        self._light_x[which] = x[which]
        self._light_y[which] = y[which]
        self._dark = dark

    def _take_snapshot(self) -> None:
        x, y = self.world.positions()
        r = self.world.radii()
        lamp = self.world.lamp
        snapshot = [
            ParticleSnapshot(
                index=i,
                id=particle_id,
                x=float(x[i]),
                y=float(y[i]),
                ground_distance=math.hypot(x[i] - lamp.x, y[i] - lamp.y),
                radius_um=round(float(r[i]) * 1e6),
            )
            for i, particle_id in enumerate(self.ids)
        ]
        with self._lock:
            self._snapshot = snapshot

    def run_until(self, time_s: float) -> None:
        """Runs to time_s (to the nearest cycle)."""
        self._run_to(cycles(time_s))

    def run_for(self, seconds: float) -> None:
        self._run_to(self.cycle + cycles(seconds))

    def run_until_true(
        self, condition: Callable[[], bool], timeout_s: float, check_every_s: float = 0.01
    ) -> bool:
        """Runs until condition() holds (checked every check_every_s) or timeout_s pass."""
        end = self.cycle + cycles(timeout_s)
        every = max(1, cycles(check_every_s))
        while not condition():
            if self.cycle >= end:
                return False
            self._run_to(min(end, self.cycle + every))
        return True

    def _run_to(self, end: int) -> None:
        while self.cycle < end:
            self.step(end)

    # ---- running on a thread, paced to the wall clock ----------------------------------------

    def _advance(self, target: float) -> bool:
        end = cycles(target)
        if self.cycle >= end:
            return False
        # Short runs keep the console's view of the air fresh and stop() prompt.
        self._run_to(min(end, self.cycle + cycles(PACED_STEP_S)))
        return True

    # ---- lifetime ----------------------------------------------------------------------------

    def close(self) -> None:
        self.stop()
        self.particles.close()


def _particles(config: SwarmConfig, ids: list[int], factory: ParticleFactory) -> FirmwareParticles:
    if config.level is Level.NATIVE:
        return NativeParticles(ids, params=config.params, seed=config.seed, factory=factory)
    return EmulatedParticles(
        ids,
        params=config.params,
        seed=config.seed,
        quantum_us=config.quantum_us,
        elf=config.elf,
        fault_elf=config.fault_elf,
        harness=config.harness,
        keep_history=config.keep_history,
    )
