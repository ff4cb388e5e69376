"""Writes the host's Python module (particlebot/protocol/generated.py) from a parsed Definition."""

from __future__ import annotations

import json
import textwrap

from protocolgen.parse import (
    DEFINITION,
    FRAME_OVERHEAD,
    GENERATOR_VERSION,
    Definition,
    MessageDef,
)


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
