"""Several emulated particles (the real ELF in simavr) in a light field, joined by emulated air.

EmulatedSwarm runs one tools/sim/particle_sim process per particle and steps them in lockstep:
each step runs every particle to the same cycle, at most `quantum_us` ahead and never past the
next moment the Medium must act (a packet going on the air, a packet reaching a particle), so
every byte reaches every radio at the cycle the model says. The processes run their steps in
parallel. BaseStation is the base station's end of it for tests and benchmarks; the console
reaches a swarm through particlebot.radio.emulated.
"""

from __future__ import annotations

import math
import struct
import threading
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from types import TracebackType
from typing import Self

from particlebot.pacing import Paced, PacedRunner
from particlebot.protocol import (
    BASE_STATION_ID,
    BROADCAST_ID,
    PARAM_SPECS,
    DecodeStats,
    Frame,
    Message,
    Param,
    Ping,
    Status,
    StreamDecoder,
    crc16,
    encode_frame,
)
from particlebot.sim.harness import CPU_HZ, ParticleSim, default_elf
from particlebot.sim.medium import BASE, BAUD, DEFAULT_BUFFER_BYTES, NOISE, AirPacket, Medium
from particlebot.sim.world.light import ADC_FULL_SCALE, Lamp, LightField
from particlebot.sim.world.photocells import Photocells

AVCC_MV = 3300
PACED_STEP_S = 0.01
"""Emulated time one call of the wall-clock pacing covers, at most."""
MAX_QUANTUM_US = 3000
"""A particle's byte needs RO (3 characters) of silence plus its airtime before anyone can hear
it; steps shorter than that let no effect reach another particle within the same step."""

# EEPROM layout of firmware/lib/settings/settings.h (version 1): magic, version, parameter
# count, id, resets, last reset cause, one int32 per parameter id below 64, CRC-16 of it all.
_EEPROM_MAGIC = b"PB"
_EEPROM_VERSION = 1
_EEPROM_PARAM_SLOTS = 64


def eeprom_image(particle_id: int, params: Mapping[Param, int] | None = None) -> bytes:
    """A settings block as the firmware stores it: this id, the defaults but for params, no
    resets counted yet. The firmware replaces a block it does not recognise by the defaults and
    the unassigned id, which the swarm's tests would notice at once."""
    # Slots of ids the protocol lacks keep a blank chip's 0xFF (the CRC covers them anyway).
    values = [-1] * _EEPROM_PARAM_SLOTS
    for param, spec in PARAM_SPECS.items():
        values[int(param)] = spec.default
    for param, value in (params or {}).items():
        spec = PARAM_SPECS[Param(param)]
        if not spec.min <= value <= spec.max:
            raise ValueError(f"{Param(param).name}={value} is outside {spec.min}..{spec.max}")
        values[int(param)] = value
    block = _EEPROM_MAGIC + bytes([_EEPROM_VERSION, len(PARAM_SPECS), particle_id, 0, 0])
    block += struct.pack(f"<{_EEPROM_PARAM_SLOTS}i", *values)
    return block + struct.pack("<H", crc16(block))


def light_to_millivolts(value: float) -> int:
    """The divider voltage that makes an eq. 11 reading of value (on a 1023 scale) at 3.3 V."""
    return round(min(max(value, 0.0), ADC_FULL_SCALE) * AVCC_MV / ADC_FULL_SCALE)


def node_name(index: int) -> str:
    """The emulated XBee's 64-bit address (Digi's OUI, then the particle's number)."""
    return f"0013A200{index + 1:08X}"


@dataclass(frozen=True)
class SwarmConfig:
    count: int = 5
    lamp: Lamp = field(default_factory=Lamp)
    start: float = 0.10
    """Ground distance (m) from the lamp's foot to the nearest particle's centre."""
    spacing: float = 0.155
    """Centre-to-centre distance (m) along the line away from the lamp."""
    positions: Sequence[tuple[float, float]] | None = None
    """(x, y) of each particle in metres; overrides start and spacing."""
    first_id: int = 1
    params: Mapping[Param, int] = field(default_factory=dict)
    """Parameter values preset in every particle's EEPROM."""
    loss: float = 0.0
    """Probability that one receiver misses one packet."""
    delay_us: float = 0.0
    """Added to every packet's airtime before receivers have it."""
    buffer_bytes: int = DEFAULT_BUFFER_BYTES
    """A radio's buffer towards its host: a packet that does not fit is dropped."""
    base_baud: int = BAUD
    """The base station radio's serial rate (particles' radios run at 9600)."""
    seed: int = 1
    """Seeds the losses and, with each particle's index, what its firmware seeds itself from."""
    quantum_us: float = 2000.0
    """Longest lockstep step; at most MAX_QUANTUM_US, so stepping never delays a delivery."""
    elf: Path | None = None
    """The firmware image (default: build/firmware/particle.elf)."""
    fault_elf: Sequence[int] = ()
    """Indices of particles that run build/firmware/particle-faults.elf instead."""
    harness: Path | None = None
    keep_history: bool = True
    """Keep every UART byte, servo pulse and packet (tests); off, memory stays bounded."""
    photocell_spread: float = 0.0
    """0: every photocell the ideal one; s: gamma within 1 +- s and so on (Photocells.spread)."""


@dataclass(frozen=True)
class HeardFrame:
    """A frame the base station received, when its last byte was in, and from which radio."""

    time_s: float
    source: int
    frame: Frame


BROADCAST_ANSWERS_S = 0.7
"""A particle answers a broadcast PING in a random one of 10 slots of 60 ms while it knows no group
size (firmware/lib/particle/particle.h), so that a swarm's answers do not all reach the base
station's radio at once; the last one is in within this (a STATUS takes 54 ms at 9600 baud)."""

BaseListener = Callable[[int, bytes, float], None]
"""listener(source_index, data, time_s): a packet the base station's radio hands over."""


class EmulatedSwarm(Paced):
    """Particles in a line from a lamp (or at given positions), each the real firmware image."""

    def __init__(self, config: SwarmConfig | None = None) -> None:
        config = config or SwarmConfig()
        if config.count < 1:
            raise ValueError("a swarm needs at least one particle")
        if not 1 <= config.first_id <= 253 - (config.count - 1):
            raise ValueError("particle ids must stay within 1..253")
        if not 0 < config.quantum_us <= MAX_QUANTUM_US:
            raise ValueError(f"quantum_us must be in (0, {MAX_QUANTUM_US}]")
        self.config = config
        cells = None
        if config.photocell_spread:
            cells = Photocells.spread(config.count, config.photocell_spread, config.seed)
        self.light = LightField(config.lamp, photocells=cells)
        if config.positions is not None:
            if len(config.positions) != config.count:
                raise ValueError("one position per particle")
            self.positions = [(float(x), float(y)) for x, y in config.positions]
        else:
            lamp = config.lamp
            self.positions = [
                (lamp.x + config.start + i * config.spacing, lamp.y) for i in range(config.count)
            ]
        self.ids = [config.first_id + i for i in range(config.count)]
        self.medium = Medium(
            config.count,
            self._deliver,
            loss=config.loss,
            delay_us=config.delay_us,
            seed=config.seed,
            base_baud=config.base_baud,
            buffer_bytes=config.buffer_bytes,
            keep_history=config.keep_history,
        )
        self.cycle = 0
        self._quantum = round(config.quantum_us * CPU_HZ / 1_000_000)
        self._base_listeners: list[BaseListener] = []
        self._inbox: list[bytes] = []
        self._inbox_lock = threading.Lock()
        self._seen: list[int] = []
        self.sims: list[ParticleSim] = []
        self._runner = PacedRunner(
            lambda: self.time_s,
            self._advance,
            name="emulated-swarm",
            step_s=PACED_STEP_S,
            join_timeout_s=10.0,
        )
        try:
            for index in range(config.count):
                elf = default_elf(faults=True) if index in config.fault_elf else config.elf
                sim = ParticleSim(
                    elf,
                    harness=config.harness,
                    eeprom=eeprom_image(self.ids[index], config.params),
                    light_mv=self.sensor_millivolts(index),
                    # The firmware seeds its random numbers from this: every particle differs.
                    noise_mv=250 + (config.seed * 37 + index * 11) % 200,
                )
                self.sims.append(sim)
                self._seen.append(0)
        except BaseException:
            self.close()
            raise

    # ---- the world ---------------------------------------------------------------------------

    @property
    def time_s(self) -> float:
        return self.cycle / CPU_HZ

    def sensor_values(self, index: int) -> list[int]:
        """The six readings (0..1023) the light field gives particle index where it stands."""
        x, y = self.positions[index]
        return self.light.sensor_values(x, y, particle=index)

    def sensor_millivolts(self, index: int) -> list[int]:
        return [light_to_millivolts(v) for v in self.sensor_values(index)]

    def move(self, index: int, x: float, y: float) -> None:
        """Puts particle index at (x, y); its photocells see the new light from now on."""
        self.positions[index] = (x, y)
        self.sims[index].set_light_mv(self.sensor_millivolts(index))

    def node_name(self, index: int) -> str:
        return "noise" if index == NOISE else node_name(index)

    def epoch(self, time_s: float | None = None) -> float:
        """Simulated time as seconds since the Unix epoch (what radio packets are stamped with)."""
        return self._runner.epoch(time_s)

    # ---- the air -----------------------------------------------------------------------------

    def add_base_listener(self, listener: BaseListener) -> None:
        """Called (on the stepping thread) with each packet the base station's radio receives."""
        self._base_listeners.append(listener)

    def send_from_base(self, data: bytes) -> None:
        """The base station writes one frame to its radio; it goes out at the next step. Safe
        from any thread."""
        with self._inbox_lock:
            self._inbox.append(bytes(data))

    def inject(self, data: bytes, at_s: float | None = None) -> None:
        """Puts foreign bytes on the air (at at_s, default now), heard by every radio."""
        cycle = self.cycle if at_s is None else max(self.cycle, round(at_s * CPU_HZ))
        self.medium.inject(data, cycle)

    def _deliver(self, receiver: int, source: int, data: bytes, cycle: int) -> None:
        if receiver == BASE:
            for listener in self._base_listeners:
                listener(source, data, cycle / CPU_HZ)
        else:
            self.sims[receiver].send_uart(data)

    def received(
        self, index: int, *, until_s: float | None = None, silence_s: float | None = 0.1
    ) -> tuple[list[tuple[float, Frame]], DecodeStats]:
        """What particle index's serial port got (needs keep_history), decoded as one stream as
        its firmware does (a transparent radio gives no sender): every frame with the time its
        last byte was in, and the decoder's counters. A partial frame is dropped after
        silence_s without a byte, like the firmware parser's timeout (None: never)."""
        decoder = StreamDecoder()
        frames: list[tuple[float, Frame]] = []
        end = math.inf if until_s is None else until_s * CPU_HZ
        copies = sorted(
            (r for r in self.medium.receptions if r.receiver == index and r.delivered),
            key=lambda r: r.line_start,
        )
        last_byte: int | None = None
        for copy in copies:
            for i, value in enumerate(copy.packet.data):
                at = copy.byte_end(i)
                if at > end:
                    return frames, decoder.stats
                if (
                    silence_s is not None
                    and last_byte is not None
                    and at - last_byte > silence_s * CPU_HZ
                ):
                    frames += [(last_byte / CPU_HZ, f) for f in decoder.flush()]
                frames += [(at / CPU_HZ, f) for f in decoder.feed(bytes([value]))]
                last_byte = at
        return frames, decoder.stats

    # ---- stepping ----------------------------------------------------------------------------

    def step(self, limit: int | None = None) -> None:
        """Runs every particle one step ahead (at most a quantum, never past limit)."""
        target = self.cycle + self._quantum
        if limit is not None:
            target = min(target, limit)
        due = self.medium.next_event()
        if due is not None:
            target = min(target, due)
        target = max(target, self.cycle + 1)
        with self._inbox_lock:
            inbox, self._inbox = self._inbox, []
        for data in inbox:
            self.medium.base_send(data, self.cycle)
        for sim in self.sims:
            sim.begin_run(target)
        for sim in self.sims:
            sim.finish_run()
        for index, sim in enumerate(self.sims):
            for byte in sim.uart[self._seen[index] :]:
                self.medium.uart_byte(index, byte.cycle, byte.value)
            if self.config.keep_history:
                self._seen[index] = len(sim.uart)
            else:
                sim.forget()
        self.cycle = target
        self.medium.advance(target)

    def run_until(self, time_s: float) -> None:
        end = round(time_s * CPU_HZ)
        while self.cycle < end:
            self.step(end)

    def run_for(self, seconds: float) -> None:
        self.run_until(self.time_s + seconds)

    def run_until_true(
        self, condition: Callable[[], bool], timeout_s: float, check_every_s: float = 0.01
    ) -> bool:
        """Runs until condition() holds (checked every check_every_s) or timeout_s pass."""
        end = self.time_s + timeout_s
        while not condition():
            if self.time_s >= end:
                return False
            self.run_until(min(end, self.time_s + check_every_s))
        return True

    # ---- running on a thread, paced to the wall clock ----------------------------------------

    def _advance(self, target: float) -> bool:
        if self.time_s >= target:
            return False
        # Short runs keep the console's view of the air fresh and stop() prompt.
        self.run_until(min(target, self.time_s + PACED_STEP_S))
        return True

    # ---- lifetime ----------------------------------------------------------------------------

    def close(self) -> None:
        self.stop()
        for sim in self.sims:
            sim.close()

    def __enter__(self) -> Self:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()


class BaseStation:
    """The base station's end of an EmulatedSwarm, driven from the caller's thread: numbered
    frames out, every frame heard in (reassembled per radio, as a console does)."""

    def __init__(self, swarm: EmulatedSwarm) -> None:
        self.swarm = swarm
        self.seq = 0
        self.decoder = StreamDecoder()
        self.heard: list[HeardFrame] = []
        self.sent: list[tuple[float, bytes]] = []
        """Each frame sent, with the time it was handed to the base station's radio."""
        swarm.add_base_listener(self._on_packet)

    def _on_packet(self, source: int, data: bytes, time_s: float) -> None:
        for frame in self.decoder.feed(data, source):
            self.heard.append(HeardFrame(time_s, source, frame))

    def send(self, message: Message) -> float:
        """Broadcasts message from the base station; returns the time it was handed over."""
        raw = encode_frame(message, BASE_STATION_ID, self.seq)
        self.seq = (self.seq + 1) % 256
        self.swarm.send_from_base(raw)
        self.sent.append((self.swarm.time_s, raw))
        return self.swarm.time_s

    def frames(
        self, kind: type[Message] | None = None, since_s: float = 0.0
    ) -> list[tuple[HeardFrame, Message]]:
        """Frames heard at or after since_s whose message is a kind (any message if None)."""
        found = []
        for heard in self.heard:
            message = heard.frame.message
            if heard.time_s < since_s or message is None:
                continue
            if kind is None or isinstance(message, kind):
                found.append((heard, message))
        return found

    def statuses(self, since_s: float = 0.0) -> dict[int, Status]:
        """The latest STATUS of each particle id heard since since_s."""
        latest: dict[int, Status] = {}
        for heard, message in self.frames(Status, since_s):
            assert isinstance(message, Status)
            latest[heard.frame.sender] = message
        return latest

    def ping_all(
        self, timeout_s: float = 1.5, ids: Sequence[int] | None = None, attempts: int = 3
    ) -> dict[int, Status]:
        """A STATUS from every particle (default: the swarm's ids) asked for now: one broadcast
        PING, whose answers spread over up to BROADCAST_ANSWERS_S, then PINGs to each silent one
        (an answer can be lost, or dropped by a full radio buffer), which answer at once. Missing
        ids did not answer."""
        wanted = set(self.swarm.ids if ids is None else ids)
        asked = self.send(Ping(target=BROADCAST_ID))
        first = min(timeout_s, BROADCAST_ANSWERS_S)
        waits = [first] + [(timeout_s - first) / max(1, attempts - 1)] * (attempts - 1)
        for wait_s in waits:
            self.swarm.run_until_true(lambda: wanted <= set(self.statuses(asked)), wait_s)
            missing = wanted - set(self.statuses(asked))
            if not missing:
                break
            for particle_id in sorted(missing):
                self.send(Ping(target=particle_id))
        return {k: v for k, v in self.statuses(asked).items() if k in wanted}


def packet_frames(packet: AirPacket) -> list[Frame]:
    """The whole frames inside one RF packet (frames split across packets are not counted)."""
    return StreamDecoder().feed(packet.data)
