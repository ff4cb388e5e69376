"""The simulated air: 9600-baud pacing, transparent-mode packetisation, broadcast to all others."""

from __future__ import annotations

import pytest

from particlebot.virtual.air import BYTE_S, MAX_RF_PAYLOAD, VirtualAir


class Inbox:
    def __init__(self) -> None:
        self.items: list[tuple[bytes, int, float]] = []

    def __call__(self, data: bytes, source: int, at: float) -> None:
        self.items.append((data, source, at))


def make_air(nodes: int) -> tuple[VirtualAir, list[Inbox]]:
    air = VirtualAir()
    inboxes = [Inbox() for _ in range(nodes)]
    for inbox in inboxes:
        air.attach(inbox)
    return air, inboxes


def run_until(air: VirtualAir, end: float, step: float = 0.005) -> None:
    t = 0.0
    while t < end:
        t += step
        air.advance(t)


def test_a_frame_written_at_once_goes_out_as_one_packet_to_every_other_node() -> None:
    air, inboxes = make_air(3)
    air.write(0, bytes(50), 0.0)
    run_until(air, 1.0)
    assert inboxes[0].items == []
    for inbox in inboxes[1:]:
        assert [(data, source) for data, source, _ in inbox.items] == [(bytes(50), 0)]


def test_a_frame_takes_at_least_twice_its_serial_time_to_arrive() -> None:
    air, inboxes = make_air(2)
    air.write(0, bytes(52), 0.0)
    run_until(air, 1.0)
    ((_, _, at),) = inboxes[1].items
    # Into the sender's radio at 9600 baud, then out of the receiver's at 9600 baud.
    assert at >= 2 * 52 * 10 / 9600
    assert at < 2 * 52 * 10 / 9600 + 0.02


def test_a_receiver_gets_packets_of_two_senders_one_after_the_other() -> None:
    air, inboxes = make_air(3)
    air.write(0, b"a" * 40, 0.0)
    air.write(1, b"b" * 40, 0.0)
    run_until(air, 1.0)
    arrivals = [at for _, _, at in inboxes[2].items]
    assert len(arrivals) == 2
    assert arrivals[1] - arrivals[0] == pytest.approx(40 * BYTE_S)


def test_more_than_a_full_rf_payload_is_cut_into_packets() -> None:
    air, inboxes = make_air(2)
    air.write(0, bytes(range(250)), 0.0)
    run_until(air, 2.0)
    sizes = [len(data) for data, _, _ in inboxes[1].items]
    assert sizes == [MAX_RF_PAYLOAD, MAX_RF_PAYLOAD, 50]
    assert b"".join(data for data, _, _ in inboxes[1].items) == bytes(range(250))


def test_bytes_written_after_a_quiet_gap_make_a_new_packet() -> None:
    air, inboxes = make_air(2)
    air.write(0, b"first", 0.0)
    run_until(air, 0.1)
    air.write(0, b"second", 0.1)
    run_until(air, 1.0)
    assert [data for data, _, _ in inboxes[1].items] == [b"first", b"second"]


def test_a_drop_rule_loses_only_the_copies_it_names() -> None:
    air, inboxes = make_air(3)
    air.drop = lambda source, receiver, data: receiver == 2
    air.write(0, b"lost for node 2", 0.0)
    run_until(air, 1.0)
    assert len(inboxes[1].items) == 1
    assert inboxes[2].items == []
