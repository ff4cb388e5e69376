"""One emulated particle: the real firmware ELF in simavr (particle_sim.c beside it), from Python.

Simulated time advances only inside run_until()/run_for(); between runs the emulated particle is
frozen, so several ParticleSim objects stay in lockstep when each is run to the same cycle
(begin_run() on all of them, then finish_run() on all, lets their processes work in parallel).
The wire protocol is described in particle_sim.md beside this module.
"""

from __future__ import annotations

import os
import shlex
import shutil
import subprocess
import tempfile
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import IO

from particlebot import resources
from particlebot.closing import ClosedOnExit
from particlebot.errors import ParticlebotError
from particlebot.fileio import atomic_path
from particlebot.sim.clock import CPU_HZ

SENSOR_COUNT = 6
EEPROM_SIZE = 1024
FAULT_PIN = ("D", 1)
"""Arduino D2 (PD1): the fault-injection build hangs (and the watchdog bites) while it is low."""
MCUSR_POWER_ON = 0x01
MCUSR_WATCHDOG = 0x08

HARNESS_PACKAGES = ("gcc", "pkg-config", "libsimavr-dev", "libelf-dev")
"""Debian's packages that building the harness needs."""


def default_harness() -> Path:
    """The harness executable (see particlebot.resources; it may not be built yet)."""
    return resources.harness()


def default_elf(faults: bool = False) -> Path:
    """The firmware `make firmware` (or, with faults, `make firmware-faults`) builds, or the image
    an installed wheel carries."""
    return resources.firmware_image(faults=faults, suffix=".elf")


class HarnessBuildError(ParticlebotError, RuntimeError):
    """The harness is missing and cannot be built here; the message is one line saying why."""


def _missing_build_tools() -> list[str]:
    missing = [tool for tool in ("gcc", "pkg-config") if shutil.which(tool) is None]
    if missing:
        return [*missing, "libsimavr-dev", "libelf-dev"]
    for module, package in (("simavr", "libsimavr-dev"), ("libelf", "libelf-dev")):
        found = subprocess.run(["pkg-config", "--exists", module], check=False)
        if found.returncode != 0:
            missing.append(package)
    return missing


def ensure_harness(path: Path | None = None) -> Path:
    """The harness at path (default: default_harness()), compiled from this package's
    particle_sim.c first when it is not there yet, as `make harness` does in a clone."""
    path = path or default_harness()
    if path.exists():
        return path
    if resources.ENV_SIM_HARNESS in os.environ:
        raise HarnessBuildError(f"no simavr harness at {path}: fix {resources.ENV_SIM_HARNESS}")
    missing = _missing_build_tools()
    if missing:
        raise HarnessBuildError(
            "emulated particles need the simavr harness, built once from "
            f"{resources.HARNESS_SOURCE.name}; install {', '.join(missing)} first "
            f"(Debian/Ubuntu: sudo apt-get install {' '.join(HARNESS_PACKAGES)})"
        )
    path.parent.mkdir(parents=True, exist_ok=True)

    def pkg_config(*options: str) -> list[str]:
        command = ["pkg-config", *options, "simavr"]
        found = subprocess.run(command, capture_output=True, text=True, check=False)
        return shlex.split(found.stdout)

    # simavr's headers as system headers, so that warnings judge only our code (as the Makefile).
    includes = [w for i in pkg_config("--cflags-only-I") for w in ("-isystem", i[2:])]
    # Built beside its final name and renamed (fileio), so that a parallel first use never runs
    # half a file and a failed build leaves nothing behind.
    with atomic_path(path, mode=0o755) as partial:
        command = ["gcc", "-std=gnu11", "-O2", *includes, "-o", str(partial)]
        command += [str(resources.HARNESS_SOURCE), *pkg_config("--libs"), "-lelf"]
        result = subprocess.run(command, capture_output=True, text=True, check=False)
        if result.returncode != 0:
            last = (result.stderr.strip().splitlines() or ["(no output)"])[-1]
            raise HarnessBuildError(f"building the simavr harness failed: {last}")
    return path


@dataclass(frozen=True)
class UartByte:
    """A byte the firmware finished sending on Serial1."""

    cycle: int
    value: int

    @property
    def time_s(self) -> float:
        return self.cycle / CPU_HZ


@dataclass(frozen=True)
class ServoPulse:
    """One high pulse on the servo pin D9."""

    start_cycle: int
    end_cycle: int

    @property
    def start_s(self) -> float:
        return self.start_cycle / CPU_HZ

    @property
    def width_us(self) -> float:
        return (self.end_cycle - self.start_cycle) * 1e6 / CPU_HZ


@dataclass(frozen=True)
class Reset:
    """A reset of the emulated AVR after power-on; mcusr is what the firmware finds in MCUSR."""

    cycle: int
    mcusr: int

    @property
    def time_s(self) -> float:
        return self.cycle / CPU_HZ

    @property
    def by_watchdog(self) -> bool:
        return bool(self.mcusr & MCUSR_WATCHDOG)


class HarnessError(ParticlebotError, RuntimeError):
    """The harness process refused a command, died, or said something unexpected."""


class ParticleSim(ClosedOnExit):
    """A particle_sim process running one firmware image; collects what the firmware does.

    uart, servo_pulses and resets grow as simulated time passes; forget() drops what was kept.
    """

    def __init__(
        self,
        elf: Path | None = None,
        *,
        harness: Path | None = None,
        eeprom: bytes | None = None,
        light_mv: Sequence[int] | None = None,
        noise_mv: int | None = None,
    ) -> None:
        """light_mv: the photocells' voltages (default 1650 mV each). noise_mv: what the chip's
        temperature sensor reads (default 300 mV); the firmware seeds its random numbers from it
        and the photocells, so particles of a swarm need different values."""
        elf = elf or default_elf()
        if not elf.exists():
            advice = "run `make firmware`" if resources.source_root() else "pass an ELF"
            raise FileNotFoundError(f"{elf} is missing: {advice}")
        harness = ensure_harness(harness)
        args = [str(harness)]
        self._eeprom_file: Path | None = None
        if eeprom is not None:
            if len(eeprom) > EEPROM_SIZE:
                raise ValueError(f"EEPROM image of {len(eeprom)} bytes exceeds {EEPROM_SIZE}")
            fd, name = tempfile.mkstemp(prefix="particle-eeprom-", suffix=".bin")
            with os.fdopen(fd, "wb") as file:
                file.write(eeprom)
            self._eeprom_file = Path(name)
            args += ["--eeprom-in", name]
        args.append(str(elf))
        # Closed in close(): the object outlives this method.
        self._stderr: IO[bytes] = tempfile.TemporaryFile()  # noqa: SIM115
        self._proc = subprocess.Popen(
            args, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=self._stderr
        )
        self.cycle = 0
        self.uart: list[UartByte] = []
        self.servo_pulses: list[ServoPulse] = []
        self.resets: list[Reset] = []
        self.crashed_cycle: int | None = None
        self._rise: int | None = None
        self._running = False
        hello = self._readline().split()
        if hello != ["hello", "particle_sim", "1", str(CPU_HZ)]:
            raise HarnessError(f"unexpected greeting {hello!r}")
        if self._eeprom_file is not None:  # read before the greeting
            self._eeprom_file.unlink()
            self._eeprom_file = None
        if light_mv is not None:
            self.set_light_mv(light_mv)
        if noise_mv is not None:
            self.set_noise_mv(noise_mv)

    # ---- time --------------------------------------------------------------------------------

    @property
    def time_s(self) -> float:
        """Simulated seconds since power-on."""
        return self.cycle / CPU_HZ

    def begin_run(self, cycle: int) -> None:
        """Lets the particle run up to cycle; finish_run() waits for it."""
        self._send(f"run {cycle}")
        self._running = True

    def finish_run(self) -> None:
        """Collects the events of the run begun by begin_run(), up to the harness's `at`."""
        if not self._running:
            raise HarnessError("finish_run() without begin_run()")
        self._running = False
        while True:
            words = self._readline().split()
            if words[0] == "at":
                self.cycle = int(words[1])
                return
            self._event(words)

    def run_until(self, cycle: int) -> None:
        self.begin_run(cycle)
        self.finish_run()

    def run_for(self, us: float) -> None:
        self.run_until(self.cycle + round(us * CPU_HZ / 1_000_000))

    def run_until_reset(self, timeout_us: float, step_us: float = 1000.0) -> Reset | None:
        """Runs in steps of step_us until the AVR resets (returns that reset) or timeout_us pass
        (returns None). Stops within step_us of the reset, before the firmware is far into its
        boot, so a test can change the inputs the rebooted firmware will see."""
        resets_before = len(self.resets)
        end = self.cycle + round(timeout_us * CPU_HZ / 1_000_000)
        while self.cycle < end and len(self.resets) == resets_before:
            self.run_until(min(end, self.cycle + round(step_us * CPU_HZ / 1_000_000)))
        return self.resets[resets_before] if len(self.resets) > resets_before else None

    # ---- inputs ------------------------------------------------------------------------------

    def send_uart(self, data: bytes) -> None:
        """Queues bytes for Serial1's receiver; they arrive at 9600 baud, one after the other."""
        for start in range(0, len(data), 2048):
            self._send(f"rx {data[start : start + 2048].hex()}")

    def set_light_mv(self, mv: Sequence[int]) -> None:
        """The voltage each photocell divider (A0..A5) presents from now on, 0..3300 mV."""
        if len(mv) != SENSOR_COUNT:
            raise ValueError(f"need {SENSOR_COUNT} values, got {len(mv)}")
        for k, value in enumerate(mv):
            self._send(f"light {k} {self._millivolts(value)}")

    def set_noise_mv(self, mv: int) -> None:
        """What the temperature sensor reads; only the next boot's random seed depends on it."""
        self._send(f"temp {self._millivolts(mv)}")

    def set_pin(self, port: str, bit: int, level: bool) -> None:
        """Drives an input pin from outside (it beats the internal pull-up), across resets."""
        if port not in "BCDEF" or len(port) != 1 or not 0 <= bit <= 7:
            raise ValueError(f"no pin P{port}{bit}")
        self._send(f"pin {port}{bit} {int(level)}")

    def set_fault_pin(self, asserted: bool) -> None:
        """Pulls D2 low (asserted) or lets it go high; only particle-faults.elf looks at it."""
        self.set_pin(*FAULT_PIN, not asserted)

    def usb_touch(self) -> None:
        """What the Arduino core's USB code does when a host closes the port it opened at 1200
        baud: the bootloader's key in RAM and the watchdog set to 120 ms, expecting a reset into
        the bootloader. (simavr has no USB; the emulated chip has no bootloader, so the firmware
        simply starts again.)"""
        self._send("usb-touch")

    # ---- outputs -----------------------------------------------------------------------------

    def forget(self) -> None:
        """Drops the UART bytes and servo pulses recorded so far, so that a long run (the console
        driving a swarm for hours) keeps its memory bounded."""
        self.uart.clear()
        self.servo_pulses.clear()

    def eeprom(self) -> bytes:
        """The emulated chip's 1024 EEPROM bytes now."""
        self._send("eeprom")
        words = self._readline().split()
        while words[0] != "eeprom":  # events cannot come outside a run, but stay tolerant
            self._event(words)
            words = self._readline().split()
        data = bytes.fromhex(words[1])
        if len(data) != EEPROM_SIZE:
            raise HarnessError(f"EEPROM dump of {len(data)} bytes")
        return data

    # ---- lifetime ----------------------------------------------------------------------------

    def close(self) -> None:
        if self._proc.poll() is None:
            try:
                self._send("quit")
                self._proc.communicate(timeout=10)
            except (HarnessError, OSError, subprocess.TimeoutExpired):
                self._proc.kill()
                self._proc.wait()
        for stream in (self._proc.stdin, self._proc.stdout):
            if stream is not None:
                stream.close()
        self._stderr.close()
        if self._eeprom_file is not None:
            self._eeprom_file.unlink(missing_ok=True)
            self._eeprom_file = None

    # ---- plumbing ----------------------------------------------------------------------------

    @staticmethod
    def _millivolts(mv: int) -> int:
        if not 0 <= mv <= 5500:
            raise ValueError(f"{mv} mV is outside what the ADC pins take")
        return int(mv)

    def _send(self, line: str) -> None:
        if self._running:
            raise HarnessError("a run is in flight: call finish_run() first")
        stdin = self._proc.stdin
        if stdin is None:
            raise HarnessError("harness closed")
        try:
            stdin.write(line.encode() + b"\n")
            stdin.flush()
        except BrokenPipeError as error:
            raise HarnessError(f"harness died: {self._stderr_text()}") from error

    def _readline(self) -> str:
        stdout = self._proc.stdout
        if stdout is None:
            raise HarnessError("harness closed")
        line = stdout.readline().decode()
        if not line:
            self._proc.wait()
            raise HarnessError(
                f"harness exited with {self._proc.returncode}: {self._stderr_text()}"
            )
        if line.startswith("error"):
            raise HarnessError(line.strip())
        return line

    def _stderr_text(self) -> str:
        self._stderr.seek(0)
        return self._stderr.read().decode(errors="replace")[-2000:]

    def _event(self, words: list[str]) -> None:
        kind = words[0]
        if kind == "tx":
            self.uart.append(UartByte(int(words[1]), int(words[2], 16)))
        elif kind == "servo":
            cycle = int(words[1])
            if words[2] == "1":
                self._rise = cycle
            elif self._rise is not None:
                self.servo_pulses.append(ServoPulse(self._rise, cycle))
                self._rise = None
        elif kind == "reset":
            self.resets.append(Reset(int(words[1]), int(words[2], 16)))
        elif kind == "crashed":
            self.crashed_cycle = int(words[1])
        else:
            raise HarnessError(f"unexpected line from the harness: {' '.join(words)}")
