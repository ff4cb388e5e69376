"""Message payloads and single frames: round trips, CRC and every way a frame can be refused."""

from __future__ import annotations

import dataclasses
import tomllib

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from particlebot.protocol import (
    BASE_STATION_ID,
    BROADCAST_ID,
    FRAME_OVERHEAD,
    MAX_PAYLOAD,
    MESSAGES,
    PARAM_SPECS,
    SYNC,
    UNASSIGNED_ID,
    DropReason,
    Frame,
    FrameError,
    Message,
    MessageType,
    Param,
    PayloadError,
    Ping,
    SetParam,
    Status,
    Stop,
    crc16,
    decode_frame,
    encode_frame,
)
from particlebot.protocol.frames import encode_raw_frame
from tests.protocol.protocol_reference import DEFINITION, bitwise_crc16

MESSAGE_CLASSES = sorted(MESSAGES.values(), key=lambda cls: cls.MESSAGE_TYPE)
SIZES = {"u8": 1, "u16": 2, "u32": 4, "i8": 1, "i16": 2, "i32": 4}


@given(st.binary(max_size=300))
def test_crc16_agrees_with_the_bitwise_definition(data: bytes) -> None:
    assert crc16(data) == bitwise_crc16(data)


def test_crc16_continues_from_a_previous_value() -> None:
    assert crc16(b"56789", crc16(b"1234")) == 0x29B1


def test_generated_layout_matches_the_definition_file() -> None:
    definition = tomllib.loads(DEFINITION.read_text())
    assert bytes(definition["frame"]["sync"]) == SYNC
    assert definition["frame"]["max_payload"] == MAX_PAYLOAD
    assert (BASE_STATION_ID, BROADCAST_ID, UNASSIGNED_ID) == (0, 255, 254)
    assert FRAME_OVERHEAD == 8
    by_name = {cls.MESSAGE_TYPE.name: cls for cls in MESSAGE_CLASSES}
    assert set(by_name) == {message["name"] for message in definition["message"]}
    for message in definition["message"]:
        cls = by_name[message["name"]]
        assert message["id"] == cls.MESSAGE_TYPE
        assert message["from"] == cls.SENT_BY
        size = sum(SIZES[field["type"]] * field.get("count", 1) for field in message["fields"])
        assert size == cls.PAYLOAD_SIZE
        names = [field.name for field in dataclasses.fields(cls)]
        assert names == [field["name"] for field in message["fields"]]
    params = definition["enums"]["param"]
    assert {param.name for param in PARAM_SPECS} == {key for key in params if key != "description"}
    for param, spec in PARAM_SPECS.items():
        entry = params[param.name]
        assert (param.value, spec.default, spec.min, spec.max) == (
            entry["value"],
            entry["default"],
            entry["min"],
            entry["max"],
        )


@pytest.mark.parametrize("cls", MESSAGE_CLASSES, ids=lambda cls: cls.__name__)
@settings(max_examples=60)
@given(data=st.data())
def test_every_message_round_trips_through_payload_and_frame(
    cls: type[Message], data: st.DataObject
) -> None:
    # Every byte string of the right size is a valid payload, so this reaches every field value.
    payload = data.draw(st.binary(min_size=cls.PAYLOAD_SIZE, max_size=cls.PAYLOAD_SIZE))
    sender = data.draw(st.integers(0, 255))
    seq = data.draw(st.integers(0, 255))
    message = cls.decode_payload(payload)
    assert message.encode_payload() == payload
    frame = encode_frame(message, sender, seq)
    assert len(frame) == FRAME_OVERHEAD + cls.PAYLOAD_SIZE
    decoded = decode_frame(frame)
    assert (decoded.type, decoded.sender, decoded.seq) == (cls.MESSAGE_TYPE, sender, seq)
    assert decoded.message == message
    assert cls(**{f.name: getattr(message, f.name) for f in dataclasses.fields(message)}) == message


@pytest.mark.parametrize("cls", MESSAGE_CLASSES, ids=lambda cls: cls.__name__)
def test_decode_payload_refuses_a_payload_of_the_wrong_size(cls: type[Message]) -> None:
    for size in (cls.PAYLOAD_SIZE - 1, cls.PAYLOAD_SIZE + 1):
        if size >= 0:
            with pytest.raises(PayloadError):
                cls.decode_payload(bytes(size))


def test_encode_payload_refuses_values_that_do_not_fit() -> None:
    with pytest.raises(PayloadError):
        Ping(target=256).encode_payload()
    with pytest.raises(PayloadError):
        SetParam(target=1, param=Param.CYCLE_STEPS, value=2**31).encode_payload()
    status = Status.decode_payload(bytes(Status.PAYLOAD_SIZE))
    with pytest.raises(PayloadError):
        dataclasses.replace(status, sensors=(1, 2, 3)).encode_payload()


def test_i32_extremes_survive_the_round_trip() -> None:
    for value in (-(2**31), -1, 0, 2**31 - 1):
        frame = encode_frame(SetParam(target=255, param=Param.SERVO_CAL_8, value=value), 0, 1)
        assert decode_frame(frame).message == SetParam(255, Param.SERVO_CAL_8, value)


def test_enum_fields_accept_the_enum_and_decode_as_plain_ints() -> None:
    message = SetParam(target=3, param=Param.ROUND_MS, value=5000)
    decoded = decode_frame(encode_frame(message, 0, 0)).message
    assert isinstance(decoded, SetParam)
    assert decoded.param == Param.ROUND_MS
    assert decoded == message


def _valid() -> bytes:
    return encode_frame(Ping(target=7), 0, 42)


@pytest.mark.parametrize(
    ("data", "reason"),
    [
        (b"", DropReason.SKIPPED),
        (b"\x00" + _valid()[1:], DropReason.SKIPPED),
        (_valid()[:-1], DropReason.TRUNCATED),
        (_valid() + b"\x00", DropReason.SKIPPED),
        (_valid()[:-1] + bytes([_valid()[-1] ^ 0x40]), DropReason.BAD_CRC),
        (SYNC + bytes([MAX_PAYLOAD + 1]) + bytes(MAX_PAYLOAD + 6), DropReason.BAD_LENGTH),
    ],
    ids=["empty", "no_sync", "short", "trailing_byte", "bad_crc", "len_over_max"],
)
def test_decode_frame_refuses_anything_but_one_valid_frame(data: bytes, reason: DropReason) -> None:
    with pytest.raises(FrameError) as caught:
        decode_frame(data)
    assert caught.value.reason is reason


def test_encode_refuses_a_payload_over_max_payload_and_non_byte_header_fields() -> None:
    with pytest.raises(FrameError):
        encode_raw_frame(0x40, 1, 1, bytes(MAX_PAYLOAD + 1))
    with pytest.raises(FrameError):
        encode_frame(Stop(), 256, 0)
    assert len(encode_raw_frame(0x40, 1, 1, bytes(MAX_PAYLOAD))) == MAX_PAYLOAD + FRAME_OVERHEAD


def test_a_frame_of_unknown_type_or_wrong_size_is_valid_but_has_no_message() -> None:
    unknown = decode_frame(encode_raw_frame(0x7E, 3, 4, b"\x01\x02"))
    assert unknown.message is None
    assert unknown.type_name == "0x7E"
    wrong_size = decode_frame(encode_raw_frame(MessageType.PING, 3, 4, b"\x01\x02"))
    assert wrong_size.message is None
    assert wrong_size.type_name == "PING"


def test_frame_raw_gives_back_the_bytes_on_the_air() -> None:
    data = _valid()
    assert decode_frame(data).raw == data
    assert Frame(MessageType.PING, 0, 42, b"\x07").raw == data
