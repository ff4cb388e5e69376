"""The one 802.15.4 medium of every simulated swarm: who hears whom, loss, delay, packetisation, the
radios' buffers and serial lines at 9600 baud, one shared channel.

Times are cycles of the particles' CPU (particlebot.sim.clock: 8 MHz, counted from power-on),
the one clock a simulated swarm keeps, so that a swarm stepping its particles can stop exactly
where something happens on the air, whether they are the firmware image in simavr or the
firmware logic built for the PC.

What a transparent XBee Series 1 does, as modelled here:
- Bytes its host writes collect in its serial buffer. They leave as one RF packet after RO = 3
  character times of silence after the last one, or at once when 100 bytes (one RF payload) have
  collected (see the project's XBee notes).
- The RF packet occupies the one shared channel for its airtime at 250 kbit/s plus ~20 bytes of
  PHY and MAC framing; a radio that finds the channel busy waits for it (CSMA, no collisions).
- Every other radio in the room hears it after `delay` more, each copy lost independently with
  probability `loss` (802.15.4 broadcasts are never acknowledged or retried).
- A receiving radio hands the packet to its host over its own 9600-baud serial line, after any
  packet still going out there. A packet that would not fit in the radio's serial buffer
  (`buffer_bytes`) is dropped, as a flooded radio drops.
The base station's radio sends each frame it is given as one packet, once its bytes are in.
A host that hands its radio whole frames (the firmware logic on the PC, as main.cpp hands
Serial1 one frame at a time) times their bytes with a SerialLine.
"""

from __future__ import annotations

import heapq
import random
from collections.abc import Callable
from dataclasses import dataclass, field

from particlebot.sim.clock import CPU_HZ

BAUD = 9600
BITS_PER_CHAR = 10  # start bit, 8 data bits, stop bit
RO_CHARS = 3
"""XBee RO default: character times of silence that end a packet."""
MAX_RF_PAYLOAD = 100
RF_BITRATE = 250_000
RF_OVERHEAD_BYTES = 20
"""Preamble, headers, addresses and FCS around each 802.15.4 payload (approximately)."""
DEFAULT_BUFFER_BYTES = 256

BASE = -1
"""Node number of the base station's radio."""
NOISE = -2
"""Node number of the source of injected bytes (interference, a foreign transmitter)."""


def char_cycles(baud: int = BAUD) -> float:
    """Cycles one serial character takes at baud."""
    return BITS_PER_CHAR * CPU_HZ / baud


def rf_cycles(length: int) -> int:
    """Cycles an RF packet of length payload bytes occupies the channel."""
    return (length + RF_OVERHEAD_BYTES) * 8 * CPU_HZ // RF_BITRATE


@dataclass(frozen=True)
class AirPacket:
    """One RF packet: who sent it, what, when it was ready and when it went on the air."""

    number: int
    source: int
    data: bytes
    ready: int
    aired: int
    landed: int
    """End of its airtime: from here (plus the delay) receivers have it."""


@dataclass(frozen=True)
class Reception:
    """One copy of a packet at one receiver. A delivered copy goes out on the receiver's serial
    line from line_start (in cycles * baud, as the harness counts); first and last are when its
    first and last byte have fully reached the host (-1 for a copy that never does)."""

    packet: AirPacket
    receiver: int
    arrival: int
    lost: bool
    overflow: bool
    line_start: int
    baud: int

    @property
    def delivered(self) -> bool:
        return not (self.lost or self.overflow)

    @property
    def source(self) -> int:
        return self.packet.source

    @property
    def data(self) -> bytes:
        return self.packet.data

    def byte_end(self, index: int) -> int:
        """When byte `index` of the packet has fully reached the receiver's host."""
        if not self.delivered:
            return -1
        return _line_end(self.line_start, index + 1, self.baud)

    @property
    def first(self) -> int:
        return self.byte_end(0)

    @property
    def last(self) -> int:
        return self.byte_end(len(self.packet.data) - 1)


Deliver = Callable[[Reception], None]
"""deliver(copy): a delivered copy of a packet reaches its receiver's host. A particle's copy is
handed over at copy.arrival, when its radio has it (an emulated UART paces the bytes itself;
copy.byte_end(i) says when byte i is in); the base station's at copy.last, when its last byte is
in."""

Drop = Callable[[AirPacket, int], bool]
"""drop(packet, receiver) -> True loses that copy, on top of the random loss."""


def _line_end(start_scaled: int, count: int, baud: int) -> int:
    """Cycle at which the count-th byte after start_scaled (cycles * baud) has arrived; the same
    rounding as sim/particles/emulated/particle_sim.c, so both agree to the cycle."""
    end_scaled = start_scaled + count * BITS_PER_CHAR * CPU_HZ
    return (end_scaled + baud - 1) // baud


class SerialLine:
    """A host's serial line into its radio at `baud`: what is written leaves one byte after
    another, 10 bits each, from when the line is free."""

    def __init__(self, baud: int = BAUD) -> None:
        self.baud = baud
        self._free_scaled = 0

    def write(self, data: bytes, cycle: int) -> list[int]:
        """Writes data at cycle; returns the cycle at which each byte has fully reached the
        radio."""
        start = max(cycle * self.baud, self._free_scaled)
        self._free_scaled = start + len(data) * BITS_PER_CHAR * CPU_HZ
        return [_line_end(start, i + 1, self.baud) for i in range(len(data))]

    @property
    def free_at(self) -> int:
        """The cycle at which everything written so far is in."""
        return (self._free_scaled + self.baud - 1) // self.baud


@dataclass
class _Radio:
    node: int
    baud: int
    pending: bytearray = field(default_factory=bytearray)
    last_byte: int = 0
    line_free_scaled: int = 0
    """When its serial line towards its host is free again, in cycles * baud."""


@dataclass(order=True)
class _Arrival:
    cycle: int
    order: int
    copy: Reception = field(compare=False)


class Medium:
    """The air shared by `particles` transparent XBees (nodes 0..particles-1) and the base.

    Feed it what each host writes (uart_byte, base_send, inject), ask next_event() how far every
    node may run before something must reach someone, run them there, then call advance().
    """

    def __init__(
        self,
        particles: int,
        deliver: Deliver,
        *,
        loss: float = 0.0,
        delay_us: float = 0.0,
        seed: int = 1,
        baud: int = BAUD,
        base_baud: int = BAUD,
        buffer_bytes: int = DEFAULT_BUFFER_BYTES,
        drop: Drop | None = None,
        keep_history: bool = True,
    ) -> None:
        if not 0.0 <= loss <= 1.0:
            raise ValueError(f"loss {loss} is not a probability")
        if delay_us < 0:
            raise ValueError("delay cannot be negative")
        self.particles = particles
        self.deliver = deliver
        self.loss = loss
        self.delay = round(delay_us * CPU_HZ / 1_000_000)
        self.baud = baud
        self.buffer_bytes = buffer_bytes
        self.drop = drop
        self.keep_history = keep_history
        self.base_baud = base_baud
        self._char = char_cycles(baud)
        self._random = random.Random(seed)
        self._radios = {node: _Radio(node, baud) for node in range(particles)}
        self._radios[BASE] = _Radio(BASE, base_baud)
        self._scheduled: list[tuple[int, int, int, bytes]] = []  # (ready, order, source, data)
        self._arrivals: list[_Arrival] = []
        self._order = 0
        self._channel_free = 0
        self._base_uart_free = 0
        self.packets: list[AirPacket] = []
        self.receptions: list[Reception] = []
        self.packets_aired = 0
        self.bytes_aired = 0
        self.copies_lost = 0
        self.copies_overflowed = 0

    # ---- what hosts write ------------------------------------------------------------------

    def uart_byte(self, node: int, cycle: int, value: int) -> None:
        """Particle `node` finished writing a byte to its radio at cycle (in time order)."""
        radio = self._radios[node]
        if radio.pending and cycle >= self._ready(radio):
            self._schedule(self._ready(radio), node, bytes(radio.pending))
            radio.pending.clear()
        radio.pending.append(value)
        radio.last_byte = cycle
        if len(radio.pending) >= MAX_RF_PAYLOAD:
            self._schedule(cycle + round(self._char), node, bytes(radio.pending))
            radio.pending.clear()

    def base_send(self, data: bytes, cycle: int) -> None:
        """The base station writes one frame at cycle; it airs as one packet once it is in."""
        if not data:
            return
        start = max(cycle, self._base_uart_free)
        self._base_uart_free = start + round(len(data) * char_cycles(self.base_baud))
        self._schedule(self._base_uart_free, BASE, bytes(data))

    def inject(self, data: bytes, cycle: int) -> None:
        """Bytes from a foreign transmitter, ready at cycle, in packets of at most 100 bytes."""
        for start in range(0, len(data), MAX_RF_PAYLOAD):
            self._schedule(cycle, NOISE, bytes(data[start : start + MAX_RF_PAYLOAD]))

    # ---- time --------------------------------------------------------------------------------

    def next_event(self) -> int | None:
        """Earliest cycle at which a packet may go on the air or reach a particle. Nodes run
        to it (or less) before advance(): nothing a particle sends in between can reach another
        before then, since a packet needs RO of silence and its airtime first."""
        times = [self._ready(r) for r in self._radios.values() if r.pending]
        if self._scheduled:
            times.append(self._scheduled[0][0])
        if self._arrivals:
            times.append(self._arrivals[0].cycle)
        return min(times) if times else None

    def advance(self, cycle: int) -> None:
        """Airs what is ready by cycle and hands every copy due by cycle to its receiver."""
        for radio in self._radios.values():
            if radio.pending and self._ready(radio) <= cycle:
                self._schedule(self._ready(radio), radio.node, bytes(radio.pending))
                radio.pending.clear()
        while self._scheduled and self._scheduled[0][0] <= cycle:
            ready, _, source, data = heapq.heappop(self._scheduled)
            self._air(ready, source, data)
        while self._arrivals and self._arrivals[0].cycle <= cycle:
            self.deliver(heapq.heappop(self._arrivals).copy)

    def forget(self) -> None:
        """Drops the packet and reception history (long runs keep memory bounded)."""
        self.packets.clear()
        self.receptions.clear()

    # ---- plumbing ----------------------------------------------------------------------------

    def _ready(self, radio: _Radio) -> int:
        # The last byte takes one character time on the wire, then RO characters of silence.
        return radio.last_byte + round((1 + RO_CHARS) * self._char)

    def _schedule(self, ready: int, source: int, data: bytes) -> None:
        self._order += 1
        heapq.heappush(self._scheduled, (ready, self._order, source, data))

    def _air(self, ready: int, source: int, data: bytes) -> None:
        aired = max(ready, self._channel_free)
        landed = aired + rf_cycles(len(data))
        self._channel_free = landed
        packet = AirPacket(self.packets_aired, source, data, ready, aired, landed)
        self.packets_aired += 1
        self.bytes_aired += len(data)
        if self.keep_history:
            self.packets.append(packet)
        for receiver in [*range(self.particles), BASE]:
            if receiver != source:
                self._receive(packet, receiver, landed + self.delay)

    def _receive(self, packet: AirPacket, receiver: int, arrival: int) -> None:
        radio = self._radios[receiver]
        lost = self._random.random() < self.loss
        if self.drop is not None and self.drop(packet, receiver):
            lost = True
        start_scaled = max(arrival * radio.baud, radio.line_free_scaled)
        backlog = (start_scaled - arrival * radio.baud) / (BITS_PER_CHAR * CPU_HZ)
        overflow = not lost and backlog + len(packet.data) > self.buffer_bytes
        copy = Reception(packet, receiver, arrival, lost, overflow, start_scaled, radio.baud)
        if lost:
            self.copies_lost += 1
        elif overflow:
            self.copies_overflowed += 1
        else:
            radio.line_free_scaled = start_scaled + len(packet.data) * BITS_PER_CHAR * CPU_HZ
            self._order += 1
            due = copy.last if receiver == BASE else arrival
            heapq.heappush(self._arrivals, _Arrival(due, self._order, copy))
        if self.keep_history:
            self.receptions.append(copy)
