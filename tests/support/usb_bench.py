"""A stand-in USB hub for the flash tool: boards that reset into an emulated Caterina on a pty.

pyserial never lists ptys and a pty has no 1200-baud reset, so the tool's UsbBus is replaced by
this bench. A board plugged in shows a running port (1B4F:F101) or, if so made, its bootloader
port (F100). Touching a running board makes its bootloader appear on a fresh pty served by a
CaterinaEmulator, which the real avrdude then talks to; when avrdude ends the session the board
runs its new firmware and, if that keeps USB, shows a running port again. The "person" at the
bench unplugs a board when the tool reports on it and plugs in the next.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass
from pathlib import Path

from particlebot.provision.boards import BoardMode, BoardPort
from tests.support.caterina_emulator import CaterinaEmulator

SOCKET = "1-1.4:1.0"


class FakeClock:
    """Time that passes only when someone sleeps on it, so the tool's waits cost nothing."""

    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now

    def sleep(self, seconds: float) -> None:
        self.now += seconds


@dataclass
class BenchBoard:
    """How one board behaves."""

    name: str
    starts_in_bootloader: bool = False
    answers_touch: bool = True
    """False: the board drops off USB at the touch and never shows a bootloader."""
    corrupt_flash: bool = False
    usb_firmware: bool = True
    """The new firmware keeps USB serial: the board shows a running port after the upload."""
    eeprom: bytes | None = None
    serial_number: str | None = None
    emulator: CaterinaEmulator | None = None


class UsbBench:
    """A one-socket USB hub with a queue of boards a person plugs in one after another."""

    def __init__(
        self,
        directory: Path,
        boards: list[BenchBoard],
        *,
        location: str | None = SOCKET,
        swap_s: float = 0.0,
    ) -> None:
        """swap_s: how long after unplugging a board the person plugs in the next (on clock)."""
        self.directory = directory
        self.queue = list(boards)
        self.location = location
        self.clock = FakeClock()
        self.swap_s = swap_s
        self._next_plug_at = 0.0
        self.current: BenchBoard | None = None
        self.finished: list[BenchBoard] = []
        self.touched: list[str] = []
        self._ports: list[BoardPort] = []
        self._lock = threading.Lock()
        self._plug_next()

    # ---- UsbBus ------------------------------------------------------------------------------

    def boards(self) -> list[BoardPort]:
        if self.current is None and self.queue and self.clock() >= self._next_plug_at:
            self._plug_next()
        with self._lock:
            return list(self._ports)

    def touch(self, device: str) -> None:
        self.touched.append(device)
        board = self.current
        with self._lock:
            self._ports = [p for p in self._ports if p.device != device]
        if board is not None and board.answers_touch:
            self._start_bootloader(board)

    # ---- the person --------------------------------------------------------------------------

    def report(self, line: str) -> None:
        """The tool's progress output: a finished board is unplugged and the next plugged in."""
        if "FAILED" in line or "flashed and verified" in line:
            self._unplug()
            self._next_plug_at = self.clock() + self.swap_s

    def close(self) -> None:
        self._unplug()
        for board in self.queue:
            if board.emulator is not None:
                board.emulator.close()

    def _plug_next(self) -> None:
        if not self.queue:
            return
        board = self.current = self.queue.pop(0)
        if board.starts_in_bootloader:
            self._start_bootloader(board)
        else:
            self._show_running(board)

    def _unplug(self) -> None:
        board, self.current = self.current, None
        with self._lock:
            self._ports = []
        if board is not None:
            if board.emulator is not None:
                board.emulator.close()
            self.finished.append(board)

    def _start_bootloader(self, board: BenchBoard) -> None:
        path = self._device(board, "boot")
        board.emulator = CaterinaEmulator(
            Path(path),
            eeprom=board.eeprom,
            corrupt_flash=board.corrupt_flash,
            on_exit=lambda _: self._bootloader_left(board),
        )
        self._show(BoardPort(path, BoardMode.BOOTLOADER, None, self.location))

    def _bootloader_left(self, board: BenchBoard) -> None:
        with self._lock:
            self._ports = []
        if board.usb_firmware and board is self.current:
            self._show_running(board)

    def _show_running(self, board: BenchBoard) -> None:
        device = self._device(board, "run")
        self._show(BoardPort(device, BoardMode.RUNNING, board.serial_number, self.location))

    def _show(self, port: BoardPort) -> None:
        with self._lock:
            self._ports.append(port)

    def _device(self, board: BenchBoard, kind: str) -> str:
        return str(self.directory / f"tty-{board.name}-{kind}")
