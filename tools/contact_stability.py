#!/usr/bin/env python3
"""Whether the world's explicit step is stable in a packed swarm: the spectral radius of one step,
linearised, for a touching hexagonal patch, over dashpots and shears (why swarms "boil")."""

from __future__ import annotations

import argparse
import csv
import math
import sys
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import numpy.typing as npt

from particlebot.sim.world import PhysicsParams

FloatArray = npt.NDArray[np.float64]


def hexagonal_patch(rings: int, spacing: float) -> FloatArray:
    """Centres of a hexagon of touching discs `rings` deep around one: (N, 2)."""
    points = [
        ((i + 0.5 * j) * spacing, j * math.sqrt(3) / 2 * spacing)
        for i in range(-rings, rings + 1)
        for j in range(-rings, rings + 1)
        if abs(i + j) <= rings
    ]
    return np.array(points)


def step_matrix(centres: FloatArray, radius: float, params: PhysicsParams) -> FloatArray:
    """The world's step (positions by the old velocity, then forces from the new positions and the
    old velocities), linearised about rest for every touching pair: contact spring k n n^T and the
    dashpot on the whole relative velocity plus the shear on its tangential part, unit masses.
    Ground friction, magnets and the servo are left out (they are not linear)."""
    n = len(centres)
    stiffness = np.zeros((2 * n, 2 * n))
    damping = np.zeros((2 * n, 2 * n))
    eye = np.eye(2)
    for a in range(n):
        for b in range(a + 1, n):
            rel = centres[b] - centres[a]
            distance = float(np.hypot(*rel))
            if distance > 2 * radius * (1 + 1e-9):
                continue
            normal = np.outer(rel, rel) / distance**2
            blocks = (
                (stiffness, params.spring * normal),
                (damping, params.damping * eye + params.shear * (eye - normal)),
            )
            for matrix, block in blocks:  # the force on a is block (x_b - x_a); b gets its opposite
                sa, sb = slice(2 * a, 2 * a + 2), slice(2 * b, 2 * b + 2)
                matrix[sa, sa] -= block
                matrix[sa, sb] += block
                matrix[sb, sb] -= block
                matrix[sb, sa] += block
    dt = params.dt
    ident = np.eye(2 * n)
    # x' = x + dt v;  v' = v + dt (K x' + C v)
    top = np.hstack([ident, dt * ident])
    bottom = np.hstack([dt * stiffness, ident + dt * dt * stiffness + dt * damping])
    return np.vstack([top, bottom])


@dataclass(frozen=True)
class Stability:
    damping: float
    shear: float
    spectral_radius: float
    dominant: complex
    """The eigenvalue of largest modulus (negative real: a mode that flips sign every step)."""
    threshold_speed: float
    """Speed (m/s) above which that mode outgrows what sliding friction takes off a step, mu g dt
    / (radius - 1); infinite for a stable step."""


def stability(params: PhysicsParams, rings: int) -> Stability:
    centres = hexagonal_patch(rings, 2 * params.r_min)
    values = np.linalg.eigvals(step_matrix(centres, params.r_min, params))
    dominant = complex(values[np.argmax(np.abs(values))])
    rho = float(abs(dominant))
    slide = params.mu * params.gravity * params.dt
    threshold = slide / (rho - 1) if rho > 1 + 1e-6 else math.inf  # (1: rigid motions)
    return Stability(params.damping, params.shear, rho, dominant, threshold)


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
