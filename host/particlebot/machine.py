"""What this machine can hold: its memory, and a refusal in one line for a job beyond it, said
before anything is allocated (a MemoryError half-way through helps nobody)."""

from __future__ import annotations

import os

from particlebot.errors import ParticlebotError


class TooBigError(ParticlebotError):
    """A job that needs more than the machine has; the message says how much of each."""


def available_memory() -> int:
    """Bytes this process may still allocate without the machine swapping: Linux's MemAvailable,
    else the physical memory (other systems)."""
    try:
        with open("/proc/meminfo", encoding="ascii") as meminfo:
            for line in meminfo:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (ValueError, OSError, AttributeError):
        return 1 << 62  # nothing to go by: let the allocation itself decide


def size_text(count: float) -> str:
    """Bytes as a person reads them: 3.1 GiB, 12 TiB, 8.7e+21 B beyond YiB."""
    value = float(count)
    for unit in ("B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB", "ZiB", "YiB"):
        if value < 1024 or unit == "YiB":
            return f"{value:.3g} {unit}"
        value /= 1024
    return f"{count:.3g} B"  # pragma: no cover (the loop returns)


def check_memory(need: float, what: str) -> None:
    """TooBigError when `need` bytes exceed what the machine has free; `what` is the job, as in
    "10,000,000,000 particles"."""
    have = available_memory()
    if need > have:
        raise TooBigError(
            f"{what} would need about {size_text(need)} of memory; "
            f"this machine has {size_text(have)} free"
        )
