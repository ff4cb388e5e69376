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
from particlebot.firmware.native import NativeParticle
from particlebot.protocol import (
    DEFINITION_HASH,
    MAX_PAYLOAD,
    GetParam,
    Param,
    ParamValue,
    StreamDecoder,
)
from particlebot.protocol.frames import encode_raw_frame
from tests.firmware.conftest import Bench


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


def test_a_library_the_override_names_but_that_is_missing_says_so(tmp_path: Path) -> None:
    missing = tmp_path / "libparticle.so"
    env = dict(os.environ, PARTICLEBOT_NATIVE_LIB=str(missing))
    code = (
        "from particlebot.firmware.native import NativeParticle, NativeLibraryError\n"
        "try:\n    NativeParticle()\nexcept NativeLibraryError as e:\n    print(e)\n"
    )
    result = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True
    )
    # The override is what is wrong, so it is what the line says to fix (not `make native`).
    assert f"not found at {missing}: fix PARTICLEBOT_NATIVE_LIB" in result.stdout


def test_a_settings_image_boots_a_particle_with_its_id_and_values() -> None:
    image = native.settings_image(42, {Param.ROUND_MS: 1500, Param.CYCLE_STEPS: 300})
    assert len(image) == native.EEPROM_SIZE
    bench = Bench(NativeParticle(eeprom=image, rng_seed=7))
    try:
        assert bench.particle.id == 42
        assert bench.status().resets == 1  # this boot: the image itself counted none
        for param, value in ((Param.ROUND_MS, 1500), (Param.CYCLE_STEPS, 300)):
            bench.send(GetParam(target=42, param=param))
            replies = [f.message for f in bench.collect() if isinstance(f.message, ParamValue)]
            assert [(r.param, r.value) for r in replies] == [(param, value)]
    finally:
        bench.particle.close()


@pytest.mark.parametrize(
    ("particle_id", "params", "complaint"),
    [
        (1, {Param.ROUND_MS: 10}, "ROUND_MS=10 refused by the firmware: OUT_OF_RANGE"),
        (254, {}, "id 254 is outside 1..253"),
    ],
)
def test_a_settings_image_refuses_what_the_firmware_refuses(
    particle_id: int, params: dict[Param, int], complaint: str
) -> None:
    with pytest.raises(ValueError, match=complaint):
        native.settings_image(particle_id, params)
