"""Reads shared/protocol.toml once: checks it and gives the Definition both emitters write."""

from __future__ import annotations

import json
import keyword
import re
import tomllib
import zlib
from dataclasses import dataclass
from typing import Any

# Bump when the shape of the generated code changes: hand-written code that depends on it states the
# version it expects (frame.h), so a header from another generator stops the build.
GENERATOR_VERSION = 2

# The definition's path in the repository, as the generated files name it.
DEFINITION = "shared/protocol.toml"

SUPPORTED_CRC = "crc16-ccitt-false"
FRAME_OVERHEAD = 8  # sync (2), len, type, sender, seq, crc (2)
INT32_MIN = -(2**31)
INT32_MAX = 2**31 - 1


@dataclass(frozen=True)
class WireType:
    """One scalar type a field may have."""

    size: int
    signed: bool
    cpp: str
    struct_code: str

    @property
    def bits(self) -> int:
        return self.size * 8

    @property
    def low(self) -> int:
        return -(1 << (self.bits - 1)) if self.signed else 0

    @property
    def high(self) -> int:
        return (1 << (self.bits - 1)) - 1 if self.signed else (1 << self.bits) - 1


WIRE_TYPES: dict[str, WireType] = {
    "u8": WireType(1, False, "uint8_t", "B"),
    "u16": WireType(2, False, "uint16_t", "H"),
    "u32": WireType(4, False, "uint32_t", "I"),
    "i8": WireType(1, True, "int8_t", "b"),
    "i16": WireType(2, True, "int16_t", "h"),
    "i32": WireType(4, True, "int32_t", "i"),
}

# Names the generated code defines itself; an enum or message must not take them.
RESERVED_TYPE_NAMES = {"MessageType", "Message", "ParamSpec", "PayloadError", "AnyMessage"}
CPP_KEYWORDS = {
    "alignas", "alignof", "and", "asm", "auto", "bool", "break", "case", "catch", "char", "class",
    "const", "constexpr", "continue", "default", "delete", "do", "double", "else", "enum",
    "explicit", "export", "extern", "false", "float", "for", "friend", "goto", "if", "inline",
    "int", "long", "mutable", "namespace", "new", "noexcept", "not", "nullptr", "operator", "or",
    "private", "protected", "public", "register", "return", "short", "signed", "sizeof", "static",
    "struct", "switch", "template", "this", "throw", "true", "try", "typedef", "typeid",
    "typename", "union", "unsigned", "using", "virtual", "void", "volatile", "while", "xor",
}  # fmt: skip
# Field names the message structs and dataclasses already use for their own members.
RESERVED_FIELD_NAMES = {"encode", "decode", "encode_payload", "decode_payload", "kType"}

SNAKE = re.compile(r"^[a-z][a-z0-9_]*$")
UPPER_SNAKE = re.compile(r"^[A-Z][A-Z0-9_]*$")


class DefinitionError(Exception):
    """The protocol definition is malformed; the message lists every problem found."""


@dataclass(frozen=True)
class FrameDef:
    sync: tuple[int, int]
    max_payload: int
    crc: str
    base_station_id: int
    broadcast_id: int
    unassigned_id: int


@dataclass(frozen=True)
class ParamRange:
    default: int
    min: int
    max: int


@dataclass(frozen=True)
class EnumMember:
    name: str
    value: int
    description: str
    param: ParamRange | None


@dataclass(frozen=True)
class EnumDef:
    key: str
    description: str
    members: tuple[EnumMember, ...]

    @property
    def type_name(self) -> str:
        return camel(self.key)


@dataclass(frozen=True)
class FieldDef:
    name: str
    type: str
    count: int | None
    enum: str | None
    description: str

    @property
    def wire(self) -> WireType:
        return WIRE_TYPES[self.type]

    @property
    def size(self) -> int:
        return self.wire.size * (self.count or 1)


@dataclass(frozen=True)
class MessageDef:
    name: str
    id: int
    sent_by: str
    description: str
    fields: tuple[FieldDef, ...]

    @property
    def type_name(self) -> str:
        return camel(self.name.lower())

    @property
    def payload_size(self) -> int:
        return sum(field.size for field in self.fields)


@dataclass(frozen=True)
class Definition:
    frame: FrameDef
    enums: tuple[EnumDef, ...]
    messages: tuple[MessageDef, ...]

    def canonical(self) -> dict[str, Any]:
        """Everything that changes what goes over the air or what a value means; no descriptions."""
        enums: dict[str, Any] = {}
        for enum in self.enums:
            members: dict[str, Any] = {}
            for member in enum.members:
                entry: dict[str, Any] = {"value": member.value}
                if member.param is not None:
                    entry.update(
                        default=member.param.default, min=member.param.min, max=member.param.max
                    )
                members[member.name] = entry
            enums[enum.key] = members
        messages = [
            {
                "name": message.name,
                "id": message.id,
                "from": message.sent_by,
                "fields": [
                    {
                        "name": field.name,
                        "type": field.type,
                        "count": field.count or 1,
                        "enum": field.enum,
                    }
                    for field in message.fields
                ],
            }
            for message in self.messages
        ]
        frame = {
            "sync": list(self.frame.sync),
            "max_payload": self.frame.max_payload,
            "crc": self.frame.crc,
            "base_station_id": self.frame.base_station_id,
            "broadcast_id": self.frame.broadcast_id,
            "unassigned_id": self.frame.unassigned_id,
        }
        return {"frame": frame, "enums": enums, "messages": messages}

    @property
    def hash(self) -> int:
        text = json.dumps(self.canonical(), sort_keys=True, separators=(",", ":"))
        return zlib.crc32(text.encode("ascii")) & 0xFFFFFFFF

    def enum(self, key: str) -> EnumDef:
        return next(enum for enum in self.enums if enum.key == key)


def camel(snake: str) -> str:
    return "".join(part.capitalize() for part in snake.split("_"))


# ---- parsing and validation ---------------------------------------------------------------------


class _Checker:
    """Collects every problem in the definition so one run reports them all."""

    def __init__(self) -> None:
        self.problems: list[str] = []

    def fail(self, where: str, problem: str) -> None:
        self.problems.append(f"{where}: {problem}")

    def keys(
        self, where: str, table: dict[str, Any], allowed: set[str], required: set[str]
    ) -> None:
        for key in sorted(set(table) - allowed):
            self.fail(where, f"unknown key {key!r}")
        for key in sorted(required - set(table)):
            self.fail(where, f"missing key {key!r}")

    def integer(self, where: str, value: Any, low: int, high: int) -> int:
        if isinstance(value, bool) or not isinstance(value, int):
            self.fail(where, f"expected an integer, got {value!r}")
            return low
        if not low <= value <= high:
            self.fail(where, f"{value} is outside {low}..{high}")
        return value

    def text(self, where: str, value: Any) -> str:
        if not isinstance(value, str):
            self.fail(where, f"expected a string, got {value!r}")
            return ""
        if '"""' in value or "\\" in value or "\n" in value or "*/" in value:
            self.fail(where, 'descriptions may not contain \'"""\', "*/", backslashes or newlines')
        return value

    def table(self, where: str, value: Any) -> dict[str, Any]:
        if not isinstance(value, dict):
            self.fail(where, f"expected a table, got {value!r}")
            return {}
        return value


def parse(text: str) -> Definition:
    """Parses and validates a protocol definition; raises DefinitionError listing every problem."""
    try:
        document = tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        raise DefinitionError(f"not valid TOML: {error}") from None
    check = _Checker()
    check.keys("top level", document, {"frame", "enums", "message"}, {"frame", "enums", "message"})
    frame = _parse_frame(check, check.table("[frame]", document.get("frame", {})))
    enums = _parse_enums(check, check.table("[enums]", document.get("enums", {})))
    raw_messages = document.get("message", [])
    if not isinstance(raw_messages, list):
        check.fail("[[message]]", "expected an array of tables")
        raw_messages = []
    messages = _parse_messages(check, raw_messages, frame, enums)
    if check.problems:
        raise DefinitionError("\n".join(check.problems))
    return Definition(frame, enums, messages)


def _parse_frame(check: _Checker, table: dict[str, Any]) -> FrameDef:
    names = {"sync", "max_payload", "crc", "base_station_id", "broadcast_id", "unassigned_id"}
    check.keys("[frame]", table, names, names)
    sync = table.get("sync", [0, 0])
    if not isinstance(sync, list) or len(sync) != 2:
        check.fail("[frame] sync", "expected two bytes")
        sync = [0, 0]
    sync0 = check.integer("[frame] sync[0]", sync[0], 0, 255)
    sync1 = check.integer("[frame] sync[1]", sync[1], 0, 255)
    if sync0 == sync1:
        check.fail("[frame] sync", "the two sync bytes must differ")
    # LEN is one byte and the whole frame must stay addressable by a uint8_t index.
    max_payload = check.integer("[frame] max_payload", table.get("max_payload"), 1, 255 - 8)
    crc = check.text("[frame] crc", table.get("crc", ""))
    if crc != SUPPORTED_CRC:
        check.fail("[frame] crc", f"only {SUPPORTED_CRC!r} is supported")
    ids = {
        name: check.integer(f"[frame] {name}", table.get(name), 0, 255)
        for name in ("base_station_id", "broadcast_id", "unassigned_id")
    }
    if len(set(ids.values())) != len(ids):
        check.fail("[frame]", "base_station_id, broadcast_id and unassigned_id must differ")
    return FrameDef(
        sync=(sync0, sync1),
        max_payload=max_payload,
        crc=crc,
        base_station_id=ids["base_station_id"],
        broadcast_id=ids["broadcast_id"],
        unassigned_id=ids["unassigned_id"],
    )


def _parse_enums(check: _Checker, table: dict[str, Any]) -> tuple[EnumDef, ...]:
    enums: list[EnumDef] = []
    for key, raw in table.items():
        where = f"[enums.{key}]"
        body = check.table(where, raw)
        if not SNAKE.match(key):
            check.fail(where, "enum names are snake_case")
        if camel(key) in RESERVED_TYPE_NAMES:
            check.fail(where, f"{camel(key)} is a name the generated code uses itself")
        description = check.text(f"{where} description", body.get("description", ""))
        if "description" not in body:
            check.fail(where, "missing key 'description'")
        members: list[EnumMember] = []
        values: dict[int, str] = {}
        for name, raw_member in body.items():
            if name == "description":
                continue
            member_where = f"{where} {name}"
            if not UPPER_SNAKE.match(name):
                check.fail(member_where, "enum members are UPPER_SNAKE_CASE")
            member = check.table(member_where, raw_member)
            ranged = {"default", "min", "max"}
            check.keys(member_where, member, {"value", "description"} | ranged, {"value"})
            value = check.integer(f"{member_where} value", member.get("value"), 0, 255)
            if value in values:
                check.fail(member_where, f"value {value} already used by {values[value]}")
            values[value] = name
            param: ParamRange | None = None
            present = ranged & set(member)
            if present and present != ranged:
                check.fail(member_where, "give all of default, min and max, or none")
            elif present:
                low = check.integer(f"{member_where} min", member["min"], INT32_MIN, INT32_MAX)
                high = check.integer(f"{member_where} max", member["max"], INT32_MIN, INT32_MAX)
                default = check.integer(f"{member_where} default", member["default"], low, high)
                if low > high:
                    check.fail(member_where, f"min {low} is above max {high}")
                param = ParamRange(default, low, high)
            members.append(
                EnumMember(
                    name=name,
                    value=value,
                    description=check.text(
                        f"{member_where} description", member.get("description", "")
                    ),
                    param=param,
                )
            )
        if not members:
            check.fail(where, "an enum needs at least one member")
        with_range = sum(member.param is not None for member in members)
        if with_range not in (0, len(members)):
            check.fail(where, "either every member has default/min/max or none has")
        enums.append(EnumDef(key, description, tuple(members)))
    if not any(enum.key == "param" for enum in enums):
        check.fail("[enums]", "the param enum (SET_PARAM's parameters) is missing")
    elif any(member.param is None for member in next(e for e in enums if e.key == "param").members):
        check.fail("[enums.param]", "every parameter needs default, min and max")
    return tuple(enums)


def _parse_messages(
    check: _Checker, raw_messages: list[Any], frame: FrameDef, enums: tuple[EnumDef, ...]
) -> tuple[MessageDef, ...]:
    messages: list[MessageDef] = []
    names: set[str] = set()
    ids: dict[int, str] = {}
    enum_by_key = {enum.key: enum for enum in enums}
    for index, raw in enumerate(raw_messages):
        body = check.table(f"[[message]] #{index + 1}", raw)
        name = body.get("name", f"#{index + 1}")
        where = f"message {name}"
        allowed = {"name", "id", "from", "description", "fields"}
        check.keys(where, body, allowed, allowed)
        if not isinstance(name, str) or not UPPER_SNAKE.match(name):
            check.fail(where, "message names are UPPER_SNAKE_CASE strings")
            name = f"INVALID_{index}"
        if name in names:
            check.fail(where, "name used twice")
        names.add(name)
        if camel(name.lower()) in RESERVED_TYPE_NAMES or camel(name.lower()) in {
            enum.type_name for enum in enums
        }:
            check.fail(where, f"{camel(name.lower())} clashes with a generated type name")
        message_id = check.integer(f"{where} id", body.get("id"), 0, 255)
        if message_id in ids:
            check.fail(where, f"id 0x{message_id:02X} already used by {ids[message_id]}")
        ids[message_id] = name
        sent_by = body.get("from")
        if sent_by not in ("base", "particle"):
            check.fail(where, "from must be 'base' or 'particle'")
            sent_by = "base"
        raw_fields = body.get("fields", [])
        if not isinstance(raw_fields, list):
            check.fail(where, "fields must be an array of inline tables")
            raw_fields = []
        fields = _parse_fields(check, where, raw_fields, enum_by_key)
        message = MessageDef(
            name=name,
            id=message_id,
            sent_by=sent_by,
            description=check.text(f"{where} description", body.get("description", "")),
            fields=fields,
        )
        if message.payload_size > frame.max_payload:
            check.fail(
                where,
                f"payload of {message.payload_size} bytes exceeds max_payload {frame.max_payload}",
            )
        messages.append(message)
    if not messages:
        check.fail("[[message]]", "no messages defined")
    return tuple(messages)


def _parse_fields(
    check: _Checker, where: str, raw_fields: list[Any], enums: dict[str, EnumDef]
) -> tuple[FieldDef, ...]:
    fields: list[FieldDef] = []
    seen: set[str] = set()
    for index, raw in enumerate(raw_fields):
        body = check.table(f"{where} field #{index + 1}", raw)
        name = body.get("name", f"#{index + 1}")
        field_where = f"{where} field {name}"
        check.keys(
            field_where,
            body,
            {"name", "type", "count", "enum", "description"},
            {"name", "type", "description"},
        )
        if not isinstance(name, str) or not SNAKE.match(name):
            check.fail(field_where, "field names are snake_case strings")
            name = f"invalid_{index}"
        if name in CPP_KEYWORDS or keyword.iskeyword(name) or name in RESERVED_FIELD_NAMES:
            check.fail(field_where, "field name is a C++ or Python keyword or a generated member")
        if name in seen:
            check.fail(field_where, "name used twice in this message")
        seen.add(name)
        type_name = body.get("type")
        if type_name not in WIRE_TYPES:
            check.fail(field_where, f"unknown type {type_name!r} (known: {', '.join(WIRE_TYPES)})")
            type_name = "u8"
        count: int | None = None
        if "count" in body:
            count = check.integer(f"{field_where} count", body["count"], 1, 255)
        enum_key = body.get("enum")
        if enum_key is not None:
            enum = enums.get(enum_key) if isinstance(enum_key, str) else None
            if enum is None:
                check.fail(field_where, f"unknown enum {enum_key!r}")
            else:
                wire = WIRE_TYPES[type_name]
                for member in enum.members:
                    if not wire.low <= member.value <= wire.high:
                        check.fail(field_where, f"{type_name} cannot hold {enum_key}.{member.name}")
        fields.append(
            FieldDef(
                name=name,
                type=type_name,
                count=count,
                enum=enum_key if isinstance(enum_key, str) else None,
                description=check.text(f"{field_where} description", body.get("description", "")),
            )
        )
    return tuple(fields)
