"""Writes the firmware's C++ header (protocol_gen.h) from a parsed Definition."""

from __future__ import annotations

import textwrap

from protocolgen.parse import (
    DEFINITION,
    FRAME_OVERHEAD,
    GENERATOR_VERSION,
    INT32_MIN,
    Definition,
    MessageDef,
)


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
