"""Golden frames of shared/vectors.toml against the Python codec; the C++ tests read them too."""

from __future__ import annotations

import dataclasses
from typing import Any

import pytest

from particlebot.protocol import (
    MESSAGES,
    Frame,
    MessageType,
    StreamDecoder,
    crc16,
    decode_frame,
    encode_frame,
)
from tests.protocol.protocol_reference import bitwise_crc16, hex_bytes, load_vectors, reference_scan

VECTORS = load_vectors()
GOOD: list[dict[str, Any]] = VECTORS["vector"]
BAD: list[dict[str, Any]] = VECTORS["bad"]
COUNTERS = ("frames", "bad_crc", "bad_length", "truncated", "skipped_bytes")


def test_crc16_of_the_check_string_is_0x29b1() -> None:
    check = VECTORS["check"]
    assert check["crc16"] == 0x29B1
    assert crc16(check["crc16_input"].encode()) == 0x29B1
    assert bitwise_crc16(check["crc16_input"].encode()) == 0x29B1


def test_vectors_cover_every_message_type() -> None:
    assert {vector["type"] for vector in GOOD} == {member.name for member in MessageType}


def test_vectors_cover_extreme_values() -> None:
    values = [
        value
        for vector in GOOD
        for field_value in vector["fields"].values()
        for value in (field_value if isinstance(field_value, list) else [field_value])
    ]
    assert {0, 255, 65535, 2**32 - 1, -(2**31), 2**31 - 1} <= set(values)


@pytest.mark.parametrize("vector", GOOD, ids=[vector["name"] for vector in GOOD])
def test_golden_vector_decodes_to_its_fields_and_reencodes_to_the_same_bytes(
    vector: dict[str, Any],
) -> None:
    data = hex_bytes(vector["frame"])
    # The vector file's CRC is checked against the bitwise definition, not the codec under test.
    assert bitwise_crc16(data[2:-2]) == int.from_bytes(data[-2:], "little")
    frame = decode_frame(data)
    assert (frame.type, frame.sender, frame.seq) == (
        MessageType[vector["type"]],
        vector["sender"],
        vector["seq"],
    )
    message = frame.message
    assert message is not None
    assert type(message) is MESSAGES[MessageType[vector["type"]]]
    decoded = {
        item.name: list(value) if isinstance(value := getattr(message, item.name), tuple) else value
        for item in dataclasses.fields(message)
    }
    assert decoded == vector["fields"]
    assert encode_frame(message, vector["sender"], vector["seq"]) == data
    assert frame.raw == data


@pytest.mark.parametrize("vector", GOOD, ids=[vector["name"] for vector in GOOD])
def test_golden_vector_builds_from_its_fields(vector: dict[str, Any]) -> None:
    cls = MESSAGES[MessageType[vector["type"]]]
    arguments = {
        name: tuple(value) if isinstance(value, list) else value
        for name, value in vector["fields"].items()
    }
    message = cls(**arguments)
    assert encode_frame(message, vector["sender"], vector["seq"]) == hex_bytes(vector["frame"])


def _expected(bad: dict[str, Any]) -> dict[str, int]:
    return {name: bad[name] for name in COUNTERS}


@pytest.mark.parametrize("bad", BAD, ids=[bad["name"] for bad in BAD])
def test_bad_vector_gives_the_expected_counters(bad: dict[str, Any]) -> None:
    data = hex_bytes(bad["bytes"])
    decoder = StreamDecoder()
    frames = decoder.feed(data) + decoder.flush()
    counts = decoder.stats.as_dict()
    assert {name: counts[name] for name in COUNTERS} == _expected(bad)
    assert len(frames) == bad["frames"]
    assert bad[bad["expect"] if bad["expect"] != "skipped" else "skipped_bytes"] > 0
    # The naive reference agrees, so the file's hand-worked counts are not the decoder's echo.
    assert reference_scan(data).counts == _expected(bad)


@pytest.mark.parametrize("bad", BAD, ids=[bad["name"] for bad in BAD])
def test_bad_vector_gives_the_same_counters_byte_by_byte(bad: dict[str, Any]) -> None:
    decoder = StreamDecoder()
    frames: list[Frame] = []
    for byte in hex_bytes(bad["bytes"]):
        frames += decoder.feed(bytes([byte]))
    frames += decoder.flush()
    counts = decoder.stats.as_dict()
    assert {name: counts[name] for name in COUNTERS} == _expected(bad)
    assert len(frames) == bad["frames"]
