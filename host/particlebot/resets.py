"""Why a particle reset: the MCUSR bits its STATUS reports, in words, and how to spot a reset."""

from __future__ import annotations

from particlebot.protocol import Status

# MCUSR bits of the ATmega32U4 (datasheet section 8.9.1), a hardware register the firmware reports
# as it found it at boot, not a value the firmware defines.
PORF = 0x01  # power-on
EXTRF = 0x02  # external: the RESET pin (the Fio's button, or a programmer)
BORF = 0x04  # brown-out: the supply dipped below the BOD level
WDRF = 0x08  # watchdog: the firmware hung for longer than its 250 ms watchdog
JTRF = 0x10  # JTAG reset instruction

# The cause named when several bits are set: power-on sets BORF as well while the supply rises, so
# it comes first; the others are rare together.
_CAUSES = (
    (PORF, "power-on"),
    (WDRF, "watchdog"),
    (BORF, "brown-out"),
    (EXTRF, "external"),
    (JTRF, "JTAG"),
)

ADVICE = {
    "brown-out": "the supply dipped, typically a weak battery under servo load",
    "watchdog": "the firmware stopped for over 250 ms",
    "external": "its reset button or a programmer",
    "power-on": "it was switched off and on, or lost power",
}


def reset_cause(mcusr: int) -> str:
    """The main cause in MCUSR, e.g. "brown-out"; "unknown" when no bit is set (behind the USB
    bootloader, which clears MCUSR before the firmware can read it)."""
    for bit, name in _CAUSES:
        if mcusr & bit:
            return name
    return "unknown"


UPTIME_WRAP_MS = 1 << 32
"""uptime_ms is a u32: it wraps after 49.7 days, which is not a reset."""


def reset_between(before: Status, after: Status) -> bool:
    """Whether the particle reset between two of its STATUS reports: its reset counter moved (it
    saturates at 255) or its uptime went back (which a counter that saturated still shows)."""
    return restarted(before.resets, before.uptime_ms, after.resets, after.uptime_ms)


def restarted(resets_before: int, uptime_before: int, resets_after: int, uptime_after: int) -> bool:
    """reset_between on the bare fields (a log's records hold them as numbers)."""
    # A wrap takes the uptime from near 2^32 back to near 0; a reset starts it again from 0 at any
    # time. Within ten minutes of the wrap the two cannot be told apart: take it as the wrap.
    wrapped = uptime_before > UPTIME_WRAP_MS - 600_000
    return resets_after != resets_before or (uptime_after < uptime_before and not wrapped)
