"""StreamDecoder: resynchronisation, per-source reassembly, truncation and drop statistics."""

from __future__ import annotations

import itertools
from collections.abc import Hashable

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from particlebot.protocol import (
    SYNC,
    DropEvent,
    DropReason,
    Frame,
    Intensity,
    MessageType,
    Ping,
    Status,
    StreamDecoder,
    encode_frame,
)
from particlebot.protocol.frames import encode_raw_frame
from tests.protocol.protocol_reference import reference_scan

SYNC0, SYNC1 = SYNC

# Frames of any type and payload size, as bytes.
frames_st = st.builds(
    encode_raw_frame,
    st.integers(0, 255),
    st.integers(0, 255),
    st.integers(0, 255),
    st.binary(max_size=48),
)
# Garbage that often looks like the start of a frame.
garbage_st = st.lists(
    st.one_of(st.sampled_from([SYNC0, SYNC1, 0, 3, 48, 49, 255]), st.integers(0, 255)),
    max_size=60,
).map(bytes)


def _mutate(frame: bytes, data: st.DataObject) -> bytes:
    kind = data.draw(st.sampled_from(["flip", "cut", "insert", "length", "none"]))
    position = data.draw(st.integers(0, len(frame) - 1))
    if kind == "flip":
        return frame[:position] + bytes([frame[position] ^ 0x5A]) + frame[position + 1 :]
    if kind == "cut":
        return frame[:position]
    if kind == "insert":
        return frame[:position] + bytes([data.draw(st.integers(0, 255))]) + frame[position:]
    if kind == "length":
        return frame[:2] + bytes([data.draw(st.integers(0, 255))]) + frame[3:]
    return frame


def _as_tuples(frames: list[Frame]) -> list[tuple[int, int, int, bytes]]:
    return [(frame.type, frame.sender, frame.seq, frame.payload) for frame in frames]


def _split(stream: bytes, data: st.DataObject) -> list[bytes]:
    cuts = sorted(data.draw(st.lists(st.integers(0, len(stream)), max_size=8)))
    bounds = [0, *cuts, len(stream)]
    return [stream[a:b] for a, b in itertools.pairwise(bounds)]


@pytest.mark.slow
@settings(max_examples=300, derandomize=True)
@given(data=st.data())
def test_decoder_matches_the_naive_reference_scan_on_mutated_streams(data: st.DataObject) -> None:
    pieces = data.draw(st.lists(st.one_of(garbage_st, frames_st), max_size=8))
    stream = b"".join(
        _mutate(piece, data) if piece and data.draw(st.booleans()) else piece for piece in pieces
    )
    decoder = StreamDecoder()
    frames: list[Frame] = []
    for chunk in _split(stream, data):
        frames += decoder.feed(chunk)
    frames += decoder.flush()
    expected = reference_scan(stream)
    assert _as_tuples(frames) == expected.frames
    counts = decoder.stats.as_dict()
    assert {key: counts[key] for key in expected.counts} == expected.counts


@pytest.mark.slow
@settings(max_examples=200, derandomize=True)
@given(frames=st.lists(frames_st, min_size=1, max_size=6), data=st.data())
def test_every_frame_not_overlapped_by_garbage_is_recovered(
    frames: list[bytes], data: st.DataObject
) -> None:
    stream = b""
    for frame in frames:
        stream += data.draw(garbage_st) + frame
    stream += data.draw(garbage_st)
    decoder = StreamDecoder()
    decoded: list[Frame] = []
    for chunk in _split(stream, data):
        decoded += decoder.feed(chunk)
    decoded += decoder.flush()
    raws = [frame.raw for frame in decoded]
    # Garbage may hold a frame of its own (a CRC match by chance), so the real frames must appear
    # in order among those found.
    remaining = iter(raws)
    assert all(any(raw == frame for raw in remaining) for frame in frames)
    stats = decoder.stats
    dropped = stats.bad_crc + stats.bad_length + stats.truncated
    assert len(stream) == sum(len(raw) for raw in raws) + 2 * dropped + stats.skipped_bytes


@settings(max_examples=200, derandomize=True)
@given(data=st.data())
def test_frames_split_across_packets_of_interleaved_sources_are_reassembled_per_source(
    data: st.DataObject,
) -> None:
    sources: list[Hashable] = [None, 0x0013A200, ("xbee", 7)]
    streams = {
        source: data.draw(st.lists(frames_st, max_size=5), label=f"frames of {source}")
        for source in sources
    }
    packets: dict[Hashable, list[bytes]] = {
        source: _split(b"".join(frames), data) for source, frames in streams.items()
    }
    order = data.draw(
        st.permutations([source for source, chunks in packets.items() for _ in chunks])
    )
    decoder = StreamDecoder()
    received: dict[Hashable, list[bytes]] = {source: [] for source in sources}
    positions = dict.fromkeys(sources, 0)
    for source in order:
        chunk = packets[source][positions[source]]
        positions[source] += 1
        received[source] += [frame.raw for frame in decoder.feed(chunk, source)]
    for source in sources:
        assert received[source] == streams[source]
        assert decoder.buffered(source) == 0
    assert decoder.stats.skipped_bytes == 0
    assert decoder.stats.frames == sum(len(frames) for frames in streams.values())


@settings(max_examples=200, derandomize=True)
@given(st.lists(st.binary(max_size=80), max_size=10))
def test_decoder_never_raises_and_accounts_for_every_byte(chunks: list[bytes]) -> None:
    decoder = StreamDecoder()
    frames: list[Frame] = []
    for chunk in chunks:
        frames += decoder.feed(chunk, "radio")
    waiting = decoder.buffered("radio")
    assert waiting <= 56
    stats = decoder.stats
    dropped = stats.bad_crc + stats.bad_length + stats.truncated
    total = sum(len(chunk) for chunk in chunks)
    assert total == sum(len(f.raw) for f in frames) + 2 * dropped + stats.skipped_bytes + waiting


def test_a_truncated_frame_waits_then_is_counted_on_flush() -> None:
    status = encode_frame(Status.decode_payload(bytes(Status.PAYLOAD_SIZE)), 4, 1)
    decoder = StreamDecoder()
    assert decoder.feed(status[:20], "a") == []
    assert decoder.buffered("a") == 20
    assert decoder.stats.truncated == 0
    assert decoder.flush("a") == []
    assert decoder.stats.truncated == 1
    assert decoder.stats.skipped_bytes == 18
    assert decoder.buffered("a") == 0
    assert decoder.flush("a") == []
    assert decoder.stats.truncated == 1


def test_flush_finds_a_frame_hidden_in_a_truncated_one() -> None:
    ping = encode_frame(Ping(target=3), 0, 1)
    decoder = StreamDecoder()
    # A header announcing 40 payload bytes swallows the PING until the stream is declared over.
    assert decoder.feed(SYNC + bytes([40, 1, 2, 3]) + ping) == []
    flushed = decoder.flush()
    assert [frame.message for frame in flushed] == [Ping(target=3)]
    assert (decoder.stats.truncated, decoder.stats.skipped_bytes) == (1, 4)


def test_drop_events_say_what_was_dropped_why_and_from_where() -> None:
    seen: list[DropEvent] = []
    decoder = StreamDecoder(on_drop=seen.append)
    good = encode_frame(Intensity(run_id=1, round=0, repeat=2, intensity=700), 9, 3)
    bad_crc = good[:-1] + bytes([good[-1] ^ 1])
    decoder.feed(b"\x01\x02" + bad_crc + good, source="b")
    decoder.feed(SYNC + bytes([200]), source="c")
    reasons = [(event.reason, event.source) for event in seen]
    assert reasons[:3] == [
        (DropReason.SKIPPED, "b"),
        (DropReason.BAD_CRC, "b"),
        (DropReason.SKIPPED, "b"),
    ]
    assert seen[1].data == bad_crc
    assert (DropReason.BAD_LENGTH, "c") in reasons
    assert list(decoder.events) == seen


def test_frames_of_unknown_type_or_payload_size_are_returned_and_counted() -> None:
    decoder = StreamDecoder()
    unknown = encode_raw_frame(0x7F, 1, 1, b"abc")
    wrong_size = encode_raw_frame(MessageType.STATUS, 1, 2, b"\x00" * 3)
    frames = decoder.feed(unknown + wrong_size)
    assert [frame.message for frame in frames] == [None, None]
    stats = decoder.stats
    assert (stats.frames, stats.unknown_type, stats.bad_payload) == (2, 1, 1)
    assert [event.reason for event in decoder.events] == [
        DropReason.UNKNOWN_TYPE,
        DropReason.BAD_PAYLOAD,
    ]


def test_the_event_log_keeps_only_the_most_recent_events() -> None:
    decoder = StreamDecoder(keep_events=3)
    for _ in range(10):
        decoder.feed(SYNC + bytes([99]))
    assert len(decoder.events) == 3
    assert decoder.stats.bad_length == 10
