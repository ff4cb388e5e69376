"""The ctypes binding itself: library lookup, pure functions and particle lifetime."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from particlebot.firmware import native
from particlebot.protocol import DEFINITION_HASH, MAX_PAYLOAD, StreamDecoder
from particlebot.protocol.frames import encode_raw_frame


def test_the_library_was_built_from_the_same_protocol_definition() -> None:
    assert native.definition_hash() == DEFINITION_HASH


@settings(max_examples=100, deadline=None)
@given(
    frame_type=st.integers(0, 255),
    sender=st.integers(0, 255),
    seq=st.integers(0, 255),
    payload=st.binary(max_size=MAX_PAYLOAD),
)
def test_encode_frame_matches_the_host_codec(
    frame_type: int, sender: int, seq: int, payload: bytes
) -> None:
    assert native.encode_frame(frame_type, sender, seq, payload) == encode_raw_frame(
        frame_type, sender, seq, payload
    )


def test_encode_frame_refuses_an_oversized_payload() -> None:
    with pytest.raises(ValueError, match="does not fit"):
        native.encode_frame(1, 0, 0, bytes(MAX_PAYLOAD + 1))


@settings(max_examples=100, deadline=None)
@given(
    chunks=st.lists(
        st.one_of(
            st.binary(max_size=12),
            st.tuples(st.integers(0, 255), st.binary(max_size=MAX_PAYLOAD)).map(
                lambda t: encode_raw_frame(t[0], 7, 1, t[1])
            ),
        ),
        max_size=8,
    )
)
def test_parse_stream_accepts_what_the_host_decoder_accepts(chunks: list[bytes]) -> None:
    data = b"".join(chunks)
    frames, counters = native.parse_stream(data)
    host = StreamDecoder().feed(data)
    assert [(f.type, f.sender, f.seq, f.payload) for f in frames] == [
        (f.type, f.sender, f.seq, f.payload) for f in host
    ]
    assert counters.frames == len(frames)


def test_a_closed_particle_refuses_calls_and_closing_twice_is_harmless() -> None:
    with native.NativeParticle() as particle:
        particle.tick(10)
    particle.close()
    with pytest.raises(ValueError, match="closed"):
        particle.tick(20)


def test_wrong_adc_input_is_rejected() -> None:
    with native.NativeParticle() as particle:
        with pytest.raises(ValueError):
            particle.set_adc([1, 2, 3])
        with pytest.raises(ValueError):
            particle.set_adc([70000] * 6)


def test_a_missing_library_names_the_make_target(tmp_path: Path) -> None:
    env = dict(os.environ, PARTICLEBOT_NATIVE_LIB=str(tmp_path / "libparticle.so"))
    code = (
        "from particlebot.firmware.native import NativeParticle, NativeLibraryError\n"
        "try:\n    NativeParticle()\nexcept NativeLibraryError as e:\n    print(e)\n"
    )
    result = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True
    )
    assert "make native" in result.stdout
