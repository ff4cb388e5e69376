"""Boot a raw flash image in simavr and ask it who it is: its id and protocol definition hash.

The image is what a bootloader holds, or an Intel HEX file's bytes; the STATUS it answers a PING
with carries both."""

from __future__ import annotations

import shutil
import subprocess
import tempfile
from dataclasses import dataclass
from pathlib import Path

from particlebot.errors import ParticlebotError
from particlebot.protocol import (
    BASE_STATION_ID,
    BROADCAST_ID,
    Ping,
    Status,
    StreamDecoder,
    encode_frame,
)
from particlebot.sim.particles.emulated.harness import HarnessBuildError, HarnessError, ParticleSim

_BOOT_US = 100_000
_STEP_US = 100_000


class BootError(ParticlebotError, RuntimeError):
    """The image never answered as a particle does."""


class EmulatorMissingError(BootError):
    """The image could not be run: avr-objcopy or the simavr harness is not built/installed."""


@dataclass(frozen=True)
class BootReport:
    particle_id: int
    status: Status
    time_s: float
    """Simulated seconds from power-on to the STATUS."""


def elf_from_flash(flash: bytes, elf: Path) -> None:
    """Wraps raw flash bytes (from address 0) in an ELF simavr loads, with avr-objcopy."""
    objcopy = shutil.which("avr-objcopy")
    if objcopy is None:
        raise EmulatorMissingError(
            "avr-objcopy is missing (`make system-deps` installs binutils-avr)"
        )
    raw = elf.with_suffix(".bin")
    raw.write_bytes(flash)
    result = subprocess.run(
        [
            objcopy,
            "-I",
            "binary",
            "-O",
            "elf32-avr",
            # simavr loads the section named .text into flash at its address (0).
            "--rename-section",
            ".data=.text,contents,alloc,load,readonly,code",
            str(raw),
            str(elf),
        ],
        capture_output=True,
        text=True,
        check=False,
    )
    raw.unlink()
    if result.returncode != 0:
        raise BootError(f"avr-objcopy failed: {result.stderr.strip()}")


def boot_and_ping(
    flash: bytes,
    *,
    eeprom: bytes | None = None,
    harness: Path | None = None,
    timeout_s: float = 3.0,
) -> BootReport:
    """Powers the image up with this EEPROM, PINGs every particle, returns the STATUS answer."""
    with tempfile.TemporaryDirectory(prefix="particle-image-") as directory:
        elf = Path(directory) / "image.elf"
        elf_from_flash(flash, elf)
        try:
            sim = ParticleSim(elf, harness=harness, eeprom=eeprom)
        except (FileNotFoundError, HarnessBuildError) as exc:
            raise EmulatorMissingError(str(exc)) from None
        try:
            return _ping(sim, timeout_s)
        except HarnessError as exc:
            raise BootError(f"the image crashed the emulator: {exc}") from None
        finally:
            sim.close()


def _ping(sim: ParticleSim, timeout_s: float) -> BootReport:
    sim.run_for(_BOOT_US)
    sim.send_uart(encode_frame(Ping(target=BROADCAST_ID), BASE_STATION_ID, 1))
    decoder = StreamDecoder()
    read = 0
    while sim.time_s < timeout_s:
        sim.run_for(_STEP_US)
        fresh, read = sim.uart[read:], len(sim.uart)
        for frame in decoder.feed(bytes(byte.value for byte in fresh)):
            message = frame.message
            if isinstance(message, Status):
                return BootReport(frame.sender, message, sim.time_s)
    raise BootError(
        f"the image sent no STATUS within {timeout_s:.0f} s of emulated time: it does not "
        "behave like a particle firmware"
    )
