"""A pseudo-terminal reached through a symlink, so tests can unplug and replug a 'USB' port."""

from __future__ import annotations

import os
import select
import time
import tty
from pathlib import Path


class VanishingPty:
    """The slave end is what the radio opens (via `path`); the test talks to the master end."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.master = -1
        self.slave = -1
        self.replug()

    def replug(self) -> None:
        self.master, self.slave = os.openpty()
        tty.setraw(self.slave)
        if self.path.is_symlink() or self.path.exists():
            self.path.unlink()
        os.symlink(os.ttyname(self.slave), self.path)

    def unplug(self) -> None:
        """Like pulling the USB cable: the device node goes and open handles start failing."""
        self.path.unlink()
        os.close(self.master)
        os.close(self.slave)
        self.master = self.slave = -1

    def write(self, data: bytes) -> None:
        os.write(self.master, data)

    def read_until(self, wanted: int, timeout: float = 2.0) -> bytes:
        """Reads from the master until `wanted` bytes came or timeout passed."""
        got = b""
        deadline = time.monotonic() + timeout
        while len(got) < wanted:
            left = deadline - time.monotonic()
            if left <= 0:
                break
            ready, _, _ = select.select([self.master], [], [], left)
            if ready:
                got += os.read(self.master, 4096)
        return got

    def close(self) -> None:
        if self.master >= 0:
            self.unplug()
