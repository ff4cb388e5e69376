"""Simulated XBee air: 9600-baud serial links into and out of every radio; packets go to all."""

from __future__ import annotations

import heapq
from collections.abc import Callable
from dataclasses import dataclass, field

BAUD = 9600
BYTE_S = 10 / BAUD  # start bit, 8 data bits, stop bit
# A transparent XBee sends what it has buffered after RO (3) character times of serial silence,
# or at once when the buffer reaches a full RF payload.
PACKETIZATION_GAP_S = 3 * BYTE_S
MAX_RF_PAYLOAD = 100
RF_BIT_S = 1 / 250_000  # 802.15.4 at 2.4 GHz
RF_OVERHEAD_BYTES = 20  # preamble, headers, addresses, FCS

Deliver = Callable[[bytes, int, float], None]
"""deliver(data, source_node, time): bytes a radio hands to its host over its serial port."""


@dataclass
class _Node:
    id: int
    deliver: Deliver
    uart_free_at: float = 0.0
    pending: bytearray = field(default_factory=bytearray)
    airs_at: float | None = None
    rx_free_at: float = 0.0


class VirtualAir:
    """Every node hears every other node (one room, no collisions, no loss unless `drop` says so).

    Time is the caller's simulated clock in seconds. Serial pacing is modelled both ways: bytes a
    host writes reach its radio at 9600 baud and a radio hands received packets to its host at
    9600 baud, one after another, which is what limits a real swarm's traffic.
    """

    def __init__(self, byte_s: float = BYTE_S) -> None:
        self.byte_s = byte_s
        self._nodes: list[_Node] = []
        self._arrivals: list[tuple[float, int, int, int, bytes]] = []
        self._order = 0
        self.packets_aired = 0
        self.bytes_aired = 0
        self.drop: Callable[[int, int, bytes], bool] | None = None
        """drop(source, receiver, data) -> True loses that copy (for fault tests)."""

    def attach(self, deliver: Deliver) -> int:
        node = _Node(len(self._nodes), deliver)
        self._nodes.append(node)
        return node.id

    def write(self, node_id: int, data: bytes, now: float) -> float:
        """Bytes a host writes to its radio's serial port at time now; returns when the last of
        them has reached the radio (the host's serial line is busy until then)."""
        node = self._nodes[node_id]
        if not data:
            return max(now, node.uart_free_at)
        start = max(now, node.uart_free_at)
        if node.airs_at is not None and node.airs_at <= start:
            self._air(node, bytes(node.pending), node.airs_at)
            node.pending.clear()
        for byte in data:
            start += self.byte_s
            node.pending.append(byte)
            if len(node.pending) >= MAX_RF_PAYLOAD:
                self._air(node, bytes(node.pending), start)
                node.pending.clear()
        node.uart_free_at = start
        node.airs_at = start + PACKETIZATION_GAP_S if node.pending else None
        return start

    def advance(self, now: float) -> None:
        """Airs every packet due by now and delivers every arrival due by now, in time order."""
        for node in self._nodes:
            if node.airs_at is not None and node.airs_at <= now:
                self._air(node, bytes(node.pending), node.airs_at)
                node.pending.clear()
                node.airs_at = None
        while self._arrivals and self._arrivals[0][0] <= now:
            at, _, receiver, source, data = heapq.heappop(self._arrivals)
            self._nodes[receiver].deliver(data, source, at)

    def _air(self, node: _Node, data: bytes, at: float) -> None:
        self.packets_aired += 1
        self.bytes_aired += len(data)
        landed = at + (len(data) + RF_OVERHEAD_BYTES) * 8 * RF_BIT_S
        for other in self._nodes:
            if other is node or (self.drop is not None and self.drop(node.id, other.id, data)):
                continue
            start = max(landed, other.rx_free_at)
            other.rx_free_at = start + len(data) * self.byte_s
            self._order += 1
            heapq.heappush(self._arrivals, (other.rx_free_at, self._order, other.id, node.id, data))
