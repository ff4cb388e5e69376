"""The default image's USB port: a 1200-baud touch lets the watchdog bite (so the bootloader
runs), and the port describes itself to a host exactly as the Arduino core would."""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest

from particlebot.sim.particles.emulated.harness import ParticleSim, default_elf

pytestmark = pytest.mark.usefixtures("built_images")

# The core's USB code sets the watchdog to WDTO_120MS. A real chip resets 120 ms after the last
# watchdog reset; simavr 1.6 applies a new period only at the next one, which never comes, so
# here the particle's own 250 ms period runs out. Either way it resets, where a loop that kept
# feeding the watchdog would never let it.
LATEST_RESET_S = 0.3


def test_a_usb_touch_resets_the_particle_by_its_watchdog() -> None:
    with ParticleSim() as sim:
        sim.run_for(300_000)  # booted and looping, feeding its own 250 ms watchdog
        assert sim.resets == []
        touched_s = sim.time_s
        sim.usb_touch()
        reset = sim.run_until_reset(timeout_us=1_000_000)
        assert reset is not None, "the loop kept feeding the watchdog: no bootloader"
        assert reset.by_watchdog
        assert reset.time_s - touched_s <= LATEST_RESET_S


def test_without_a_touch_the_watchdog_never_bites() -> None:
    with ParticleSim() as sim:
        assert sim.run_until_reset(timeout_us=1_500_000) is None


ARDUINO_CORE = Path("/usr/share/arduino/hardware/arduino/avr")
ARDUINO_FLAGS = [
    "-mmcu=atmega32u4",
    "-DF_CPU=8000000L",
    "-DARDUINO=10807",
    "-DARDUINO_AVR_FIOV3",
    "-DARDUINO_ARCH_AVR",
    "-DUSB_VID=0x1B4F",
    "-DUSB_PID=0xF101",
    "-DDECIMAL_DIG=__DECIMAL_DIG__",
    "-std=gnu++11",
    "-Os",
    "-fdata-sections",
    f"-I{ARDUINO_CORE}/cores/arduino",
    f"-I{ARDUINO_CORE}/variants/leonardo",
]


def symbol_bytes(elf: Path, symbol: str, section: str, tmp_path: Path) -> bytes:
    """The bytes of a data symbol of elf, read from the section that holds it."""
    listing = subprocess.run(
        ["avr-nm", "-S", str(elf)], capture_output=True, text=True, check=True
    ).stdout
    address, size = next(
        (int(words[0], 16), int(words[1], 16))
        for words in (line.split() for line in listing.splitlines())
        if len(words) == 4 and words[3] == symbol
    )
    dump = tmp_path / f"{symbol}.bin"
    subprocess.run(
        ["avr-objcopy", "-O", "binary", f"--only-section={section}", str(elf), str(dump)],
        check=True,
    )
    data = dump.read_bytes()
    return data[address : address + size]


def test_the_upload_ports_descriptors_are_those_the_arduino_core_sends(tmp_path: Path) -> None:
    # The particle keeps the Arduino core's USB driver but answers for the CDC function itself
    # (firmware/src/usb_upload_port.cpp). Its descriptors must be what hosts enumerate a Fio by:
    # compare them byte for byte with those of the core's own CDC.cpp.
    if not (ARDUINO_CORE / "cores/arduino/CDC.cpp").exists():
        pytest.skip("the Arduino core (arduino-core-avr) is not installed")
    reference = tmp_path / "CDC.o"
    subprocess.run(
        [
            "avr-g++",
            *ARDUINO_FLAGS,
            "-c",
            str(ARDUINO_CORE / "cores/arduino/CDC.cpp"),
            "-o",
            str(reference),
        ],
        check=True,
    )
    expected = symbol_bytes(reference, "_cdcInterface", ".progmem.data._cdcInterface", tmp_path)
    ours = symbol_bytes(default_elf(), "_ZN12_GLOBAL__N_1L12kCdcFunctionE", ".text", tmp_path)
    assert len(expected) == 66
    assert ours == expected
