"""Uploading to a Fio v3's Caterina bootloader with avrdude: flash and EEPROM in one session.

Caterina leaves its bootloader when avrdude closes the port (AVR109 'E'), so a second avrdude
run would need a second reset, which a board whose firmware has no USB stack cannot be given
from here. One session therefore does everything: avrdude's terminal mode (-t) reads the
EEPROM, the caller decides what it should hold, the changed bytes are written back (avrdude
verifies them as it writes its cache out at `quit`), and then the -U operation writes and
verifies the flash image. avrdude runs terminal mode before -U operations.
"""

from __future__ import annotations

import re
import shutil
import subprocess
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import IO

from particlebot.errors import ParticlebotError

EEPROM_SIZE = 1024
"""The ATmega32U4's EEPROM (datasheet), which avrdude reads whole."""
PART = "atmega32u4"
PROGRAMMER = "avr109"
# Caterina ignores the line rate (USB CDC); 57600 is what the Arduino tools pass, and anything
# but 1200 (the reset request) would do.
BAUD = 57600

_PROMPT = "avrdude> "
_DUMP_LINE = re.compile(r"^\s*([0-9a-fA-F]{4,})\s+((?:[0-9a-fA-F]{2}\s+){1,16})")
_WRITE_CHUNK = 32
_FAILURE_WORDS = ("error", "mismatch", "not respond", "can't", "cannot", "failed", "timeout")


class AvrdudeError(ParticlebotError):
    """avrdude is missing, or the session failed; the message is one line saying why."""


@dataclass(frozen=True)
class UploadReport:
    eeprom_before: bytes
    eeprom_after: bytes
    eeprom_bytes_written: int
    flash_bytes_verified: int
    seconds: float


EepromEditor = Callable[[bytes], bytes]
"""Given the EEPROM the board holds, returns what it should hold (same length)."""


def find_avrdude(executable: str = "avrdude") -> str:
    path = shutil.which(executable)
    if path is None:
        raise AvrdudeError(
            f"{executable} is not installed: `make system-deps` installs it "
            "(Debian/Ubuntu: sudo apt install avrdude)"
        )
    return path


class Avrdude:
    """Runs avrdude against one bootloader port per upload()."""

    def __init__(
        self,
        executable: str = "avrdude",
        *,
        start_timeout_s: float = 20.0,
        command_timeout_s: float = 15.0,
        finish_timeout_s: float = 120.0,
    ) -> None:
        self.executable = find_avrdude(executable)
        self.start_timeout_s = start_timeout_s
        self.command_timeout_s = command_timeout_s
        self.finish_timeout_s = finish_timeout_s

    def upload(self, port: str, hex_file: Path, edit_eeprom: EepromEditor) -> UploadReport:
        started = time.monotonic()
        session = _TerminalSession(
            [
                self.executable,
                "-p",
                PART,
                "-c",
                PROGRAMMER,
                "-P",
                port,
                "-b",
                str(BAUD),
                "-D",  # Caterina erases each page as it writes it; no chip erase
                "-q",  # no progress bars
                "-U",
                f"flash:w:{hex_file}:i",
                "-t",
            ]
        )
        try:
            session.wait_for_prompt(self.start_timeout_s)
            before = parse_dump(
                session.command(f"dump eeprom 0 {EEPROM_SIZE}", self.command_timeout_s),
                EEPROM_SIZE,
            )
            after = edit_eeprom(before)
            if len(after) != len(before):
                raise ValueError("the EEPROM editor changed the image's length")
            commands = write_commands(before, after)
            for line in commands:
                session.command(line, self.command_timeout_s)
            output = session.finish("quit", self.finish_timeout_s)
        finally:
            # On failure the board stays in its bootloader until that times out (8 s).
            session.close()
        return UploadReport(
            eeprom_before=before,
            eeprom_after=after,
            eeprom_bytes_written=sum(a != b for a, b in zip(before, after, strict=True)),
            flash_bytes_verified=_verified_bytes(output),
            seconds=time.monotonic() - started,
        )


def parse_dump(text: str, size: int) -> bytes:
    """Bytes of avrdude's `dump` output ("ADDR  hh hh ...  |ascii|" lines) from address 0.

    A run of identical lines may be printed once followed by "*" (as hexdump does); the gap is
    filled with the line before it.
    """
    image = bytearray()
    previous = b""
    for line in text.splitlines():
        match = _DUMP_LINE.match(line)
        if not match:
            continue
        address = int(match.group(1), 16)
        data = bytes.fromhex(match.group(2))
        while len(image) < address and previous:
            image += previous[: address - len(image)]
        if len(image) != address:
            raise AvrdudeError(f"unexpected line in avrdude's EEPROM dump: {line.strip()}")
        image += data
        previous = data
    while len(image) < size and previous and text.rstrip().endswith("*"):
        image += previous[: size - len(image)]
    if len(image) < size:
        raise AvrdudeError(f"avrdude's EEPROM dump held {len(image)} of {size} bytes")
    return bytes(image[:size])


def write_commands(before: bytes, after: bytes) -> list[str]:
    """Terminal `write eeprom` lines that change before into after, changed runs only."""
    lines: list[str] = []
    address = 0
    while address < len(after):
        if before[address] == after[address]:
            address += 1
            continue
        end = address
        while end < len(after) and end - address < _WRITE_CHUNK and before[end] != after[end]:
            end += 1
        values = " ".join(f"0x{b:02x}" for b in after[address:end])
        lines.append(f"write eeprom 0x{address:04x} {values}")
        address = end
    return lines


def _verified_bytes(output: str) -> int:
    match = re.search(r"(\d+) bytes of flash verified", output)
    return int(match.group(1)) if match else 0


def failure_reason(output: str) -> str:
    """The line of avrdude's output that best says what went wrong, with its indented details."""
    lines = [line.rstrip() for line in output.splitlines() if line.strip()]
    for index, line in enumerate(lines):
        if any(word in line.lower() for word in _FAILURE_WORDS):
            details = []
            for follower in lines[index + 1 :]:
                if not follower[:1].isspace():
                    break
                details.append(follower.strip())
            return ": ".join([_tidy(line.strip()), *details])
    return _tidy(lines[-1].strip()) if lines else "no output"


def _tidy(line: str) -> str:
    line = re.sub(r"^avrdude( OS)?( error| warning)?:\s*", "", line)
    return re.sub(r"^\w+\(\):\s*", "", line)


class _TerminalSession:
    """avrdude in terminal mode on pipes; stdout is searched for the prompt, stderr kept."""

    def __init__(self, argv: Sequence[str]) -> None:
        self._proc = subprocess.Popen(
            list(argv),
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            bufsize=1,
        )
        self._out = ""
        self._err = ""
        self._changed = threading.Condition()
        self._readers = [
            threading.Thread(target=self._pump, args=(self._proc.stdout, False), daemon=True),
            threading.Thread(target=self._pump, args=(self._proc.stderr, True), daemon=True),
        ]
        for reader in self._readers:
            reader.start()
        self._consumed = 0

    def _pump(self, stream: IO[str] | None, is_stderr: bool) -> None:
        if stream is None:
            return
        for chunk in iter(lambda: stream.read(1), ""):
            with self._changed:
                if is_stderr:
                    self._err += chunk
                else:
                    self._out += chunk
                self._changed.notify_all()
        with self._changed:
            self._changed.notify_all()

    def wait_for_prompt(self, timeout: float) -> str:
        """Output up to the next prompt; AvrdudeError if avrdude ends or stalls first."""
        deadline = time.monotonic() + timeout
        with self._changed:
            while True:
                at = self._out.find(_PROMPT, self._consumed)
                if at >= 0:
                    text = self._out[self._consumed : at]
                    self._consumed = at + len(_PROMPT)
                    return text
                if self._proc.poll() is not None and not any(r.is_alive() for r in self._readers):
                    raise AvrdudeError(failure_reason(self._err + self._out))
                left = deadline - time.monotonic()
                if left <= 0:
                    raise AvrdudeError(
                        f"avrdude did not answer within {timeout:.0f} s "
                        f"({failure_reason(self._err)})"
                    )
                self._changed.wait(min(left, 0.1))

    def command(self, line: str, timeout: float) -> str:
        self._send(line)
        return self.wait_for_prompt(timeout)

    def finish(self, line: str, timeout: float) -> str:
        """Sends the last command and waits for avrdude to exit; its output, or AvrdudeError."""
        self._send(line)
        try:
            code = self._proc.wait(timeout)
        except subprocess.TimeoutExpired:
            raise AvrdudeError(f"avrdude did not finish within {timeout:.0f} s") from None
        for reader in self._readers:
            reader.join(timeout=5)
        output = self._err + self._out
        if code != 0:
            raise AvrdudeError(failure_reason(output))
        return output

    def _send(self, line: str) -> None:
        stdin = self._proc.stdin
        if stdin is None:
            raise AvrdudeError("avrdude's input is closed")
        try:
            stdin.write(line + "\n")
            stdin.flush()
        except (BrokenPipeError, OSError):
            raise AvrdudeError(failure_reason(self._err + self._out)) from None

    def close(self) -> None:
        """Ends avrdude if it still runs (without its goodbye to the bootloader)."""
        if self._proc.poll() is None:
            self._proc.kill()
        self._proc.wait()
        for stream in (self._proc.stdin, self._proc.stdout, self._proc.stderr):
            if stream is not None:
                stream.close()
