"""The one 802.15.4 medium: XBee packetising, airtime, loss, delay and serial pacing."""

from __future__ import annotations

import pytest

from particlebot.sim.air.medium import (
    BASE,
    BAUD,
    MAX_RF_PAYLOAD,
    NOISE,
    RO_CHARS,
    Medium,
    Reception,
    SerialLine,
    char_cycles,
    rf_cycles,
)
from particlebot.sim.clock import CPU_HZ

CHAR = char_cycles()  # 8333.3 cycles: 10 bits at 9600 baud


class Air:
    """A medium with three particle radios and the base, recording what each host receives."""

    def __init__(self, particles: int = 3, **options: float) -> None:
        self.got: list[tuple[int, int, bytes, int]] = []
        self.medium = Medium(particles, self._deliver, **options)  # type: ignore[arg-type]

    def _deliver(self, copy: Reception) -> None:
        due = copy.last if copy.receiver == BASE else copy.arrival
        self.got.append((copy.receiver, copy.source, copy.data, due))

    def write(self, node: int, data: bytes, start: int, spacing: float = CHAR) -> int:
        """Node's host writes data back to back from start; returns the last byte's cycle."""
        cycle = start
        for i, value in enumerate(data):
            cycle = start + round(i * spacing)
            self.medium.uart_byte(node, cycle, value)
        return cycle

    def run(self, until: int) -> None:
        """Advances event by event, as a swarm does, up to until."""
        while True:
            due = self.medium.next_event()
            if due is None or due > until:
                break
            self.medium.advance(due)
        self.medium.advance(until)

    def to(self, receiver: int) -> list[tuple[int, bytes, int]]:
        return [(s, d, c) for r, s, d, c in self.got if r == receiver]


def test_bytes_written_back_to_back_leave_as_one_packet_after_three_silent_characters():
    air = Air()
    last = air.write(0, b"hello", 1000)
    air.run(last + 10 * round(CHAR))

    (packet,) = air.medium.packets
    assert packet.data == b"hello" and packet.source == 0
    # The last byte's own character time, then RO = 3 characters of silence.
    assert packet.ready == last + round((1 + RO_CHARS) * CHAR)
    landed = packet.aired + rf_cycles(5)
    assert sorted(r for r, *_ in air.got) == [BASE, 1, 2]  # everyone but the sender
    for receiver in (1, 2):
        ((source, data, cycle),) = air.to(receiver)
        assert (source, data, cycle) == (0, b"hello", landed)
    ((_, _, at_base),) = air.to(BASE)
    assert at_base == pytest.approx(landed + 5 * CHAR, abs=1)  # once its last byte is in


def test_a_pause_longer_than_ro_splits_the_stream_into_packets():
    air = Air()
    end = air.write(0, b"abc", 0)
    gap_start = end + round((1 + RO_CHARS) * CHAR) + 1
    end = air.write(0, b"def", gap_start)
    air.run(end + 10 * round(CHAR))
    assert [p.data for p in air.medium.packets] == [b"abc", b"def"]

    air = Air()
    end = air.write(0, b"abc", 0)
    end = air.write(0, b"def", end + round(3 * CHAR))  # shorter than RO after the last byte
    air.run(end + 10 * round(CHAR))
    assert [p.data for p in air.medium.packets] == [b"abcdef"]


def test_a_long_burst_goes_out_in_packets_of_at_most_100_bytes():
    air = Air()
    data = bytes(range(250))
    end = air.write(1, data, 0)
    air.run(end + 10 * round(CHAR))
    sizes = [len(p.data) for p in air.medium.packets]
    assert sizes == [MAX_RF_PAYLOAD, MAX_RF_PAYLOAD, 50]
    assert b"".join(d for _, d, _ in air.to(0)) == data


def test_each_base_station_frame_is_one_packet_and_reaches_every_particle():
    air = Air()
    air.medium.base_send(b"frame-one", 0)
    air.medium.base_send(b"frame-two", 0)  # queued behind the first on the base's serial line
    air.run(CPU_HZ // 10)
    assert [p.data for p in air.medium.packets] == [b"frame-one", b"frame-two"]
    first, second = air.medium.packets
    assert first.ready == round(9 * CHAR)
    assert second.ready == round(18 * CHAR)
    for particle in range(3):
        assert [d for _, d, _ in air.to(particle)] == [b"frame-one", b"frame-two"]
    assert air.to(BASE) == []


def test_the_channel_carries_one_packet_at_a_time():
    air = Air()
    end_a = air.write(0, b"A" * 40, 0)
    end_b = air.write(1, b"B" * 40, 0)
    assert end_a == end_b
    air.run(end_a + 20 * round(CHAR))
    a, b = air.medium.packets
    assert a.ready == b.ready
    assert b.aired == a.landed  # waited for the channel (no collisions in this model)


def test_delay_is_added_to_every_copy():
    plain, slow = Air(), Air(delay_us=5000)
    for air in (plain, slow):
        air.write(2, b"xyz", 0)
        air.run(CPU_HZ // 10)
    assert [c for *_, c in slow.got] == [c + 5 * CPU_HZ // 1000 for *_, c in plain.got]


def test_each_receiver_loses_packets_independently_at_the_configured_rate():
    air = Air(particles=4, loss=0.2, seed=3)
    for k in range(500):
        air.medium.inject(bytes([k % 256]), k * CPU_HZ // 100)
    air.run(600 * CPU_HZ // 100)
    copies = [r for r in air.medium.receptions if r.packet.source == NOISE]
    assert len(copies) == 500 * 5  # four particles and the base
    lost = sum(r.lost for r in copies)
    assert 0.17 < lost / len(copies) < 0.23  # 2500 draws: 3 standard deviations is +-0.024
    per_packet = {}
    for r in copies:
        per_packet.setdefault(r.packet.number, []).append(r.lost)
    mixed = sum(0 < sum(flags) < len(flags) for flags in per_packet.values())
    assert mixed > 100  # most losses hit some receivers and not others


def test_a_receiver_gets_packets_one_after_another_at_9600_baud_and_drops_what_overflows():
    air = Air(particles=2, buffer_bytes=120)
    air.medium.inject(b"a" * 60, 0)
    air.medium.inject(b"b" * 50, 0)
    air.medium.inject(b"c" * 20, 0)  # 130 bytes waiting: more than the buffer holds
    air.run(CPU_HZ)
    copies = [r for r in air.medium.receptions if r.receiver == 0]
    assert [(len(r.packet.data), r.delivered) for r in copies] == [
        (60, True),
        (50, True),
        (20, False),
    ]
    first, second, third = copies
    assert third.overflow and not third.lost
    assert second.first == pytest.approx(first.last + CHAR, abs=1)
    assert first.last - first.first == pytest.approx(59 * CHAR, abs=1)
    assert air.medium.copies_overflowed == 3  # the third packet, at both particles and the base


def test_next_event_never_lets_a_step_skip_past_a_packet_or_an_arrival():
    air = Air()
    assert air.medium.next_event() is None
    end = air.write(0, b"go", 0)
    ready = end + round((1 + RO_CHARS) * CHAR)
    assert air.medium.next_event() == ready
    air.medium.advance(ready)
    (packet,) = air.medium.packets
    assert air.medium.next_event() == packet.landed  # when the copies reach the particles
    assert packet.landed - ready == rf_cycles(2)


def test_airtime_is_the_802_15_4_rate_with_framing():
    assert rf_cycles(0) == 20 * 8 * CPU_HZ // 250_000
    assert rf_cycles(100) == 120 * 8 * 32
    assert char_cycles(BAUD) == pytest.approx(8333.33, abs=0.01)


def test_a_serial_line_takes_ten_bits_a_byte_and_queues_what_is_written_while_busy():
    line = SerialLine()
    first = line.write(b"abc", 1000)
    # Each byte is in once its stop bit ends, rounded up to a whole cycle as the harness does.
    assert first == [1000 + -(-(k * 10 * CPU_HZ) // BAUD) for k in (1, 2, 3)]
    assert line.free_at == first[-1]
    second = line.write(b"d", 1000)  # written while the line was still busy: after "c"
    assert second[0] == pytest.approx(first[-1] + CHAR, abs=1)
    later = line.write(b"e", 10 * CPU_HZ)  # an idle line starts at once
    assert later == [10 * CPU_HZ + -(-(10 * CPU_HZ) // BAUD)]
