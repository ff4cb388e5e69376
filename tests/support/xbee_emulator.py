"""An XBee Series 1 emulator on a pty: API mode 1/2 (what digi-xbee needs) or transparent mode.

It also keeps the configuration registers a provisioning tool sets, reads back and saves."""

from __future__ import annotations

import os
import select
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

from tests.support.ptys import VanishingPty

_ESCAPED = frozenset({0x7E, 0x7D, 0x11, 0x13})

# Registers a host may set, with the largest value a Series 1 takes (numbers) or None (text).
# Ranges from Digi's 802.15.4 manual; an out-of-range value is refused as a real radio does.
SETTABLE: dict[bytes, int | None] = {
    b"ID": 0xFFFF,
    b"CH": 0xFF,  # and within the radio's channels
    b"MY": 0xFFFF,
    b"DH": 0xFFFFFFFF,
    b"DL": 0xFFFFFFFF,
    b"NI": None,
    b"EE": 1,
    b"BD": 7,
    b"AP": 2,
    b"CE": 1,
}
KEY_BYTES = 16


def api_frame(body: bytes, escaped: bool) -> bytes:
    """Start delimiter, length, body and checksum; escaped as API mode 2 when asked."""
    raw = bytes([len(body) >> 8, len(body) & 0xFF]) + body + bytes([0xFF - sum(body) & 0xFF])
    if escaped:
        out = bytearray()
        for byte in raw:
            if byte in _ESCAPED:
                out += bytes([0x7D, byte ^ 0x20])
            else:
                out.append(byte)
        raw = bytes(out)
    return b"\x7e" + raw


@dataclass
class Transmission:
    api_id: int
    destination: bytes
    data: bytes


@dataclass
class _Parser:
    """Byte-at-a-time API frame reader (unescaping in mode 2)."""

    escaped_mode: bool
    frames: list[bytes] = field(default_factory=list)
    bad_checksums: int = 0
    _buffer: bytearray = field(default_factory=bytearray)
    _in_frame: bool = False
    _escape_next: bool = False

    def feed(self, data: bytes) -> None:
        for byte in data:
            # In mode 1 a 0x7E inside a frame is data (the length decides); in mode 2 it is
            # always escaped, so a raw one always starts a frame.
            if byte == 0x7E and (self.escaped_mode or not self._in_frame):
                self._buffer.clear()
                self._in_frame = True
                self._escape_next = False
                continue
            if not self._in_frame:
                continue
            if self.escaped_mode and byte == 0x7D:
                self._escape_next = True
                continue
            if self._escape_next:
                byte ^= 0x20
                self._escape_next = False
            self._buffer.append(byte)
            if len(self._buffer) >= 2:
                length = (self._buffer[0] << 8) | self._buffer[1]
                if len(self._buffer) == length + 3:
                    body = bytes(self._buffer[2:-1])
                    if (sum(body) + self._buffer[-1]) & 0xFF == 0xFF:
                        self.frames.append(body)
                    else:
                        self.bad_checksums += 1
                    self._in_frame = False


class XBeeEmulator:
    """Serves the master side of a pty like the base-station XBee would.

    API mode answers the local AT queries digi-xbee's open() makes (AP HV VR SH SL NI MY CE),
    acknowledges TX requests with a TX status, records remote AT requests (the 4 s stall comes
    from those) without answering them, and injects RX16/RX64 packets "from particles".

    Configuration: the registers in SETTABLE can be set and read in API mode (AT frames) and in
    transparent command mode (+++, ATxx[value], ATCN). KY is write-only, as on a real radio: it
    is accepted and answered with an empty value. WR copies the registers and the key to
    `saved` (non-volatile memory) and power_cycle() restores them. A new AP takes effect after
    the reply in API mode and on leaving command mode (ATCN), as on the radio.
    """

    def __init__(
        self,
        path: Path,
        *,
        api_mode: int = 1,
        my: int = 0xFFFE,
        serial_number: int = 0x0013A20040A1B2C3,
        node_id: bytes = b"BASE",
        reply_delay: float = 0.002,
        guard_s: float = 0.1,
        channels: range = range(0x0B, 0x1B),
    ) -> None:
        """channels: those the radio accepts (an XBee-PRO S1 has 0x0C-0x17 only)."""
        self.api_mode = api_mode  # 0: transparent
        self.channels = channels
        self.reply_delay = reply_delay
        self.guard_s = guard_s
        self.registers: dict[bytes, bytes] = {
            b"AP": bytes([api_mode]),
            b"HV": b"\x17\x4a",  # first byte 0x17: Series 1 hardware
            b"VR": b"\x10\xef",  # 802.15.4 firmware (does not start with 8)
            b"SH": (serial_number >> 32).to_bytes(4, "big"),
            b"SL": (serial_number & 0xFFFFFFFF).to_bytes(4, "big"),
            b"NI": node_id,
            b"MY": my.to_bytes(2, "big"),
            b"CE": b"\x00",
            b"ID": b"\x33\x32",  # factory defaults
            b"CH": b"\x0c",
            b"DH": b"\x00",
            b"DL": b"\x00",
            b"EE": b"\x00",
            b"BD": b"\x03",
        }
        self.key: bytes | None = None
        self.saved: dict[bytes, bytes] = dict(self.registers)
        self.saved_key: bytes | None = None
        self.transmissions: list[Transmission] = []
        self.remote_at_requests: list[bytes] = []
        self.transparent_out = bytearray()
        self.at_commands_seen: list[bytes] = []
        self.changed = threading.Condition()
        self._write_lock = threading.Lock()
        self._pty = VanishingPty(path)
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._start_thread()

    @property
    def port(self) -> str:
        return str(self._pty.path)

    # ---- what the test does --------------------------------------------------------------

    def inject_rx16(self, source: int, data: bytes, rssi: int = 40) -> None:
        body = bytes([0x81]) + source.to_bytes(2, "big") + bytes([rssi, 0x02]) + data
        self._write(api_frame(body, self.api_mode == 2))

    def inject_rx64(self, source: int, data: bytes, rssi: int = 40) -> None:
        body = bytes([0x80]) + source.to_bytes(8, "big") + bytes([rssi, 0x02]) + data
        self._write(api_frame(body, self.api_mode == 2))

    def inject_air_bytes(self, data: bytes) -> None:
        """Transparent mode: bytes the radio hands to its host."""
        self._write(data)

    def wait_for(self, predicate: object, timeout: float = 5.0) -> bool:
        assert callable(predicate)
        with self.changed:
            return self.changed.wait_for(predicate, timeout)

    def power_cycle(self) -> None:
        """Off and on again: what WR saved is all that is left."""
        self._stop_thread()
        self.registers = dict(self.saved)
        self.key = self.saved_key
        self.api_mode = self.registers[b"AP"][0]
        self._start_thread()

    def unplug(self) -> None:
        self._stop_thread()
        self._pty.unplug()

    def replug(self) -> None:
        self._pty.replug()
        self._start_thread()

    def close(self) -> None:
        self._stop_thread()
        self._pty.close()

    # ---- the radio -----------------------------------------------------------------------

    def _start_thread(self) -> None:
        self._stop.clear()
        self._thread = threading.Thread(target=self._serve, name="xbee-emulator", daemon=True)
        self._thread.start()

    def _stop_thread(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=2)
            self._thread = None

    def _write(self, data: bytes) -> None:
        with self._write_lock:
            os.write(self._pty.master, data)

    def _serve(self) -> None:
        parser = _Parser(escaped_mode=self.api_mode == 2)
        parser_mode = self.api_mode
        master = self._pty.master
        last_byte_at = time.monotonic()
        plus_pending_since: float | None = None
        command_mode = False
        line = b""
        while not self._stop.is_set():
            ready, _, _ = select.select([master], [], [], 0.01)
            now = time.monotonic()
            if not ready:
                if plus_pending_since is not None and now - plus_pending_since >= self.guard_s:
                    plus_pending_since = None
                    command_mode = True
                    self._write(b"OK\r")
                continue
            try:
                data = os.read(master, 4096)
            except OSError:
                time.sleep(0.01)  # nobody has the slave open right now
                continue
            if self.api_mode == 0:
                quiet_before = now - last_byte_at >= self.guard_s
                last_byte_at = now
                if command_mode:
                    line += data
                    while b"\r" in line:
                        command, line = line.split(b"\r", 1)
                        command_mode = self._transparent_command(command)
                elif data == b"+++" and quiet_before:
                    plus_pending_since = now
                else:
                    plus_pending_since = None
                    with self.changed:
                        self.transparent_out += data
                        self.changed.notify_all()
                continue
            if parser_mode != self.api_mode:
                parser, parser_mode = _Parser(escaped_mode=self.api_mode == 2), self.api_mode
            parser.feed(data)
            frames, parser.frames = parser.frames, []
            for body in frames:
                self._handle(body)

    def _transparent_command(self, command: bytes) -> bool:
        """Answers one command-mode line; False when it ends command mode."""
        with self.changed:
            self.at_commands_seen.append(command)
            self.changed.notify_all()
        if not command.upper().startswith(b"AT"):
            self._write(b"ERROR\r")
            return True
        name, argument = command[2:4].upper(), command[4:].strip()
        if name == b"CN":
            self._write(b"OK\r")
            self.api_mode = self.registers[b"AP"][0]  # a new AP applies on leaving
            return False
        if name in (b"WR", b"AC") and not argument:
            self._execute(name)
            self._write(b"OK\r")
        elif not argument:
            value = self._query(name)
            if value is None:
                self._write(b"ERROR\r")
            elif name == b"KY":
                self._write(b"OK\r")  # write-only: acknowledged, never shown
            elif name == b"NI":
                self._write(value + b"\r")
            else:
                self._write(f"{int.from_bytes(value, 'big'):X}\r".encode())
        else:
            try:
                raw = argument if name == b"NI" else _hex_bytes(argument, name)
            except ValueError:
                self._write(b"ERROR\r")
                return True
            self._write(b"OK\r" if self._set(name, raw) == 0 else b"ERROR\r")
        return True

    def _query(self, name: bytes) -> bytes | None:
        if name == b"KY":
            return b""  # write-only: a radio never tells its key
        return self.registers.get(name)

    def _set(self, name: bytes, value: bytes) -> int:
        """0 (OK) or 3 (invalid parameter), as the AT response status."""
        if name == b"KY":
            if len(value) > KEY_BYTES:
                return 3
            self.key = value.rjust(KEY_BYTES, b"\x00")
            return 0
        if name not in SETTABLE:
            return 3 if name in self.registers else 2
        largest = SETTABLE[name]
        if largest is None:
            if len(value) > 20:
                return 3
        else:
            number = int.from_bytes(value, "big")
            if number > largest or (name == b"CH" and number not in self.channels):
                return 3
            value = number.to_bytes(max(1, (number.bit_length() + 7) // 8), "big")
        self.registers[name] = value
        return 0

    def _execute(self, name: bytes) -> None:
        if name == b"WR":
            self.saved = dict(self.registers)
            self.saved_key = self.key

    def _handle(self, body: bytes) -> None:
        api_id = body[0]
        escaped = self.api_mode == 2
        if api_id in (0x08, 0x09):  # local AT command (queued or not)
            frame_id, command, value = body[1], bytes(body[2:4]), bytes(body[4:])
            with self.changed:
                self.at_commands_seen.append(command)
                self.changed.notify_all()
            answer = b""
            if command in (b"WR", b"AC") and not value:
                self._execute(command)
                status = 0
            elif value:
                status = self._set(command, value)
            else:
                found = self._query(command)
                status, answer = (2, b"") if found is None else (0, found)  # 2: invalid command
            time.sleep(self.reply_delay)
            reply = bytes([0x88, frame_id]) + command + bytes([status]) + answer
            self._write(api_frame(reply, escaped))
            if command == b"AP" and status == 0 and value:
                self.api_mode = self.registers[b"AP"][0]  # switches after its reply
        elif api_id in (0x00, 0x01):  # TX64 / TX16 request
            frame_id = body[1]
            address_size = 8 if api_id == 0x00 else 2
            destination = bytes(body[2 : 2 + address_size])
            data = bytes(body[3 + address_size :])
            with self.changed:
                self.transmissions.append(Transmission(api_id, destination, data))
                self.changed.notify_all()
            if frame_id:
                time.sleep(self.reply_delay)
                self._write(api_frame(bytes([0x89, frame_id, 0x00]), escaped))
        elif api_id == 0x17:  # remote AT: what the 4 s stall is made of; never answered here
            with self.changed:
                self.remote_at_requests.append(body)
                self.changed.notify_all()


def _hex_bytes(argument: bytes, name: bytes) -> bytes:
    """A command-mode argument (hex digits) as the register's big-endian bytes."""
    digits = argument.decode("ascii")
    number = int(digits, 16)
    if name == b"KY":
        if number >> (8 * KEY_BYTES):
            raise ValueError("key too long")
        return number.to_bytes(KEY_BYTES, "big")
    return number.to_bytes(max(1, (number.bit_length() + 7) // 8), "big")
