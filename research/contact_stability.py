#!/usr/bin/env python3
"""Whether the world's explicit step is stable in a packed swarm: the spectral radius of one step,
linearised, for a touching hexagonal patch, over dashpots and shears (why swarms "boil"); the
analysis is particlebot.sim.world.stability, this prints and writes its table."""

from __future__ import annotations

import argparse
import csv
import math
import sys
from dataclasses import replace
from pathlib import Path

from particlebot.sim.world import PhysicsParams
from particlebot.sim.world.stability import hexagonal_patch, stability


def _numbers(text: str) -> list[float]:
    try:
        values = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a list of numbers: {text!r}") from None
    if not values or any(not math.isfinite(v) or v < 0 for v in values):
        raise argparse.ArgumentTypeError(f"need numbers >= 0: {text!r}")
    return values


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument(
        "--dampings", type=_numbers, default=[10.0, 12.5, 15.0, 17.5, 20.0],
        help="dashpots to try (default: 10,12.5,15,17.5,20; published 10)",
    )  # fmt: skip
    parser.add_argument(
        "--shears", type=_numbers, default=[40.0, 27.5, 20.0, 0.0],
        help="shears to try (default: 40,27.5,20,0; published 40)",
    )  # fmt: skip
    parser.add_argument(
        "--rings", type=int, default=5,
        help="patch size: rings of discs around the centre one (default 5: 91 discs)",
    )  # fmt: skip
    parser.add_argument("--csv", type=Path, help="also write the table here")
    args = parser.parse_args(argv)
    if not 1 <= args.rings <= 12:
        parser.exit(2, "contact_stability: --rings must be 1 to 12 (12 is 469 discs)\n")
    base = PhysicsParams()
    rows = [
        stability(replace(base, damping=damping, shear=shear), args.rings)
        for shear in args.shears
        for damping in args.dampings
    ]
    count = len(hexagonal_patch(args.rings, 1.0))
    print(f"explicit step, linearised, hexagonal patch of {count} touching discs "
          f"(dt {base.dt} s, spring {base.spring:g}, unit masses)")  # fmt: skip
    header = ("shear", 6), ("dashpot", 8), ("|lambda| max", 13), ("dominant", 18)
    print(" ".join(f"{name:>{width}}" for name, width in header), f"{'unstable above':>15}")
    for row in rows:
        speed = row.threshold_speed
        above = "stable" if math.isinf(speed) else f"{speed:.3f} m/s"
        dominant = f"{row.dominant.real:+.3f}{row.dominant.imag:+.3f}j"
        print(f"{row.shear:6g} {row.damping:8g} {row.spectral_radius:13.3f} {dominant:>18} "
              f"{above:>15}")  # fmt: skip
    if args.csv:
        try:
            with args.csv.open("w", newline="") as out:
                writer = csv.writer(out)
                writer.writerow(["shear", "damping", "spectral_radius", "dominant_real",
                                 "dominant_imag", "threshold_speed_m_s", "discs"])  # fmt: skip
                for row in rows:
                    writer.writerow([row.shear, row.damping, f"{row.spectral_radius:.4f}",
                                     f"{row.dominant.real:.4f}", f"{row.dominant.imag:.4f}",
                                     f"{row.threshold_speed:.4f}", count])  # fmt: skip
        except OSError as error:
            print(f"contact_stability: cannot write {args.csv}: {error.strerror}", file=sys.stderr)
            return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
