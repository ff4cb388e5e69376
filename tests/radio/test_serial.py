"""serial:// against a pty pair: bytes both ways, a vanished and returned port, open errors."""

from __future__ import annotations

import errno
import os
from collections.abc import Iterator
from pathlib import Path

import pytest

from particlebot.cli import main
from particlebot.radio import (
    LinkEvent,
    LinkState,
    PortBusyError,
    PortLostError,
    PortNotFoundError,
    open_radio,
)
from particlebot.radio._port import translate_open_error
from particlebot.radio.faults import FaultyRadio
from particlebot.radio.serial import SerialRadio, contains_api_frame
from particlebot.swarm.api import Swarm
from tests.support.ptys import VanishingPty
from tests.support.xbee_emulator import api_frame


@pytest.fixture
def pty(tmp_path: Path) -> Iterator[VanishingPty]:
    port = VanishingPty(tmp_path / "ttyUSB0")
    yield port
    port.close()


def test_bytes_from_the_radio_come_out_as_packets_without_a_source(pty: VanishingPty) -> None:
    with open_radio(f"serial://{pty.path}?baud=9600") as radio:
        pty.write(b"\xa5\x5a hello")
        got = b""
        while len(got) < 8:
            packet = radio.receive(timeout=2)
            assert packet is not None
            assert packet.source is None
            got += packet.data
    assert got == b"\xa5\x5a hello"


def test_sent_bytes_reach_the_radio_unchanged(pty: VanishingPty) -> None:
    with open_radio(f"serial://{pty.path}") as radio:
        radio.send(bytes(range(256)))
        assert pty.read_until(256) == bytes(range(256))


def test_a_vanished_port_is_reported_and_reopened_when_it_returns(pty: VanishingPty) -> None:
    events: list[LinkEvent] = []
    with SerialRadio(str(pty.path), retry_s=0.05) as radio:
        radio.add_link_listener(events.append)
        pty.unplug()
        assert radio.receive(timeout=0.3) is None
        assert [e.state for e in events] == [LinkState.LOST]
        assert "vanished" in events[0].message
        with pytest.raises(PortLostError):
            radio.send(b"x")
        pty.replug()
        # pyserial flushes input on open, so write only once the radio has the port again.
        for _ in range(50):
            if len(events) == 2:
                break
            assert radio.receive(timeout=0.1) is None
        pty.write(b"after")
        packet = radio.receive(timeout=3)
        assert packet is not None and packet.data == b"after"
        assert [e.state for e in events] == [LinkState.LOST, LinkState.CONNECTED]
        radio.send(b"again")
        assert pty.read_until(5) == b"again"


def test_a_missing_port_says_how_to_find_the_right_one(tmp_path: Path) -> None:
    with pytest.raises(PortNotFoundError, match="list_ports"):
        open_radio(f"serial://{tmp_path}/ttyUSB9")


def test_a_port_held_by_another_program_says_so(pty: VanishingPty) -> None:
    with open_radio(f"serial://{pty.path}"), pytest.raises(PortBusyError, match="in use"):
        open_radio(f"serial://{pty.path}")


def test_permission_errors_tell_the_user_about_the_dialout_group() -> None:
    error = translate_open_error("/dev/ttyUSB0", OSError(errno.EACCES, "Permission denied"))
    assert "dialout" in str(error)


def test_a_radio_in_api_mode_read_as_transparent_gets_a_warning(pty: VanishingPty) -> None:
    events: list[LinkEvent] = []
    with open_radio(f"serial://{pty.path}") as radio:
        radio.add_link_listener(events.append)
        rx16 = api_frame(bytes([0x81, 0x12, 0x34, 40, 0x02]) + b"\xa5\x5a payload", False)
        pty.write(rx16)
        while radio.receive(timeout=0.5) is not None and not events:
            pass
        assert [e.state for e in events] == [LinkState.WARNING]
    assert f"xbee://{pty.path}" in events[0].message


def test_api_frame_detection_needs_a_valid_checksum() -> None:
    frame = api_frame(bytes([0x81, 0x00, 0x01, 40, 0x02]) + b"data", False)
    assert contains_api_frame(b"junk" + frame + b"more")
    broken = frame[:-1] + bytes([frame[-1] ^ 1])
    assert not contains_api_frame(broken + b"x")
    assert not contains_api_frame(b"\x7e\x00\x05 plain transparent text")


def test_closing_while_lost_does_not_hang(pty: VanishingPty) -> None:
    radio = SerialRadio(str(pty.path), retry_s=0.05)
    pty.unplug()
    assert radio.receive(timeout=0.2) is None
    radio.close()
    assert radio.receive(timeout=0.2) is None
    assert not os.path.exists(pty.path)


def test_a_console_on_a_silent_port_is_told_what_to_check(pty: VanishingPty) -> None:
    swarm = Swarm.open(f"serial://{pty.path}?baud=19200", log_dir=None)
    try:
        hint = swarm.tracker.quiet_hint or ""
        assert "19200 baud" in hint and "PAN ID" in hint and "channel" in hint
    finally:
        swarm.close()


def test_a_recording_on_a_silent_port_prints_the_hint(
    pty: VanishingPty, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr("particlebot.swarm.model.QUIET_HINT_S", 0.2)
    log_dir = pty.path.parent / "logs"
    argv = ["log", "--radio", f"serial://{pty.path}", "--log-dir", str(log_dir), "--duration", "1"]
    assert main(argv) == 0
    assert "warning: Nothing heard for 0.2 s. Check that the base XBee" in capsys.readouterr().out


def test_loss_on_a_real_link_drops_whole_frames_between_the_host_and_its_radio(
    pty: VanishingPty,
) -> None:
    with open_radio(f"serial://{pty.path}?loss=0.5") as radio:
        assert isinstance(radio, FaultyRadio)
        for number in range(200):
            radio.send(bytes([number]))
        lost = radio.link_faults.lost
        arrived = pty.read_until(200 - lost)
    assert 40 <= lost <= 160  # 200 tries at one half: 1e-17 to fall outside
    assert len(arrived) == 200 - lost
    assert list(arrived) == sorted(arrived)  # in order, each whole or not at all


def test_delay_on_a_real_link_holds_frames_both_ways(pty: VanishingPty) -> None:
    with open_radio(f"serial://{pty.path}?delay_ms=300") as radio:
        radio.send(b"late")
        sent_at = radio.now()
        assert pty.read_until(4, timeout=0.1) == b""  # held, however long nobody reads
        arrived = b""
        while not arrived and radio.now() < sent_at + 3:
            radio.receive(timeout=0.1)  # sends what has waited its delay
            arrived = pty.read_until(4, timeout=0.01)
        assert arrived == b"late"
        assert radio.now() >= sent_at + 0.3

        pty.write(b"answer")
        written_at = radio.now()
        heard = b""
        while len(heard) < 6 and radio.now() < written_at + 3:
            packet = radio.receive(timeout=0.5)
            if packet is not None:
                assert radio.now() >= written_at + 0.3
                heard += packet.data
        assert heard == b"answer"
