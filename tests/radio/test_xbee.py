"""xbee:// (digi-xbee Raw802Device) against the API-mode emulator on a pty."""

from __future__ import annotations

import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from particlebot.radio import (
    LinkEvent,
    LinkState,
    NoResponseError,
    Packet,
    PortLostError,
    PortNotFoundError,
    WrongModeError,
    open_radio,
)
from particlebot.radio.xbee import XBeeRadio
from tests.support.xbee_emulator import XBeeEmulator

# Short probe and guard times: the emulator's guard time is 0.1 s, a real radio's 1 s.
FAST = "timeout=0.5&probe=0.3&guard=0.15&retry=0.05"


@pytest.fixture(params=[1, 2], ids=["api1", "api2-escaped"])
def emulator(request: pytest.FixtureRequest, tmp_path: Path) -> Iterator[XBeeEmulator]:
    emulator = XBeeEmulator(tmp_path / "ttyUSB0", api_mode=request.param)
    yield emulator
    emulator.close()


@pytest.fixture
def radio(emulator: XBeeEmulator) -> Iterator[XBeeRadio]:
    radio = open_radio(f"xbee://{emulator.port}?{FAST}")
    assert isinstance(radio, XBeeRadio)
    yield radio
    radio.close()


def receive_all(radio: XBeeRadio, count: int, timeout: float = 3.0) -> list[Packet]:
    packets: list[Packet] = []
    deadline = time.monotonic() + timeout
    while len(packets) < count and time.monotonic() < deadline:
        packet = radio.receive(timeout=0.1)
        if packet is not None:
            packets.append(packet)
    return packets


def test_opening_reads_the_radio_through_the_at_queries_digi_xbee_needs(
    emulator: XBeeEmulator, radio: XBeeRadio
) -> None:
    assert radio.api_mode == emulator.api_mode
    for command in (b"AP", b"HV", b"VR", b"SH", b"SL", b"NI", b"MY"):
        assert command in emulator.at_commands_seen


def test_a_sent_frame_is_broadcast_as_tx64_to_ffff(
    emulator: XBeeEmulator, radio: XBeeRadio
) -> None:
    data = b"\xa5\x5a\x00\x02\x00\x07\x7e\x7d\x11\x13"  # bytes that API mode 2 must escape
    radio.send(data)
    assert emulator.wait_for(lambda: emulator.transmissions)
    sent = emulator.transmissions[0]
    assert sent.api_id == 0x00
    assert sent.destination == bytes(6) + b"\xff\xff"
    assert sent.data == data


def test_a_burst_of_rx16_packets_arrives_without_the_4_s_sender_lookup(
    emulator: XBeeEmulator, radio: XBeeRadio
) -> None:
    # Stock Raw802Device asks every RX16 sender for SH and waits 4 s for the answer; twenty
    # packets would take over a minute. The budget here is generous for a slow CI machine.
    started = time.monotonic()
    for index in range(20):
        emulator.inject_rx16(0x1234, bytes([0xA5, 0x5A, index, 0x7E, 0x11]))
    packets = receive_all(radio, 20)
    elapsed = time.monotonic() - started
    assert [p.data[2] for p in packets] == list(range(20))
    assert elapsed < 2.0
    assert emulator.remote_at_requests == []
    assert {p.source for p in packets} == {"1234"}


def test_rx64_packets_carry_the_senders_64_bit_address(
    emulator: XBeeEmulator, radio: XBeeRadio
) -> None:
    emulator.inject_rx64(0x0013A20040000007, b"\xa5\x5a from a particle with MY=FFFE")
    packets = receive_all(radio, 1)
    assert packets[0].source == "0013A20040000007"
    assert packets[0].data.endswith(b"MY=FFFE")


def test_an_unplugged_radio_is_reported_and_picked_up_again(
    emulator: XBeeEmulator, radio: XBeeRadio
) -> None:
    events: list[LinkEvent] = []
    radio.add_link_listener(events.append)
    emulator.unplug()
    assert receive_all(radio, 1, timeout=0.3) == []
    assert [e.state for e in events] == [LinkState.LOST]
    with pytest.raises(PortLostError):
        radio.send(b"x")
    emulator.replug()
    for _ in range(50):
        if len(events) == 2:
            break
        radio.receive(timeout=0.1)
    assert [e.state for e in events] == [LinkState.LOST, LinkState.CONNECTED]
    emulator.inject_rx16(0x0001, b"back")
    assert receive_all(radio, 1)[0].data == b"back"


def test_a_transparent_radio_is_told_to_switch_to_api_mode(tmp_path: Path) -> None:
    emulator = XBeeEmulator(tmp_path / "ttyUSB0", api_mode=0)
    try:
        with pytest.raises(WrongModeError, match="AP=1") as raised:
            open_radio(f"xbee://{emulator.port}?{FAST}")
        assert f"serial://{emulator.port}" in str(raised.value)
        # The probe left command mode again, so the radio keeps passing data.
        assert emulator.wait_for(lambda: emulator.at_commands_seen == [b"ATCN"])
    finally:
        emulator.close()


def test_a_silent_port_says_to_check_port_and_baud(tmp_path: Path) -> None:
    emulator = XBeeEmulator(tmp_path / "ttyUSB0", api_mode=1)
    emulator.unplug()
    emulator.replug()
    emulator._stop_thread()  # the device node is there, nothing answers
    try:
        with pytest.raises(NoResponseError, match="BD"):
            open_radio(f"xbee://{emulator.port}?{FAST}")
    finally:
        emulator.close()


def test_a_missing_port_is_named(tmp_path: Path) -> None:
    with pytest.raises(PortNotFoundError):
        open_radio(f"xbee://{tmp_path}/ttyUSB7?{FAST}")
