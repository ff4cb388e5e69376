"""The session's receive thread: decoding per source, drops, timeouts, fan-out and sending."""

from __future__ import annotations

import contextlib
import threading

from particlebot.protocol import DropReason, Ping, State, Stop, encode_frame
from particlebot.radio import LinkState, RadioError
from particlebot.session import Listener, ReceivedFrame, SentFrame, Session
from particlebot.swarm.tracker import SwarmTracker
from tests.support.fakes import FakeRadio, Recorder, status_frame, wait_until


def test_frames_reach_every_listener_in_order(fake_radio: FakeRadio) -> None:
    first, second = Recorder(), Recorder()
    with Session(fake_radio, [first, second]):
        fake_radio.inject(status_frame(3, seq=1) + status_frame(4, seq=2))
        assert second.wait(lambda: len(second.frames) == 2)
        assert first.wait(lambda: len(first.frames) == 2)
    assert [r.frame.sender for r in first.frames] == [3, 4]
    assert [r.frame.seq for r in second.frames] == [1, 2]
    assert first.closed and second.closed


def test_a_frame_split_over_packets_of_one_source_is_reassembled(fake_radio: FakeRadio) -> None:
    recorder = Recorder()
    frame_a, frame_b = status_frame(5), status_frame(6)
    with Session(fake_radio, [recorder]):
        # Halves of two senders' frames interleave; each source has its own buffer.
        fake_radio.inject(frame_a[:20], source="A")
        fake_radio.inject(frame_b[:10], source="B")
        fake_radio.inject(frame_a[20:], source="A")
        fake_radio.inject(frame_b[10:], source="B")
        assert recorder.wait(lambda: len(recorder.frames) == 2)
    assert sorted((r.source, r.frame.sender) for r in recorder.frames) == [("A", 5), ("B", 6)]
    assert recorder.dropped == []


def test_noise_and_a_corrupted_frame_are_reported_and_reception_goes_on(
    fake_radio: FakeRadio,
) -> None:
    recorder = Recorder()
    corrupted = bytearray(status_frame(7))
    corrupted[10] ^= 0xFF
    with Session(fake_radio, [recorder]) as session:
        fake_radio.inject(b"\x00\x13noise" + bytes(corrupted) + status_frame(8))
        assert recorder.wait(lambda: len(recorder.frames) == 1)
        assert recorder.wait(lambda: len(recorder.dropped) >= 2)
        assert session.decoder.stats.bad_crc == 1
    reasons = {d.event.reason for d in recorder.dropped}
    assert reasons == {DropReason.SKIPPED, DropReason.BAD_CRC}
    assert recorder.frames[0].frame.sender == 8


def test_a_partial_frame_left_silent_is_dropped_as_truncated(fake_radio: FakeRadio) -> None:
    recorder = Recorder()
    with Session(fake_radio, [recorder]):
        fake_radio.inject(status_frame(9)[:15], source="A")
        fake_radio.clock.advance(0.5)  # radio time passes with nothing more from A
        assert recorder.wait(
            lambda: any(d.event.reason is DropReason.TRUNCATED for d in recorder.dropped)
        )
        fake_radio.inject(status_frame(9), source="A")
        assert recorder.wait(lambda: len(recorder.frames) == 1)


def test_a_listener_that_raises_does_not_stop_the_others(fake_radio: FakeRadio) -> None:
    class Broken(Listener):
        def on_frame(self, received: ReceivedFrame) -> None:
            raise RuntimeError("boom")

    recorder = Recorder()
    with Session(fake_radio, [Broken(), recorder]):
        fake_radio.inject(status_frame(1))
        fake_radio.inject(status_frame(2))
        assert recorder.wait(lambda: len(recorder.frames) == 2)


def test_send_frames_from_the_base_station_with_increasing_sequence_numbers(
    fake_radio: FakeRadio,
) -> None:
    recorder = Recorder()
    with Session(fake_radio, [recorder]) as session:
        session.send(Stop())
        session.send(Ping(target=255))
    frames = fake_radio.sent_frames()
    assert [(f.sender, f.seq) for f in frames] == [(0, 0), (0, 1)]
    assert fake_radio.sent[0] == encode_frame(Stop(), 0, 0)
    assert [s.frame.type_name for s in recorder.sent] == ["STOP", "PING"]


def test_a_refused_send_is_reported_to_listeners_and_raised(fake_radio: FakeRadio) -> None:
    recorder = Recorder()
    fake_radio.fail_sends = True
    with Session(fake_radio, [recorder]) as session:
        try:
            session.send(Stop())
        except Exception as exc:
            assert "gone" in str(exc)
        else:
            raise AssertionError("send should have raised")
    assert recorder.sent[0].error is not None


def test_a_lost_port_drops_half_frames_and_is_passed_on(fake_radio: FakeRadio) -> None:
    recorder = Recorder()
    with Session(fake_radio, [recorder]) as session:
        fake_radio.inject(status_frame(3)[:12])
        assert recorder.wait(lambda: len(recorder.packets) == 1)
        assert wait_until(lambda: session.decoder.buffered(None) == 12)
        fake_radio.lose("unplugged")
        assert recorder.wait(lambda: any(e.state is LinkState.LOST for e in recorder.links))
    assert any(d.event.reason is DropReason.TRUNCATED for d in recorder.dropped)


def test_a_listener_told_of_a_refused_send_does_not_hold_up_other_senders(
    fake_radio: FakeRadio,
) -> None:
    """on_sent runs after the send lock is released: a listener that waits for another thread's
    send (here, one that resends) must not deadlock the session."""
    other_done: list[bool] = []

    class Resender(Listener):
        def __init__(self, session: Session) -> None:
            self.session = session

        def on_sent(self, sent: SentFrame) -> None:
            if other_done or threading.current_thread() is not threading.main_thread():
                return

            def resend() -> None:
                with contextlib.suppress(RadioError):
                    self.session.send(Ping(target=255))

            other = threading.Thread(target=resend)
            other.start()
            other.join(timeout=2.0)
            other_done.append(not other.is_alive())

    fake_radio.fail_sends = True
    with Session(fake_radio) as session:
        session.add_listener(Resender(session))
        with contextlib.suppress(RadioError):
            session.send(Stop())
    assert other_done == [True]


def test_commands_never_go_out_from_the_receive_thread(fake_radio: FakeRadio) -> None:
    senders: list[str] = []

    class SendingThreads(Listener):
        def on_sent(self, sent: SentFrame) -> None:
            senders.append(threading.current_thread().name)

    session = Session(fake_radio, [SendingThreads()])
    model = SwarmTracker(session, fake_radio.now)
    session.add_listener(model)
    with session:
        fake_radio.inject(status_frame(1, state=int(State.CYCLING)))
        assert wait_until(lambda: len(model.rows()) == 1)
        model.stop()  # the first copy of the burst, from this thread
        fake_radio.clock.advance(0.15)  # the second copy is due...
        fake_radio.inject(status_frame(1, state=int(State.CYCLING)))  # ...when a frame comes
        assert wait_until(lambda: model.rows()[0].frames == 2)
    # The session is closed, so the receive thread has finished whatever the frame set off.
    assert senders and set(senders) == {threading.current_thread().name}
