"""The firmware's C++ frame codec (through the native library) against the host's Python codec."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from particlebot.firmware import native
from particlebot.protocol import SYNC, StreamDecoder
from particlebot.protocol.frames import encode_raw_frame

frames_st = st.builds(
    encode_raw_frame,
    st.integers(0, 255),
    st.integers(0, 255),
    st.integers(0, 255),
    st.binary(max_size=48),
)
noise_st = st.lists(
    st.one_of(st.sampled_from([SYNC[0], SYNC[1], 0, 5, 48, 49]), st.integers(0, 255)),
    max_size=40,
).map(bytes)


@st.composite
def mutated_streams(draw: st.DrawFn) -> bytes:
    stream = b""
    for piece in draw(st.lists(st.one_of(frames_st, noise_st), max_size=8)):
        if piece and draw(st.booleans()):
            at = draw(st.integers(0, len(piece) - 1))
            edit = draw(st.sampled_from(["flip", "cut", "insert", "drop"]))
            if edit == "flip":
                piece = (
                    piece[:at] + bytes([piece[at] ^ draw(st.integers(1, 255))]) + piece[at + 1 :]
                )
            elif edit == "cut":
                piece = piece[:at]
            elif edit == "insert":
                piece = piece[:at] + bytes([draw(st.integers(0, 255))]) + piece[at:]
            else:
                piece = piece[:at] + piece[at + 1 :]
        stream += piece
    return stream


@pytest.mark.slow
@settings(max_examples=400, derandomize=True)
@given(stream=mutated_streams())
def test_cpp_parser_and_python_decoder_accept_exactly_the_same_frames(stream: bytes) -> None:
    # The end of the input is a pause in the stream for both: the firmware's parser treats it as
    # its 100 ms idle timeout, the decoder is flushed.
    native_frames, counters = native.parse_stream(stream)
    decoder = StreamDecoder()
    frames = decoder.feed(stream) + decoder.flush()
    assert [(f.type, f.sender, f.seq, f.payload) for f in native_frames] == [
        (f.type, f.sender, f.seq, f.payload) for f in frames
    ]
    stats = decoder.stats
    # The firmware counts a truncated frame as a bad length.
    assert (counters.frames, counters.bad_crc, counters.bad_length, counters.skipped_bytes) == (
        stats.frames,
        stats.bad_crc,
        stats.bad_length + stats.truncated,
        stats.skipped_bytes,
    )


@settings(max_examples=200, derandomize=True)
@given(
    frame_type=st.integers(0, 255),
    sender=st.integers(0, 255),
    seq=st.integers(0, 255),
    payload=st.binary(max_size=48),
)
def test_cpp_and_python_encoders_write_the_same_frame(
    frame_type: int, sender: int, seq: int, payload: bytes
) -> None:
    assert native.encode_frame(frame_type, sender, seq, payload) == encode_raw_frame(
        frame_type, sender, seq, payload
    )


def test_cpp_encoder_refuses_a_payload_over_max_payload() -> None:
    with pytest.raises(ValueError, match="does not fit"):
        native.encode_frame(1, 2, 3, bytes(49))
