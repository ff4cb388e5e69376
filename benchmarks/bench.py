#!/usr/bin/env python3
"""Runs every benchmark whose figures README reports, one after another (`make bench`)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def _script(name: str) -> list[str]:
    """The command that runs one benchmark script of this folder."""
    return [sys.executable, f"benchmarks/{name}"]


# Each entry: a heading and the command that prints its figures. Order: cheapest first, so a
# reader sees results early; the emulator benchmark runs K simavr processes and takes minutes.
BENCHMARKS: list[tuple[str, list[str]]] = [
    ("Firmware image size against the budget", ["make", "-s", "firmware"]),
    ("Host protocol decoder", _script("bench_decoder.py")),
    ("Host receive path", _script("bench_host.py")),
    ("Simulated swarms in the world", _script("bench_world_swarms.py")),
    ("Vectorised firmware controller", _script("bench_firmware_controller.py")),
    ("STOP right after a base-station restart", _script("bench_stop_restart.py")),
    ("Swarm placement (SI Algorithm 5)", _script("bench_placement.py")),
    ("The world stepping a packed blob", _script("bench_world.py")),
    ("Firmware in the loop (simavr)", _script("bench_sim.py")),
    ("Video tracker on synthetic runs", _script("bench_tracker.py")),
]


def main() -> int:
    failed = []
    for index, (title, command) in enumerate(BENCHMARKS, start=1):
        print(f"\n== [{index}/{len(BENCHMARKS)}] {title}: {' '.join(command)}", flush=True)
        if subprocess.run(command, cwd=ROOT, check=False).returncode != 0:
            failed.append(title)
    if failed:
        print(f"\nfailed: {', '.join(failed)}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
