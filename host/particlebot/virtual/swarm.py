"""A swarm of virtual particles: the native firmware logic in a light field, on simulated air."""

from __future__ import annotations

import math
import threading
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from particlebot.pacing import Paced, PacedRunner
from particlebot.protocol import BASE_STATION_ID, UNASSIGNED_ID, SetId, encode_frame
from particlebot.sim.world.light import Lamp, LightField
from particlebot.sim.world.photocells import Photocells
from particlebot.virtual.air import VirtualAir

STEP_MS = 5  # the C API wants a tick at least every 5 ms for 20 ms servo steps
STEP_S = STEP_MS / 1000
# Particles take their 20 ms servo steps at their own phases; moving the line once per 20 ms sees
# one step of every particle together, as the friction model below assumes.
KINEMATICS_EVERY = 4
# A particle's photocells are re-read only after it moved this far (saves ctypes calls).
ADC_MOVE_THRESHOLD_M = 0.0005


class FirmwareParticle(Protocol):
    """What the swarm needs of particlebot.firmware.native.NativeParticle."""

    def set_adc(self, values: list[int]) -> None: ...

    def receive(self, data: bytes) -> None: ...

    def tick(self, now_ms: int) -> None: ...

    def transmit_frame(self) -> bytes: ...

    @property
    def inter_frame_gap_ms(self) -> int: ...

    @property
    def id(self) -> int: ...

    @property
    def radius_um(self) -> int: ...


ParticleFactory = Callable[[int], FirmwareParticle]
"""factory(rng_seed) -> a fresh particle with a blank EEPROM."""


def native_factory(seed: int) -> FirmwareParticle:
    # Imported here so the air and light models work without the native library built.
    from particlebot.firmware.native import NativeParticle

    particle: FirmwareParticle = NativeParticle(eeprom=None, reset_cause=1, rng_seed=seed)
    return particle


@dataclass(frozen=True)
class SwarmConfig:
    count: int = 10
    lamp: Lamp = field(default_factory=Lamp)
    start: float = 0.10
    """Ground distance (m) from the lamp's foot to the nearest particle's centre."""
    spacing: float = 0.155
    """Centre-to-centre distance (m); 0.155 = contracted diameter, so neighbours touch."""
    kinematics: bool = True
    seed: int = 1
    noise: float = 0.0
    first_id: int = 1
    photocell_spread: float = 0.0
    """0: every photocell the ideal one; s: gamma within 1 +- s and so on (Photocells.spread)."""


@dataclass(frozen=True)
class ParticleSnapshot:
    index: int
    id: int
    x: float
    y: float
    ground_distance: float
    radius_um: int


@dataclass
class _Member:
    index: int
    firmware: FirmwareParticle
    node: int
    x: float
    y: float
    adc_x: float = math.nan
    serial_free_at: float = 0.0
    """When the particle may hand its radio the next frame (after the last one's quiet gap)."""


class VirtualSwarm(Paced):
    """Particles in a line away from a lamp, stepped together on one simulated clock.

    step() advances 5 ms; start(speed) runs steps on a thread, `speed` times faster than real time
    (math.inf: as fast as the CPU allows). With kinematics on, the line moves as the particles
    expand and contract: each radius change must keep neighbours touching, and the particles
    that slide are the ones that make the least total sliding (equal friction everywhere: the
    median particle stays put), judged once every 20 ms. Firing in the order S_n = 1, 2, ...
    with T/2 offsets, as the firmware does, that makes the line creep towards the lamp, as in
    the paper: about 2 (R_max - R_min) per wave.
    """

    def __init__(self, config: SwarmConfig, factory: ParticleFactory = native_factory) -> None:
        if config.count < 1:
            raise ValueError("a swarm needs at least one particle")
        if config.first_id + config.count - 1 > 253:
            raise ValueError("particle ids must stay within 1..253")
        self.config = config
        cells = None
        if config.photocell_spread:
            cells = Photocells.spread(config.count, config.photocell_spread, config.seed)
        self.light = LightField(config.lamp, noise=config.noise, seed=config.seed, photocells=cells)
        self.air = VirtualAir()
        self.t = 0.0
        self.steps = 0
        self._lock = threading.Lock()
        self._inbox: list[bytes] = []
        self._base_deliver: Callable[[bytes, int, float], None] | None = None
        self._base_node = self.air.attach(self._to_base)
        self.members: list[_Member] = []
        for index in range(config.count):
            firmware = factory(config.seed * 1000 + index)
            member = _Member(
                index=index,
                firmware=firmware,
                node=-1,
                x=config.lamp.x + config.start + index * config.spacing,
                y=config.lamp.y,
            )
            member.node = self.air.attach(self._to_particle(firmware))
            self.members.append(member)
        self._radii = np.array([m.firmware.radius_um for m in self.members], dtype=float) * 1e-6
        self._update_light(force=True)
        for member in self.members:
            member.firmware.tick(0)
            # Same SET_ID a person would send, but handed to each particle alone: they all start
            # unassigned (254), so on the air it would rename every one of them at once.
            new_id = config.first_id + member.index
            member.firmware.receive(
                encode_frame(SetId(target=UNASSIGNED_ID, new_id=new_id), BASE_STATION_ID, 0)
            )
        self._snapshot: list[ParticleSnapshot] = []
        self._take_snapshot()
        self._runner = PacedRunner(
            lambda: self.t, self._advance, name="virtual-swarm", step_s=STEP_S
        )

    # ---- wiring ----------------------------------------------------------------------------

    def connect_base(self, deliver: Callable[[bytes, int, float], None]) -> None:
        """Where the base station's radio hands received packets (called on the sim thread)."""
        self._base_deliver = deliver

    def send_from_base(self, data: bytes) -> None:
        """Bytes the base station writes to its radio; safe from any thread."""
        with self._lock:
            self._inbox.append(bytes(data))

    def epoch(self, sim_t: float | None = None) -> float:
        """Simulated time as seconds since the epoch (what packets are stamped with)."""
        return self._runner.epoch(sim_t)

    def node_name(self, node: int) -> str:
        return f"virtual-{node:02d}"

    def _to_base(self, data: bytes, source: int, at: float) -> None:
        if self._base_deliver is not None:
            self._base_deliver(data, source, at)

    @staticmethod
    def _to_particle(firmware: FirmwareParticle) -> Callable[[bytes, int, float], None]:
        def deliver(data: bytes, source: int, at: float) -> None:
            firmware.receive(data)

        return deliver

    # ---- simulation ------------------------------------------------------------------------

    def step(self) -> None:
        """Advances the whole swarm by 5 ms of simulated time."""
        self.steps += 1
        self.t = self.steps * STEP_S
        now_ms = self.steps * STEP_MS
        with self._lock:
            inbox, self._inbox = self._inbox, []
        for data in inbox:
            self.air.write(self._base_node, data, self.t)
        for member in self.members:
            member.firmware.tick(now_ms & 0xFFFFFFFF)
            self._transmit(member)
        self.air.advance(self.t)
        if self.config.kinematics and self.steps % KINEMATICS_EVERY == 0:
            self._move()
        if self.steps % 10 == 0:
            self._take_snapshot()

    def _transmit(self, member: _Member) -> None:
        """Hands the particle's radio its next frame the way main.cpp does: one whole frame, then
        the serial line stays quiet for the firmware's inter-frame gap after its last byte, so the
        XBee sends every frame as an RF packet of its own. (Handing over everything queued at once
        put two frames into one packet, and cut two STATUS frames apart at 100 bytes.)"""
        if self.t < member.serial_free_at:
            return
        frame = member.firmware.transmit_frame()
        if frame:
            sent = self.air.write(member.node, frame, self.t)
            member.serial_free_at = sent + member.firmware.inter_frame_gap_ms / 1000

    def run_for(self, seconds: float) -> None:
        for _ in range(round(seconds / STEP_S)):
            self.step()

    def _move(self) -> None:
        radii = np.array([m.firmware.radius_um for m in self.members], dtype=float) * 1e-6
        change = radii - self._radii
        if not change.any():
            return
        self._radii = radii
        # Neighbours i, i+1 stay touching: their centres' gap changes by dr_i + dr_(i+1).
        offsets = np.concatenate(([0.0], np.cumsum(change[:-1] + change[1:])))
        shift = offsets - np.median(offsets)
        for member, dx in zip(self.members, shift, strict=True):
            member.x += float(dx)
        self._update_light()

    def _update_light(self, force: bool = False) -> None:
        moved = [m for m in self.members if force or abs(m.x - m.adc_x) > ADC_MOVE_THRESHOLD_M]
        if not moved:
            return
        values = self.light.sensor_matrix(
            np.array([m.x for m in moved]),
            np.array([m.y for m in moved]),
            particles=[m.index for m in moved],
        )
        for member, row in zip(moved, values, strict=True):
            member.firmware.set_adc([int(v) for v in row])
            member.adc_x = member.x

    def move(self, index: int, x: float, y: float) -> None:
        """Puts particle index at (x, y) (as a person would); its photocells see the new light
        from now on. Call it from the thread that steps the swarm, or while none does."""
        member = self.members[index]
        member.x, member.y = x, y
        self._update_light(force=True)
        self._take_snapshot()

    def _take_snapshot(self) -> None:
        lamp = self.config.lamp
        snapshot = [
            ParticleSnapshot(
                index=m.index,
                id=m.firmware.id,
                x=m.x,
                y=m.y,
                ground_distance=math.hypot(m.x - lamp.x, m.y - lamp.y),
                radius_um=m.firmware.radius_um,
            )
            for m in self.members
        ]
        with self._lock:
            self._snapshot = snapshot

    def snapshot(self) -> list[ParticleSnapshot]:
        """Ids, positions and radii as of the last 50 ms; safe from any thread."""
        with self._lock:
            return list(self._snapshot)

    # ---- running on a thread ---------------------------------------------------------------

    def _advance(self, target: float) -> bool:
        if self.t + STEP_S > target + 1e-9:
            return False
        self.step()
        return True
