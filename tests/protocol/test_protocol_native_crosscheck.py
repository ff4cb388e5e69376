"""The firmware's C++ frame codec (build/native/libparticle.so) against the host's Python codec."""

from __future__ import annotations

import ctypes
import os
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from particlebot.protocol import SYNC, StreamDecoder
from particlebot.protocol.frames import encode_raw_frame
from tests.protocol.protocol_reference import REPO_ROOT

_u8p = ctypes.POINTER(ctypes.c_uint8)


def _load() -> ctypes.CDLL | None:
    path = Path(os.environ.get("PARTICLEBOT_NATIVE_LIB", REPO_ROOT / "build/native/libparticle.so"))
    if not path.exists():
        return None
    try:
        lib = ctypes.CDLL(str(path))
        parse, encode = lib.pb_parse_stream, lib.pb_encode_frame
    except (OSError, AttributeError):
        return None
    parse.argtypes = [_u8p, ctypes.c_size_t, _u8p, ctypes.c_size_t, ctypes.POINTER(ctypes.c_uint16)]
    parse.restype = ctypes.c_size_t
    encode.argtypes = [ctypes.c_uint8] * 3 + [_u8p, ctypes.c_size_t, _u8p, ctypes.c_size_t]
    encode.restype = ctypes.c_size_t
    return lib


LIB = _load()
pytestmark = pytest.mark.skipif(
    LIB is None,
    reason="build/native/libparticle.so with pb_parse_stream is not built (make native)",
)


def _buffer(data: bytes) -> ctypes.Array[ctypes.c_uint8]:
    return (ctypes.c_uint8 * max(1, len(data))).from_buffer_copy(data.ljust(1, b"\0"))


def native_parse(data: bytes) -> tuple[list[tuple[int, int, int, bytes]], list[int]]:
    assert LIB is not None
    capacity = len(data) + 64
    out = (ctypes.c_uint8 * capacity)()
    counters = (ctypes.c_uint16 * 4)()
    written = LIB.pb_parse_stream(_buffer(data), len(data), out, capacity, counters)
    raw, frames, i = bytes(out[:written]), [], 0
    while i < len(raw):
        length = raw[i + 3]
        frames.append((raw[i], raw[i + 1], raw[i + 2], raw[i + 4 : i + 4 + length]))
        i += 4 + length
    return frames, list(counters)


def native_encode(frame_type: int, sender: int, seq: int, payload: bytes) -> bytes:
    assert LIB is not None
    out = (ctypes.c_uint8 * 64)()
    size = LIB.pb_encode_frame(frame_type, sender, seq, _buffer(payload), len(payload), out, 64)
    return bytes(out[:size])


def _ends_the_stream() -> bool:
    """Whether pb_parse_stream treats the end of its input as a timeout (drops a partial frame)."""
    return native_parse(SYNC + b"\x05")[1][2] == 1


# Without an end-of-stream timeout the C++ parser may still hold bytes queued after a frame found
# by a rescan; enough non-sync bytes make both sides scan everything.
TERMINATOR = bytes(2 * 56)

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


@settings(max_examples=400, derandomize=True)
@given(stream=mutated_streams())
def test_cpp_parser_and_python_decoder_accept_exactly_the_same_frames(stream: bytes) -> None:
    decoder = StreamDecoder()
    if _ends_the_stream():
        native_frames, counters = native_parse(stream)
        frames = decoder.feed(stream) + decoder.flush()
    else:
        native_frames, counters = native_parse(stream + TERMINATOR)
        frames = decoder.feed(stream + TERMINATOR)
    assert native_frames == [(f.type, f.sender, f.seq, f.payload) for f in frames]
    stats = decoder.stats
    # The firmware counts a truncated frame as a bad length.
    assert counters == [
        stats.frames,
        stats.bad_crc,
        stats.bad_length + stats.truncated,
        stats.skipped_bytes,
    ]


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
    assert native_encode(frame_type, sender, seq, payload) == encode_raw_frame(
        frame_type, sender, seq, payload
    )


def test_cpp_encoder_refuses_a_payload_over_max_payload() -> None:
    assert native_encode(1, 2, 3, bytes(49)) == b""
