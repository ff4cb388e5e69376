"""Fio v3 boards on USB: which ports are boards, running or in their bootloader; the reset touch.

A Fio v3 shows up as USB 1B4F:F101 while its firmware runs (if the firmware keeps the USB serial
stack) and as 1B4F:F100 while the Caterina bootloader runs (about 8 s after a reset). Opening the
running port at 1200 baud and closing it asks the firmware to reset into the bootloader, which
then appears as a new port. Everything the flash tool does with USB goes through UsbBus, so
tests can stand in for the operating system (ptys are never listed by pyserial).
"""

from __future__ import annotations

import contextlib
import enum
import errno
from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

import serial
from serial.tools import list_ports

from particlebot.errors import ParticlebotError

FIO_VID = 0x1B4F
FIO_RUNNING_PID = 0xF101
FIO_BOOTLOADER_PID = 0xF100
TOUCH_BAUD = 1200
"""The line rate the Arduino USB core takes as "reset into the bootloader"."""


class BoardMode(enum.Enum):
    RUNNING = "running"
    BOOTLOADER = "bootloader"


@dataclass(frozen=True)
class BoardPort:
    """One serial port that is (or is taken to be) a Fio v3."""

    device: str
    mode: BoardMode
    serial_number: str | None = None
    location: str | None = None
    """Where it is plugged in (USB bus path); the same for a board's running and bootloader
    ports, so it identifies the board across its reset."""

    @property
    def socket(self) -> str:
        """The physical place of the board: its USB location, else its device name."""
        return self.location or self.device


class BoardError(ParticlebotError):
    """A board could not be reached; the message says why and what to do."""


class UsbBus(Protocol):
    """What the flash tool needs from the operating system's USB serial ports."""

    def boards(self) -> list[BoardPort]:
        """Every Fio v3 port present now."""
        ...

    def touch(self, device: str) -> None:
        """Asks the firmware on device to reset into its bootloader (the 1200-baud touch)."""
        ...


class SerialLike(Protocol):
    dtr: bool

    def close(self) -> None: ...


PortOpener = Callable[[str, int], SerialLike]


def _open_serial(device: str, baud: int) -> SerialLike:
    return serial.Serial(device, baud)


class SystemUsb:
    """The real USB ports, through pyserial."""

    def __init__(self, open_port: PortOpener = _open_serial) -> None:
        self._open_port = open_port

    def boards(self) -> list[BoardPort]:
        found = []
        for info in list_ports.comports():
            mode = board_mode(info.vid, info.pid)
            if mode is not None:
                found.append(BoardPort(info.device, mode, info.serial_number, info.location))
        return sorted(found, key=lambda board: board.device)

    def touch(self, device: str) -> None:
        try:
            port = self._open_port(device, TOUCH_BAUD)
        except (serial.SerialException, OSError) as exc:
            raise BoardError(port_error(device, exc)) from exc
        try:
            # Closing drops DTR at 1200 baud: the firmware's cue to start the bootloader.
            port.dtr = False
        except (serial.SerialException, OSError):
            pass  # some adapters refuse modem lines; closing alone still sends the cue
        finally:
            # The board may already be gone into its reset.
            with contextlib.suppress(serial.SerialException, OSError):
                port.close()


def board_mode(vid: int | None, pid: int | None) -> BoardMode | None:
    if vid != FIO_VID:
        return None
    if pid == FIO_RUNNING_PID:
        return BoardMode.RUNNING
    if pid == FIO_BOOTLOADER_PID:
        return BoardMode.BOOTLOADER
    return None


def port_error(device: str, exc: BaseException) -> str:
    code = getattr(exc, "errno", None)
    text = str(exc)
    if code in (errno.EACCES, errno.EPERM) or "Permission denied" in text:
        return (
            f"no permission to open {device}: add yourself to its group "
            "(sudo usermod -aG dialout $USER, then log in again)"
        )
    if code == errno.ENOENT or "No such file" in text:
        return f"{device} vanished (board unplugged?)"
    if code in (errno.EBUSY, errno.EAGAIN) or "busy" in text.lower():
        return f"{device} is in use by another program (a serial monitor, the console?)"
    return f"cannot open {device}: {text}"
