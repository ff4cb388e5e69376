#!/usr/bin/env python3
"""Turns shared/protocol.toml into the firmware's C++ header and the host's Python module."""

from __future__ import annotations

import argparse
import json
import keyword
import re
import sys
import textwrap
import tomllib
import zlib
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

# Bump when the shape of the generated code changes: hand-written code that depends on it states the
# version it expects (frame.h), so a header from another generator stops the build.
GENERATOR_VERSION = 2

REPO_ROOT = Path(__file__).resolve().parent.parent
DEFINITION = "shared/protocol.toml"
CPP_OUTPUT = "firmware/lib/protocol/protocol_gen.h"
PY_OUTPUT = "host/particlebot/protocol/generated.py"

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


# ---- C++ header ---------------------------------------------------------------------------------


def _cpp_comment(text: str, indent: int) -> list[str]:
    prefix = " " * indent + "// "
    return [prefix + line for line in textwrap.wrap(text, 100 - len(prefix))]


def _cpp_int(value: int) -> str:
    # -2147483648 is a negation of a literal too wide for int32_t, so spell the minimum indirectly.
    if value == INT32_MIN:
        return "(-2147483647L - 1)"
    if value > 32767 or value < -32768:
        return f"{value}L"  # AVR's int is 16 bits
    return str(value)


def generate_cpp(definition: Definition) -> str:
    frame = definition.frame
    out: list[str] = [
        "// Radio protocol of the particles: constants, enums and message structs with their"
        " encoders.",
        f"// Generated from {DEFINITION} by tools/gen_protocol.py; do not edit.",
        f"// Definition hash 0x{definition.hash:08X} (kDefinitionHash, sent in every STATUS).",
        "#ifndef PARTICLEBOT_PROTOCOL_GEN_H",
        "#define PARTICLEBOT_PROTOCOL_GEN_H",
        "",
        "#include <stdint.h>",
        "#include <string.h>",
        "",
        "#ifdef __AVR__",
        "#include <avr/pgmspace.h>",
        "#endif",
        "",
        f"#define PB_PROTOCOL_GENERATOR_VERSION {GENERATOR_VERSION}",
        "// Hand-written code that relies on this header's shape defines the generator version it"
        " was",
        "// written against (frame.h does); a header from another generator stops the build here.",
        "#if defined(PB_PROTOCOL_EXPECTED_GENERATOR_VERSION) && \\",
        "    PB_PROTOCOL_EXPECTED_GENERATOR_VERSION != PB_PROTOCOL_GENERATOR_VERSION",
        '#error "Regenerate this file with tools/gen_protocol.py (make generate)"',
        "#endif",
        "",
        "// A function whose bool result must not be dropped (a failed decode or lookup, a refused",
        "// change). GCC warns even when the result is cast to void: test it.",
        "#ifndef PB_MUST_USE",
        "#define PB_MUST_USE __attribute__((warn_unused_result))",
        "#endif",
        "",
        "namespace pb {",
        "",
        f"const uint32_t kDefinitionHash = 0x{definition.hash:08X}UL;",
        f"const uint8_t kSync0 = 0x{frame.sync[0]:02X};",
        f"const uint8_t kSync1 = 0x{frame.sync[1]:02X};",
        "// Payload bytes at most; LEN counts payload bytes only.",
        f"const uint8_t kMaxPayload = {frame.max_payload};",
        "// Sync (2), LEN, TYPE, SENDER, SEQ and CRC (2) around the payload.",
        f"const uint8_t kFrameOverhead = {FRAME_OVERHEAD};",
        f"const uint8_t kBaseStationId = {frame.base_station_id};",
        f"const uint8_t kBroadcastId = {frame.broadcast_id};",
        "// Reported by a particle whose EEPROM holds no id yet.",
        f"const uint8_t kUnassignedId = {frame.unassigned_id};",
        "",
    ]
    for enum in definition.enums:
        out += _cpp_comment(enum.description, 0)
        out.append(f"enum class {enum.type_name} : uint8_t {{")
        for member in enum.members:
            out += _cpp_comment(member.description, 2)
            out.append(f"  {member.name} = {member.value},")
        out += ["};", ""]
    out += _cpp_comment("Message types, the TYPE byte of a frame.", 0)
    out.append("enum class MessageType : uint8_t {")
    for message in definition.messages:
        out.append(f"  {message.name} = 0x{message.id:02X},")
    out += ["};", ""]

    params = definition.enum("param").members
    out += [
        "// Default and accepted range of one parameter.",
        "struct ParamSpec {",
        "  int32_t default_value;",
        "  int32_t min;",
        "  int32_t max;",
        "};",
        "",
        f"const uint8_t kParamCount = {len(params)};",
        "",
        "// The parameter table lives in flash on the AVR (read through avr/pgmspace.h): 13 bytes"
        " a",
        "// parameter, where a switch statement took about 37.",
        "namespace detail {",
        "struct ParamEntry {",
        "  uint8_t id;",
        "  ParamSpec spec;",
        "};",
        "#ifdef __AVR__",
        "#define PB_PROTOCOL_FLASH PROGMEM",
        "#else",
        "#define PB_PROTOCOL_FLASH",
        "#endif",
        "const ParamEntry kParams[kParamCount] PB_PROTOCOL_FLASH = {",
    ]
    for member in params:
        assert member.param is not None
        spec = member.param
        out += [
            f"    // {member.name}",
            f"    {{{member.value}, {{{_cpp_int(spec.default)}, {_cpp_int(spec.min)},"
            f" {_cpp_int(spec.max)}}}}},",
        ]
    out += [
        "};",
        "#undef PB_PROTOCOL_FLASH",
        "}  // namespace detail",
        "",
        "// Default and range of a parameter. False for an unknown id; out may be null to test",
        "// whether an id exists.",
        "PB_MUST_USE inline bool param_spec(uint8_t param_id, ParamSpec *out) {",
        "  for (uint8_t i = 0; i < kParamCount; ++i) {",
        "#ifdef __AVR__",
        "    if (pgm_read_byte(&detail::kParams[i].id) != param_id) continue;",
        "    if (out != 0) memcpy_P(out, &detail::kParams[i].spec, sizeof *out);",
        "#else",
        "    if (detail::kParams[i].id != param_id) continue;",
        "    if (out != 0) *out = detail::kParams[i].spec;",
        "#endif",
        "    return true;",
        "  }",
        "  return false;",
        "}",
        "",
        "// Payload size of a message type; false for a type this definition does not know.",
        "PB_MUST_USE inline bool message_payload_size(uint8_t type, uint8_t *size) {",
        "  uint8_t bytes;",
        "  switch (type) {",
    ]
    for message in definition.messages:
        out += [
            f"    case 0x{message.id:02X}:  // {message.name}",
            f"      bytes = {message.payload_size};",
            "      break;",
        ]
    out += [
        "    default:",
        "      return false;",
        "  }",
        "  if (size != 0) *size = bytes;",
        "  return true;",
        "}",
        "",
        "// Each message struct below is packed, its fields in wire order: on a little-endian"
        " machine (the",
        "// AVR, x86, ARM) its bytes are the payload, so encoding and decoding are one memcpy. A"
        " generic",
        "// table-driven codec and per-field shifts both cost the particle more flash (measured in"
        " README).",
        "// A packed field binds only to a const reference or a copy (test macros take"
        " references).",
        "#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__",
        '#error "The message structs are the wire layout only on a little-endian machine"',
        "#endif",
        "",
    ]
    for message in definition.messages:
        out += _cpp_message(message, definition)
    out += [
        "#ifdef PB_PROTOCOL_DEFINE_STATICS",
        "// Out-of-class definitions, emitted once (by frame.cpp), so that binding kType or"
        " kPayloadSize",
        "// to a reference (as test macros do) still links.",
    ]
    for message in definition.messages:
        out.append(f"const MessageType {message.type_name}Message::kType;")
        out.append(f"const uint8_t {message.type_name}Message::kPayloadSize;")
    out += [
        "#endif",
        "",
        "}  // namespace pb",
        "",
        "#endif  // PARTICLEBOT_PROTOCOL_GEN_H",
        "",
    ]
    return "\n".join(out)


def _cpp_message(message: MessageDef, definition: Definition) -> list[str]:
    struct_name = f"{message.type_name}Message"
    out = _cpp_comment(f"{message.name} (from {message.sent_by}): {message.description}", 0)
    out += [
        f"struct {struct_name} {{",
        f"  static const MessageType kType = MessageType::{message.name};",
        f"  static const uint8_t kPayloadSize = {message.payload_size};",
        "",
    ]
    if not message.fields:
        out.pop()
    for field in message.fields:
        note = field.description
        if field.enum is not None:
            note += f" (enum {definition.enum(field.enum).type_name})"
        out += _cpp_comment(note, 2)
        suffix = f"[{field.count}]" if field.count else ""
        out.append(f"  {field.wire.cpp} {field.name}{suffix};")
    if message.fields:
        out.append("")
        out += [
            "  // Writes kPayloadSize bytes, little-endian, and returns kPayloadSize.",
            "  uint8_t encode(uint8_t *out) const {",
            "    memcpy(out, this, kPayloadSize);",
            "    return kPayloadSize;",
            "  }",
            "  // False, leaving the fields untouched, unless len == kPayloadSize.",
            "  PB_MUST_USE bool decode(const uint8_t *in, uint8_t len) {",
            "    if (len != kPayloadSize) return false;",
            "    memcpy(this, in, kPayloadSize);",
            "    return true;",
            "  }",
        ]
    else:
        out += [
            "  // Writes kPayloadSize (no) bytes and returns kPayloadSize.",
            "  uint8_t encode(uint8_t * /*out*/) const { return kPayloadSize; }",
            "  // False unless len == kPayloadSize.",
            "  PB_MUST_USE bool decode(const uint8_t * /*in*/, uint8_t len) {"
            " return len == kPayloadSize; }",
        ]
    out += ["} __attribute__((packed));"]
    if message.fields:
        out.append(
            f"static_assert(sizeof({struct_name}) == {struct_name}::kPayloadSize,"
            ' "packed wire layout");'
        )
    out.append("")
    return out


# ---- Python module ------------------------------------------------------------------------------


def _py_string(text: str, indent: int, width: int = 100) -> list[str]:
    """A double-quoted literal, split into implicitly joined pieces when it would be too long."""
    room = width - indent - 2
    if len(text) + 3 <= room:
        return [" " * indent + json.dumps(text)]
    pieces = textwrap.wrap(text, room - 2, drop_whitespace=False)
    return [" " * indent + json.dumps(piece) for piece in pieces]


def _py_docstring(text: str, indent: int) -> list[str]:
    pad = " " * indent
    width = 100 - indent
    lines = textwrap.wrap('"""' + text, width)
    if len(lines) == 1 and len(lines[0]) + 3 <= width:
        return [f'{pad}{lines[0]}"""']
    if len(lines) == 1:
        lines = textwrap.wrap('"""' + text, width - 4)
    return [pad + line for line in lines] + [f'{pad}"""']


def generate_python(definition: Definition) -> str:
    frame = definition.frame
    out: list[str] = [
        '"""Radio protocol of the particles: constants, enums and message classes.',
        "",
        f"Generated from {DEFINITION} by tools/gen_protocol.py; do not edit.",
        '"""',
        "",
        "import enum",
        "import struct",
        "from dataclasses import dataclass",
        "from typing import Any, ClassVar, NamedTuple, Self, TypeAlias",
        "",
        "from particlebot.errors import ParticlebotError",
        "",
        f"GENERATOR_VERSION = {GENERATOR_VERSION}",
        f"DEFINITION_HASH = 0x{definition.hash:08X}",
        '"""CRC-32 of the definition\'s layout; every STATUS frame carries the firmware\'s."""',
        f"SYNC = bytes((0x{frame.sync[0]:02X}, 0x{frame.sync[1]:02X}))",
        f"MAX_PAYLOAD = {frame.max_payload}",
        f"FRAME_OVERHEAD = {FRAME_OVERHEAD}",
        '"""Sync (2), LEN, TYPE, SENDER, SEQ and CRC (2) around the payload."""',
        f"BASE_STATION_ID = {frame.base_station_id}",
        f"BROADCAST_ID = {frame.broadcast_id}",
        f"UNASSIGNED_ID = {frame.unassigned_id}",
        '"""Reported by a particle whose EEPROM holds no id yet."""',
        "",
        "",
        "class PayloadError(ParticlebotError, ValueError):",
        '    """A payload has the wrong size for its message, or a field value does not fit."""',
        "",
        "",
    ]
    for enum in definition.enums:
        out.append(f"class {enum.type_name}(enum.IntEnum):")
        out += _py_docstring(enum.description, 4)
        out.append("")
        for member in enum.members:
            out.append(f"    {member.name} = {member.value}")
            out += _py_docstring(member.description, 4)
        out += ["", ""]
    out += ["class MessageType(enum.IntEnum):", '    """The TYPE byte of a frame."""', ""]
    for message in definition.messages:
        out.append(f"    {message.name} = 0x{message.id:02X}")
    out += [
        "",
        "",
        "class ParamSpec(NamedTuple):",
        '    """Default, accepted range and meaning of one parameter."""',
        "",
        "    default: int",
        "    min: int",
        "    max: int",
        "    description: str",
        "",
        "",
        "PARAM_SPECS: dict[Param, ParamSpec] = {",
    ]
    for member in definition.enum("param").members:
        assert member.param is not None
        spec = member.param
        out.append(f"    Param.{member.name}: ParamSpec(")
        out.append(f"        {spec.default},")
        out.append(f"        {spec.min},")
        out.append(f"        {spec.max},")
        pieces = _py_string(member.description, 8)
        pieces[-1] += ","
        out += pieces
        out.append("    ),")
    out += [
        "}",
        "",
        "",
        "def _pack(layout: struct.Struct, *values: int) -> bytes:",
        "    try:",
        "        return layout.pack(*values)",
        "    except struct.error as error:",
        "        raise PayloadError(str(error)) from None",
        "",
        "",
        "def _unpack(name: str, layout: struct.Struct, data: bytes) -> tuple[int, ...]:",
        "    if len(data) != layout.size:",
        '        raise PayloadError(f"{name} payload is {len(data)} bytes, not {layout.size}")',
        "    return layout.unpack(data)",
        "",
        "",
        "def _array(name: str, values: tuple[int, ...], count: int) -> tuple[int, ...]:",
        "    if len(values) != count:",
        '        raise PayloadError(f"{name} needs {count} values, got {len(values)}")',
        "    return values",
        "",
        "",
        "class Message:",
        '    """Base of every message: a frozen dataclass with a fixed little-endian layout."""',
        "",
        "    __slots__ = ()",
        "    # Declared so type checkers accept messages in dataclasses.fields() and asdict().",
        "    __dataclass_fields__: ClassVar[dict[str, Any]]",
        "    MESSAGE_TYPE: ClassVar[MessageType]",
        "    PAYLOAD_SIZE: ClassVar[int]",
        "    SENT_BY: ClassVar[str]",
        '    """Who sends it: "base" or "particle"."""',
        "",
        "    def encode_payload(self) -> bytes:",
        '        """The payload bytes; PayloadError when a field does not fit its type."""',
        "        raise NotImplementedError",
        "",
        "    @classmethod",
        "    def decode_payload(cls, data: bytes) -> Self:",
        '        """The message a payload holds; PayloadError unless it has PAYLOAD_SIZE bytes."""',
        "        raise NotImplementedError",
        "",
        "",
    ]
    for message in definition.messages:
        out += _py_message(message, definition)
    names = [message.type_name for message in definition.messages]
    union = " | ".join(names)
    if len(f"AnyMessage: TypeAlias = {union}") <= 100:
        out.append(f"AnyMessage: TypeAlias = {union}")
    elif len(f"    {union}") <= 100:
        out += ["AnyMessage: TypeAlias = (", f"    {union}", ")"]
    else:
        out.append("AnyMessage: TypeAlias = (")
        out += [f"    {name}" if i == 0 else f"    | {name}" for i, name in enumerate(names)]
        out.append(")")
    out += [
        "",
        "MESSAGES: dict[int, type[Message]] = {",
        *(f"    MessageType.{m.name}: {m.type_name}," for m in definition.messages),
        "}",
        '"""Message class of each known TYPE byte."""',
        "",
    ]
    return "\n".join(out)


def _py_message(message: MessageDef, definition: Definition) -> list[str]:
    layout = "<" + "".join(
        (str(field.count) if field.count else "") + field.wire.struct_code
        for field in message.fields
    )
    out = ["@dataclass(frozen=True, slots=True)", f"class {message.type_name}(Message):"]
    out += _py_docstring(f"{message.name}: {message.description}", 4)
    out += [
        "",
        f"    MESSAGE_TYPE: ClassVar[MessageType] = MessageType.{message.name}",
        f"    PAYLOAD_SIZE: ClassVar[int] = {message.payload_size}",
        f'    SENT_BY: ClassVar[str] = "{message.sent_by}"',
        f'    _LAYOUT: ClassVar[struct.Struct] = struct.Struct("{layout}")',
    ]
    if message.fields:
        out.append("")
    for field in message.fields:
        annotation = "tuple[int, ...]" if field.count else "int"
        out.append(f"    {field.name}: {annotation}")
        note = field.description
        if field.enum is not None:
            note += f" ({definition.enum(field.enum).type_name})"
        out += _py_docstring(note, 4)
    values: list[str] = []
    for field in message.fields:
        if field.count:
            values.append(f'*_array("{field.name}", self.{field.name}, {field.count})')
        else:
            values.append(f"self.{field.name}")
    out += ["", "    def encode_payload(self) -> bytes:"]
    out += _py_call("        return _pack(", ["self._LAYOUT", *values], ")")
    out += ["", "    @classmethod", "    def decode_payload(cls, data: bytes) -> Self:"]
    unpack = f'_unpack("{message.type_name}", cls._LAYOUT, data)'
    if not message.fields:
        out += [f"        {unpack}", "        return cls()"]
    else:
        out.append(f"        values = {unpack}")
        arguments: list[str] = []
        index = 0
        for field in message.fields:
            if field.count:
                arguments.append(f"{field.name}=values[{index}:{index + field.count}]")
                index += field.count
            else:
                arguments.append(f"{field.name}=values[{index}]")
                index += 1
        out += _py_call("        return cls(", arguments, ")")
    out += ["", ""]
    return out


def _py_call(head: str, arguments: list[str], tail: str) -> list[str]:
    """A call on one line when it fits, else one argument per line as ruff format writes it."""
    one_line = head + ", ".join(arguments) + tail
    if len(one_line) <= 100:
        return [one_line]
    indent = " " * (len(head) - len(head.lstrip()) + 4)
    inner = indent + ", ".join(arguments)
    if len(inner) <= 100:
        return [head, inner, indent[4:] + tail]
    return [head, *(f"{indent}{argument}," for argument in arguments), indent[4:] + tail]


# ---- command line -------------------------------------------------------------------------------


def outputs(definition: Definition) -> dict[str, str]:
    return {"cpp": generate_cpp(definition), "py": generate_python(definition)}


def main(argv: Iterable[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--input", type=Path, default=REPO_ROOT / DEFINITION)
    parser.add_argument("--cpp-out", type=Path, default=REPO_ROOT / CPP_OUTPUT)
    parser.add_argument("--py-out", type=Path, default=REPO_ROOT / PY_OUTPUT)
    parser.add_argument(
        "--check",
        action="store_true",
        help="write nothing; exit 1 naming each output that regeneration would change",
    )
    parser.add_argument(
        "--print-hash", action="store_true", help="print the definition hash and write nothing"
    )
    args = parser.parse_args(None if argv is None else list(argv))
    try:
        definition = parse(args.input.read_text(encoding="utf-8"))
    except DefinitionError as error:
        print(f"{args.input}: invalid protocol definition:\n{error}", file=sys.stderr)
        return 2
    if args.print_hash:
        print(f"0x{definition.hash:08X}")
        return 0
    texts = outputs(definition)
    targets = {"cpp": args.cpp_out, "py": args.py_out}
    if args.check:
        stale = [
            path
            for key, path in targets.items()
            if not path.exists() or path.read_text(encoding="utf-8") != texts[key]
        ]
        for path in stale:
            print(f"stale generated file: {path} (run `make generate`)", file=sys.stderr)
        return 1 if stale else 0
    for key, path in targets.items():
        path.parent.mkdir(parents=True, exist_ok=True)
        if not path.exists() or path.read_text(encoding="utf-8") != texts[key]:
            path.write_text(texts[key], encoding="utf-8", newline="\n")
            print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
