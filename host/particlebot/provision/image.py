"""The firmware image to flash: an Intel HEX file, checked before any board is touched."""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from pathlib import Path

from particlebot.errors import ParticlebotError

APPLICATION_FLASH = 28_672
"""Flash the Fio v3's Caterina bootloader leaves to the firmware (32 KB less its 4 KB)."""


class ImageError(ParticlebotError, ValueError):
    """The file is missing, unreadable or not an Intel HEX image that fits; one line says which."""


@dataclass(frozen=True)
class FirmwareImage:
    path: Path
    flash: bytes
    """The image as flash bytes from address 0 (gaps erased, 0xFF)."""
    sha256: str
    """Of the file as given, so the fleet file names exactly what was flashed."""

    @classmethod
    def load(cls, path: Path) -> FirmwareImage:
        try:
            data = path.read_bytes()
        except FileNotFoundError:
            raise ImageError(f"no firmware image {path}: build it with `make firmware`") from None
        except OSError as exc:
            raise ImageError(f"cannot read {path}: {exc.strerror}") from None
        try:
            text = data.decode("ascii")
        except UnicodeDecodeError:
            raise ImageError(f"{path} is not an Intel HEX file (binary data)") from None
        flash = parse_intel_hex(text, path)
        if len(flash) > APPLICATION_FLASH:
            raise ImageError(
                f"{path} needs {len(flash):,} B of flash; the bootloader leaves "
                f"{APPLICATION_FLASH:,} B"
            )
        return cls(path=path, flash=flash, sha256=hashlib.sha256(data).hexdigest())

    @property
    def size(self) -> int:
        return len(self.flash)


def parse_intel_hex(text: str, path: Path | str = "image") -> bytes:
    """Flash bytes of an Intel HEX text (data, end-of-file and address records)."""
    memory: dict[int, int] = {}
    base = 0
    ended = False
    for number, raw_line in enumerate(text.splitlines(), start=1):
        line = raw_line.strip()
        if not line:
            continue
        where = f"{path} line {number}"
        if ended:
            raise ImageError(f"{where}: data after the end-of-file record")
        if not line.startswith(":"):
            raise ImageError(f"{where}: not an Intel HEX record (expected ':')")
        try:
            record = bytes.fromhex(line[1:])
        except ValueError:
            raise ImageError(f"{where}: not hexadecimal") from None
        if len(record) < 5 or len(record) != 5 + record[0]:
            raise ImageError(f"{where}: the record's length is wrong")
        if sum(record) & 0xFF:
            raise ImageError(f"{where}: bad checksum")
        count, kind, payload = record[0], record[3], record[4:-1]
        address = (record[1] << 8) | record[2]
        if kind == 0x00:
            for offset, byte in enumerate(payload):
                memory[base + address + offset] = byte
        elif kind == 0x01:
            ended = True
        elif kind == 0x02 and count == 2:
            base = ((payload[0] << 8) | payload[1]) << 4
        elif kind == 0x04 and count == 2:
            base = ((payload[0] << 8) | payload[1]) << 16
        elif kind in (0x03, 0x05):
            continue  # start addresses: meaningless for an AVR
        else:
            raise ImageError(f"{where}: unknown record type {kind:02X}")
    if not ended:
        raise ImageError(f"{path} ends without the end-of-file record: truncated?")
    if not memory:
        raise ImageError(f"{path} holds no data")
    flash = bytearray(b"\xff" * (max(memory) + 1))
    for address, byte in memory.items():
        flash[address] = byte
    return bytes(flash)
