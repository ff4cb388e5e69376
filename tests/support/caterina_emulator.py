"""A Fio v3's Caterina bootloader on a pty: the AVR109 commands avrdude's avr109 programmer uses."""

from __future__ import annotations

import os
import select
import threading
import time
import tty
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

# ATmega32U4 facts (datasheet): signature 1E 95 87, 128-byte flash pages, 1 KB EEPROM; Caterina
# occupies the top 4 KB of the 32 KB flash.
SIGNATURE = bytes([0x1E, 0x95, 0x87])
PAGE_SIZE = 128
APPLICATION_SIZE = 28_672
FLASH_SIZE = 32_768
EEPROM_SIZE = 1024
IDENTIFIER = b"CATERIN"


@dataclass
class BootloaderLog:
    """What the host asked for, for assertions."""

    commands: list[str] = field(default_factory=list)
    flash_pages_written: int = 0
    eeprom_bytes_written: int = 0
    bootloader_writes: int = 0


class CaterinaEmulator:
    """Serves one bootloader session on the master side of a pty, as Caterina does over USB.

    Like the real bootloader it ends the session on 'E' (avrdude sends it when it closes) and then
    "runs the sketch": the port vanishes. `corrupt_flash` flips one bit of every flash page
    written, so that avrdude's verification fails as with a bad board.
    """

    def __init__(
        self,
        path: Path,
        *,
        eeprom: bytes | None = None,
        corrupt_flash: bool = False,
        on_exit: Callable[[CaterinaEmulator], None] | None = None,
    ) -> None:
        self.flash = bytearray(b"\xff" * FLASH_SIZE)
        self.eeprom = bytearray(b"\xff" * EEPROM_SIZE)
        if eeprom is not None:
            self.eeprom[: len(eeprom)] = eeprom
        self.corrupt_flash = corrupt_flash
        self.log = BootloaderLog()
        self.exited = threading.Event()
        self._on_exit = on_exit
        self._address = 0  # a byte address, as Caterina keeps it
        self.path = path
        # Only the host holds the slave end open, so the master sees when it lets go.
        self._master, slave = os.openpty()
        tty.setraw(slave)
        path.unlink(missing_ok=True)
        path.symlink_to(os.ttyname(slave))
        os.close(slave)
        self._stop = threading.Event()
        self._lock = threading.Lock()
        self._pending = bytearray()
        self._thread = threading.Thread(target=self._serve, name="caterina", daemon=True)
        self._thread.start()

    @property
    def port(self) -> str:
        return str(self.path)

    def application(self) -> bytes:
        """The application section of flash, trailing erased bytes removed."""
        return bytes(self.flash[:APPLICATION_SIZE]).rstrip(b"\xff")

    def close(self) -> None:
        self._stop.set()
        if self._thread is not threading.current_thread():
            self._thread.join(timeout=2)
        self._unplug()

    def _unplug(self) -> None:
        with self._lock:
            if self._master >= 0:
                os.close(self._master)
                self._master = -1
            self.path.unlink(missing_ok=True)

    def _wait_for_host_to_close(self, timeout: float = 2.0) -> None:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            ready, _, _ = select.select([self._master], [], [], 0.05)
            if ready:
                try:
                    os.read(self._master, 4096)
                except OSError:
                    return  # EIO: no slave end open any more

    # ---- the protocol ----------------------------------------------------------------------

    def _serve(self) -> None:
        try:
            while not self._stop.is_set():
                command = self._next_byte()
                if command is None:
                    return
                self.log.commands.append(chr(command))
                if not self._handle(command):
                    break
        except _PortGoneError:
            return
        self.exited.set()
        # Caterina jumps to the sketch and its USB device goes away. A pty master closed under a
        # host that still holds the slave makes the host's close() hang (a USB port that vanishes
        # fails instead), so the port vanishes once the host has let go of it.
        self._wait_for_host_to_close()
        self._unplug()
        if self._on_exit is not None:
            self._on_exit(self)

    def _handle(self, command: int) -> bool:
        """Answers one command; False when the host ended the session."""
        reply = self._reply
        c = chr(command)
        if command == 27:  # ESC: avrdude's "leave any command in progress"; no answer
            return True
        if c == "E":
            reply(b"\r")
            return False
        if c == "S":
            reply(IDENTIFIER)
        elif c == "V":
            reply(b"10")
        elif c == "p":
            reply(b"S")
        elif c == "a":
            reply(b"Y")
        elif c == "b":
            reply(b"Y" + PAGE_SIZE.to_bytes(2, "big"))
        elif c == "t":
            reply(bytes([0x44, 0x00]))
        elif c == "T":
            self._take(1)
            reply(b"\r")
        elif c in "LP":
            reply(b"\r")
        elif c == "s":
            reply(SIGNATURE[::-1])
        elif c == "A":
            high, low = self._take(2)
            self._address = (high << 9) | (low << 1)
            reply(b"\r")
        elif c == "e":
            self.flash[:APPLICATION_SIZE] = b"\xff" * APPLICATION_SIZE
            reply(b"\r")
        elif c in "rFNQ":
            reply(b"\xff")
        elif c in "Bg":
            self._block(c)
        elif c == "d":
            reply(bytes([self.eeprom[(self._address >> 1) % EEPROM_SIZE]]))
            self._address += 2
        elif c == "D":
            (value,) = self._take(1)
            self.eeprom[(self._address >> 1) % EEPROM_SIZE] = value
            self.log.eeprom_bytes_written += 1
            self._address += 2
            reply(b"\r")
        elif c == "R":
            word = self.flash[self._address : self._address + 2]
            reply(bytes([word[1], word[0]]))
        else:
            reply(b"?")
        return True

    def _block(self, command: str) -> None:
        size_high, size_low, memory = self._take(3)
        size = (size_high << 8) | size_low
        if memory not in b"EF":
            self._reply(b"?")
            return
        if command == "g":
            out = bytearray()
            for _ in range(size):
                if memory == ord("F"):
                    out.append(self.flash[self._address % FLASH_SIZE])
                    self._address += 1
                else:
                    out.append(self.eeprom[(self._address >> 1) % EEPROM_SIZE])
                    self._address += 2
            self._reply(bytes(out))
            return
        data = self._take(size)
        if memory == ord("F"):
            start = self._address
            if start + size > APPLICATION_SIZE:
                self.log.bootloader_writes += 1
            else:
                page = bytearray(data)
                if self.corrupt_flash and page:
                    page[0] ^= 0x01
                self.flash[start : start + size] = page
                self.log.flash_pages_written += 1
            self._address += size
        else:
            for value in data:
                self.eeprom[(self._address >> 1) % EEPROM_SIZE] = value
                self._address += 2
            self.log.eeprom_bytes_written += size
        self._reply(b"\r")

    # ---- bytes -----------------------------------------------------------------------------

    def _reply(self, data: bytes) -> None:
        try:
            os.write(self._master, data)
        except OSError as exc:
            raise _PortGoneError from exc

    def _take(self, count: int) -> bytes:
        out = bytearray()
        while len(out) < count:
            byte = self._next_byte()
            if byte is None:
                raise _PortGoneError
            out.append(byte)
        return bytes(out)

    def _next_byte(self) -> int | None:
        while not self._pending:
            if self._stop.is_set():
                return None
            ready, _, _ = select.select([self._master], [], [], 0.05)
            if not ready:
                continue
            try:
                data = os.read(self._master, 4096)
            except OSError:
                # Nobody holds the slave end open (between avrdude's open and close).
                self._stop.wait(0.01)
                continue
            self._pending += data
        byte = self._pending[0]
        del self._pending[0]
        return byte


class _PortGoneError(Exception):
    pass
