"""Fault options every radio URL takes (loss, delay_ms; seed and scenario on simulated radios).

So that a script can rehearse a trial under loss before it runs on hardware, the same options
mean the same on every radio, as near as each can honour them:

- virtual://, emulated://: the simulated 802.15.4 medium (particlebot.sim.air) loses and delays
  every copy of every packet at every receiver, particles' radios included.
- serial://, xbee://: real air has the loss it has; these add loss and delay on top, between the
  host and its radio, to see how a trial copes with a worse link.
- seed makes a simulated radio's losses (and its particles, and a line's or blob's placement) the
  same each time. scenario says where the simulated particles, the lamp and the obstacles are:
  line, blob, or a scenario file (particlebot.radio.simulated.parse_scenario).
"""

from __future__ import annotations

import heapq
import itertools
import random
import threading
from collections.abc import Callable
from dataclasses import dataclass
from typing import Self

from particlebot.options import NON_NEGATIVE, Bounds
from particlebot.radio.base import LinkEvent, Packet, Radio, RadioUrl

FAULT_OPTIONS = frozenset({"loss", "delay_ms"})
"""What every radio that sends takes."""
SIMULATION_OPTIONS = frozenset({"seed", "scenario"})
"""What simulated radios take on top."""
LOSS = Bounds(minimum=0, below=1)
"""A loss of 1 would leave nothing to hear: no command could ever be confirmed."""


@dataclass(frozen=True)
class Faults:
    loss: float = 0.0
    """Probability that one copy of one packet is lost."""
    delay_s: float = 0.0
    """Added to every packet's way."""

    @property
    def any(self) -> bool:
        return self.loss > 0 or self.delay_s > 0


def faults_from_url(url: RadioUrl) -> Faults:
    return Faults(
        loss=url.get_float("loss", 0.0, LOSS),
        delay_s=url.get_float("delay_ms", 0.0, NON_NEGATIVE) / 1000,
    )


class LinkFaults:
    """Loses and delays what passes between a host and its radio, on the radio's clock."""

    def __init__(self, faults: Faults, seed: int | None = None) -> None:
        self.faults = faults
        self._rng = random.Random(seed)
        self._order = itertools.count()
        self._lock = threading.Lock()
        self._sends: list[tuple[float, int, bytes]] = []
        self._packets: list[tuple[float, int, Packet]] = []
        self.lost = 0

    def _lose(self) -> bool:
        if self.faults.loss and self._rng.random() < self.faults.loss:
            self.lost += 1
            return True
        return False

    def outgoing(self, data: bytes, now: float, send: Callable[[bytes], None]) -> None:
        """send(data) now, later (delay) or never (loss)."""
        with self._lock:
            if self._lose():
                return
            if self.faults.delay_s:
                heapq.heappush(self._sends, (now + self.faults.delay_s, next(self._order), data))
                return
        send(data)

    def release_sends(self, now: float, send: Callable[[bytes], None]) -> None:
        """Sends what has waited its delay."""
        while True:
            with self._lock:
                if not self._sends or self._sends[0][0] > now:
                    return
                _, _, data = heapq.heappop(self._sends)
            send(data)

    def incoming(self, packet: Packet) -> Packet | None:
        """The packet now (no delay), or None (lost, or held until its delay has passed)."""
        with self._lock:
            if self._lose():
                return None
            if not self.faults.delay_s:
                return packet
            due = packet.time + self.faults.delay_s
            held = Packet(packet.data, packet.source, due)
            heapq.heappush(self._packets, (due, next(self._order), held))
            return None

    def due_packet(self, now: float) -> Packet | None:
        with self._lock:
            if self._packets and self._packets[0][0] <= now:
                return heapq.heappop(self._packets)[2]
            return None

    def next_send_due(self) -> float | None:
        with self._lock:
            return self._sends[0][0] if self._sends else None

    def next_due(self) -> float | None:
        with self._lock:
            times = [queue[0][0] for queue in (self._sends, self._packets) if queue]
            return min(times) if times else None


class FaultyRadio(Radio):
    """A real radio with loss and delay added between the host and it (serial://, xbee://)."""

    def __init__(self, inner: Radio, faults: Faults) -> None:
        super().__init__(inner.url)
        self.inner = inner
        self.link_faults = LinkFaults(faults)
        inner.add_link_listener(self._relay)

    @classmethod
    def from_url(cls, url: RadioUrl) -> Self:
        raise NotImplementedError("opened by open_radio around another radio")

    def _relay(self, event: LinkEvent) -> None:
        self._set_link(event.state, event.message)

    def now(self) -> float:
        return self.inner.now()

    @property
    def quiet_hint(self) -> str | None:
        return self.inner.quiet_hint

    def send(self, data: bytes) -> None:
        self.link_faults.outgoing(data, self.now(), self.inner.send)

    def receive(self, timeout: float | None = None) -> Packet | None:
        faults = self.link_faults
        faults.release_sends(self.now(), self.inner.send)
        held = faults.due_packet(self.now())
        if held is not None:
            return held
        due = faults.next_due()
        if due is not None:
            wait = max(0.0, due - self.now())
            timeout = wait if timeout is None else min(timeout, wait)
        packet = self.inner.receive(timeout)
        return None if packet is None else faults.incoming(packet)

    def close(self) -> None:
        self.inner.close()
        super().close()
