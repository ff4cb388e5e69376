"""Configuring an XBee Series 1 for the fleet: PAN, channel, addressing, AES, baud and serial mode.

digi-xbee only talks to radios in API mode, and refuses to set AP to transparent (it would lose
the radio). So the setup runs in three stages on the radio's serial port at 9600 baud:

1. A radio found in transparent mode (AP=0, the factory setting) is put into API mode through
   AT command mode (+++, ATAP1, ATNI, ATCN); one found in API mode gets its NI set by a raw API
   frame, since digi-xbee cannot open a radio whose NI is empty.
2. digi-xbee sets every value (AT frames, applied at once), reads each back, and writes them to
   the radio's non-volatile memory (WR). KY (the AES key) is write-only on Series 1 radios: the
   radio acknowledging it is all that can be checked here, with EE reading back 1. Whether two
   radios share the key shows only on the air: a particle whose key differs is never heard.
3. A particle's radio must end transparent. A raw API frame sets AP=0; then, in command mode,
   every value is read back once more, this time as the particle will use the radio, and WR
   writes AP=0 as well. A base station's radio stays in API mode.
"""

from __future__ import annotations

import contextlib
import enum
import logging
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass

import serial
from digi.xbee.exception import ATCommandException, TimeoutException, XBeeException

from particlebot.fleet import FleetKey
from particlebot.radio import NoResponseError, RadioError
from particlebot.radio._port import LIST_PORTS_HINT, open_serial
from particlebot.radio.xbee import (
    _Raw802WithoutLookups,
    at_command_frame,
    escape,
    read_until,
    unescape,
)

BAUD = 9600
BD_9600 = 3
"""BD's code for 9600 baud: the particles' firmware talks to its radio at this rate."""
MY_64BIT_SOURCE = 0xFFFE
"""MY=FFFE: send with the radio's own 64-bit address (RX64 at the base), not a shared 16-bit 0."""
BROADCAST_DL = 0xFFFF
BASE_NODE_ID = "BASE"
_FRAME_ID = 0x52  # an id whose AP query frame needs no escaping, so one probe fits both API modes
_REPLY_TIMEOUT_S = 1.0


class Role(enum.Enum):
    BASE = "base"
    PARTICLE = "particle"


class RadioSetupError(RadioError):
    """The radio refused a value, read back another one, or stopped answering."""


@dataclass(frozen=True)
class Setting:
    command: str
    value: bytes
    shown: str
    text: bool = False
    """NI: compared and sent as text, not as a number."""

    def command_mode_argument(self) -> str:
        return self.value.decode("ascii") if self.text else self.value.hex().upper()

    def matches(self, read_back: bytes) -> bool:
        if self.text:
            return read_back.rstrip(b"\x00 ") == self.value
        return int.from_bytes(read_back, "big") == int.from_bytes(self.value, "big")


@dataclass(frozen=True)
class RadioPlan:
    role: Role
    node_id: str
    pan_id: int
    channel: int
    key: FleetKey

    def settings(self) -> list[Setting]:
        """Everything set, in order; KY last but one, BD last (a rate change would cut the link,
        though a radio set up here is at 9600 already)."""
        return [
            Setting("ID", self.pan_id.to_bytes(2, "big"), f"PAN 0x{self.pan_id:04X}"),
            Setting("CH", bytes([self.channel]), f"channel 0x{self.channel:02X}"),
            Setting("MY", MY_64BIT_SOURCE.to_bytes(2, "big"), f"MY {MY_64BIT_SOURCE:04X}"),
            Setting("DH", bytes(4), "DH 0"),
            Setting("DL", BROADCAST_DL.to_bytes(4, "big"), f"DL {BROADCAST_DL:X}"),
            Setting("NI", self.node_id.encode("ascii"), f"NI {self.node_id}", text=True),
            Setting("EE", b"\x01", "AES on"),
            Setting("BD", bytes([BD_9600]), f"{BAUD} baud"),
        ]


@dataclass(frozen=True)
class SetupResult:
    address: str
    """The radio's 64-bit address (SH, SL) as 16 hex digits."""
    found_mode: int
    final_mode: int
    checked: list[str]


class XBeeSetup:
    """Configures the radio on one serial port; see the module's description for the stages."""

    def __init__(
        self,
        port: str,
        *,
        guard_s: float = 1.1,
        sync_timeout_s: float = 2.0,
        probe_timeout_s: float = 0.6,
        say: Callable[[str], None] = print,
    ) -> None:
        self.port = port
        self.guard_s = guard_s
        self.sync_timeout_s = sync_timeout_s
        self.probe_timeout_s = probe_timeout_s
        self.say = say

    def run(self, plan: RadioPlan) -> SetupResult:
        found_mode = self._into_api_mode(plan.node_id)
        api_mode = found_mode or 1
        address, checked = self._configure(plan, api_mode)
        final_mode = api_mode
        if plan.role is Role.PARTICLE:
            self._into_transparent_mode(plan, api_mode)
            checked.append("transparent (AP=0)")
            final_mode = 0
        else:
            checked.append(f"API mode (AP={api_mode})")
        return SetupResult(address, found_mode, final_mode, checked)

    # ---- stage 1 -------------------------------------------------------------------------------

    def _into_api_mode(self, node_id: str) -> int:
        """The mode the radio was found in (0, 1, 2); it is in API mode afterwards."""
        link = open_serial(self.port, BAUD, timeout=0.05)
        try:
            reply = api_command(link, 1, "AP", b"", self.probe_timeout_s)
            if reply is not None and reply[0] == 0 and reply[1] in (b"\x01", b"\x02"):
                mode = reply[1][0]
                self.say(f"The XBee on {self.port} is in API mode {mode}.")
                _expect_ok(api_command(link, mode, "NI", node_id.encode(), _REPLY_TIMEOUT_S), "NI")
                return mode
            commands = CommandMode(link, self.guard_s)
            if not commands.enter():
                raise NoResponseError(
                    f"No XBee answered on {self.port} at {BAUD} baud, neither to an API frame "
                    f"nor to +++. Is this the XBee Explorer's port ({LIST_PORTS_HINT})? A radio "
                    "set to another rate needs BD=3 (9600) first (XCTU)."
                )
            self.say(f"The XBee on {self.port} is transparent; switching it to API mode.")
            commands.set("AP", "1")
            commands.set("NI", node_id)
            commands.leave()  # AP=1 applies on leaving command mode
            return 0
        finally:
            link.close()

    # ---- stage 2 -------------------------------------------------------------------------------

    def _configure(self, plan: RadioPlan, api_mode: int) -> tuple[str, list[str]]:
        device = _Raw802WithoutLookups(self.port, BAUD)
        device.set_sync_ops_timeout(self.sync_timeout_s)
        try:
            device.open()
            *settings, baud = plan.settings()
            for setting in settings:
                self._set(device, setting.command, setting.value, setting.shown)
            with _library_logs_muted():
                self._set(device, "KY", plan.key.secret_bytes(), "the AES key (KY)")
            self._set(device, baud.command, baud.value, baud.shown)
            checked = []
            for setting in plan.settings():
                read_back = self._get(device, setting.command)
                if not setting.matches(read_back):
                    raise RadioSetupError(
                        f"the radio reads back {setting.command}={read_back.hex().upper()} after "
                        f"being set to {setting.command_mode_argument()}"
                    )
                checked.append(setting.shown)
            checked.append("key accepted (write-only: not readable)")
            device.write_changes()
            address = str(device.get_64bit_addr())
        except ATCommandException as exc:
            raise RadioSetupError(f"the radio refused a command: {exc}") from None
        except TimeoutException:
            raise RadioSetupError(f"the radio on {self.port} stopped answering") from None
        except XBeeException as exc:
            raise RadioSetupError(
                f"digi-xbee could not work with the radio on {self.port} ({exc}); it must be "
                "an XBee Series 1 (802.15.4)"
            ) from None
        finally:
            device.close()
        return address.upper(), checked

    @staticmethod
    def _set(device: _Raw802WithoutLookups, command: str, value: bytes, shown: str) -> None:
        try:
            device.set_parameter(command, bytearray(value), apply=True)
        except ATCommandException as exc:
            raise RadioSetupError(f"the radio refused {shown} ({exc})") from None

    @staticmethod
    def _get(device: _Raw802WithoutLookups, command: str) -> bytes:
        return bytes(device.get_parameter(command, apply=False))

    # ---- stage 3 -------------------------------------------------------------------------------

    def _into_transparent_mode(self, plan: RadioPlan, api_mode: int) -> None:
        link = open_serial(self.port, BAUD, timeout=0.05)
        try:
            # The reply may come in API or not at all, depending on when the radio switches;
            # command mode below is what tells.
            api_command(link, api_mode, "AP", b"\x00", _REPLY_TIMEOUT_S)
            commands = CommandMode(link, self.guard_s)
            if not commands.enter():
                raise RadioSetupError(
                    f"the radio on {self.port} did not answer +++ after AP=0: it may be left in "
                    "API mode; run the setup again"
                )
            mode = commands.query("AP")
            if mode != "0":
                raise RadioSetupError(f"the radio reads back AP={mode} after being set to 0")
            for setting in plan.settings():
                answer = commands.query(setting.command)
                read_back = answer.encode() if setting.text else _hex_value(answer)
                if not setting.matches(read_back):
                    raise RadioSetupError(
                        f"in transparent mode the radio reads back {setting.command}={answer}, "
                        f"not {setting.command_mode_argument()}"
                    )
            commands.set("WR", "")
            commands.leave()
        finally:
            link.close()


# digi-xbee logs every frame it sends and receives at DEBUG level, in hex: the KY frame would put
# the key into any log that records DEBUG.
_LIBRARY_LOGGERS = ("digi.xbee.sender", "digi.xbee.reader", "digi.xbee.devices")


@contextlib.contextmanager
def _library_logs_muted() -> Iterator[None]:
    def drop(record: logging.LogRecord) -> bool:
        return False

    loggers = [logging.getLogger(name) for name in _LIBRARY_LOGGERS]
    for logger in loggers:
        logger.addFilter(drop)
    try:
        yield
    finally:
        for logger in loggers:
            logger.removeFilter(drop)


class CommandMode:
    """An XBee's AT command mode on an open link: +++, then ATxx lines answered by lines."""

    def __init__(self, link: serial.Serial, guard_s: float) -> None:
        self.link = link
        self.guard_s = guard_s

    def enter(self) -> bool:
        # The radio wants GT of silence on both sides of "+++".
        time.sleep(self.guard_s)
        self.link.reset_input_buffer()
        self.link.write(b"+++")
        self.link.flush()
        reply = read_until(self.link, self.guard_s + 0.6, lambda got: b"OK\r" in got)
        return b"OK\r" in reply

    def query(self, command: str) -> str:
        answer = self._line(f"AT{command}")
        if answer == "ERROR":
            raise RadioSetupError(f"the radio does not know AT{command}")
        return answer

    def set(self, command: str, argument: str) -> None:
        answer = self._line(f"AT{command}{argument}")
        if answer != "OK":
            raise RadioSetupError(f"the radio answered {answer or 'nothing'} to AT{command}")

    def leave(self) -> None:
        self.set("CN", "")

    def _line(self, line: str) -> str:
        self.link.reset_input_buffer()
        self.link.write(line.encode("ascii") + b"\r")
        self.link.flush()
        reply = read_until(self.link, _REPLY_TIMEOUT_S, lambda got: b"\r" in got)
        return reply.split(b"\r", 1)[0].decode("ascii", errors="replace").strip()


def api_command(
    link: serial.Serial, api_mode: int, command: str, value: bytes, timeout: float
) -> tuple[int, bytes] | None:
    """Sends one AT command frame (0x08) and returns (status, value) of the radio's answer, or
    None if none came."""
    frame = at_command_frame(command.encode("ascii"), _FRAME_ID, value)
    link.reset_input_buffer()
    link.write(escape(frame) if api_mode == 2 else frame)
    link.flush()
    marker = bytes([0x88, _FRAME_ID]) + command.encode("ascii")
    reply = read_until(link, timeout, lambda got: _answer(got, marker) is not None)
    return _answer(reply, marker)


def _answer(data: bytes, marker: bytes) -> tuple[int, bytes] | None:
    """(status, value) of the complete AT response frame carrying marker in data."""
    plain = unescape(data)
    at = plain.find(marker)
    if at < 3 or plain[at - 3] != 0x7E:
        return None
    length = (plain[at - 2] << 8) | plain[at - 1]
    end = at + length
    if end >= len(plain) or length < len(marker) + 1:
        return None
    return plain[at + len(marker)], bytes(plain[at + len(marker) + 1 : end])


def _expect_ok(reply: tuple[int, bytes] | None, command: str) -> None:
    if reply is None:
        raise RadioSetupError(f"the radio did not answer AT{command}")
    if reply[0] != 0:
        raise RadioSetupError(f"the radio refused AT{command} (status {reply[0]})")


def _hex_value(answer: str) -> bytes:
    try:
        number = int(answer, 16)
    except ValueError:
        raise RadioSetupError(f"the radio answered {answer!r} where a hex value was due") from None
    return number.to_bytes(max(1, (number.bit_length() + 7) // 8), "big")
