#!/usr/bin/env python3
"""The first minutes of an actuating swarm, over time: how much of it rattles, its top speeds, its
extent and its contacts per particle: whether it boils, calms down packed, or blows apart."""

from __future__ import annotations

import argparse
import csv
import math
import sys
import time
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

from particlebot.sim.world import PhysicsParams
from rattle_share import FAST_M_S, published_swarm  # (beside this script)

TOUCH_M = 0.002
"""Neighbours closer than this gap count as touching (the magnets' blend gap, rounded up)."""
SAMPLES_S = (0.5, 1, 2, 3, 5, 10, 20, 30, 60, 120, 180, 300, 600)
"""Simulated times sampled, up to --until."""
COLUMNS = (
    "particles", "damping", "shear", "torque_limit", "time_s", "rattling_share", "p99_speed_m_s",
    "max_speed_m_s", "rms_radius_m", "touching_per_particle",
)  # fmt: skip


def _case(text: str) -> tuple[float, float, float]:
    """DAMPING,SHEAR,TORQUE_LIMIT"""
    parts = text.split(",")
    try:
        values = tuple(float(v) for v in parts)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not DAMPING,SHEAR,TORQUE_LIMIT: {text!r}") from None
    if len(values) != 3 or any(not math.isfinite(v) or v < 0 for v in values):
        raise argparse.ArgumentTypeError(f"need three numbers >= 0: {text!r}")
    return values[0], values[1], values[2]


def timeline(
    count: int, damping: float, shear: float, torque_limit: float, until_s: float
) -> list[dict[str, float]]:
    """rattle_share's published_swarm (SI Algorithm 5 as the studies place it), sampled at
    SAMPLES_S."""
    params = PhysicsParams(damping=damping, shear=shear, torque_limit=torque_limit)
    world = published_swarm(count, params)
    rows = []
    now = 0.0
    for sample in (t for t in SAMPLES_S if t <= until_s):
        world.run(sample - now)
        now = sample
        state = world.state()
        speed = np.hypot(state.vx, state.vy)
        centres = np.column_stack([state.x, state.y])
        radii = world.radii()
        pairs = cKDTree(centres).query_pairs(2 * params.r_max + TOUCH_M, output_type="ndarray")
        gaps = np.hypot(*(centres[pairs[:, 0]] - centres[pairs[:, 1]]).T)
        gaps -= radii[pairs[:, 0]] + radii[pairs[:, 1]]
        rows.append({
            "particles": count, "damping": damping, "shear": shear,
            "torque_limit": torque_limit, "time_s": sample,
            "rattling_share": float(np.mean(speed > FAST_M_S)),
            "p99_speed_m_s": float(np.percentile(speed, 99)), "max_speed_m_s": float(speed.max()),
            "rms_radius_m": float(np.sqrt(((centres - centres.mean(axis=0)) ** 2).sum(1).mean())),
            "touching_per_particle": 2 * int((gaps < TOUCH_M).sum()) / count,
        })  # fmt: skip
    return rows


def plot(rows: list[dict[str, float]], path: Path) -> None:
    """Extent (relative to the first sample) and touching neighbours against time, a line a case:
    solid the largest size, dashed the others."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cases = sorted({(r["damping"], r["shear"], r["torque_limit"]) for r in rows})
    sizes = sorted({int(r["particles"]) for r in rows})
    colours = plt.get_cmap("viridis")(np.linspace(0, 0.9, len(cases)))
    figure, (extent, touching) = plt.subplots(1, 2, figsize=(11, 4.2))
    for colour, case in zip(colours, cases, strict=True):
        for size in sizes:
            run = [r for r in rows if (r["damping"], r["shear"], r["torque_limit"]) == case
                   and int(r["particles"]) == size]  # fmt: skip
            if not run:
                continue
            times = [r["time_s"] for r in run]
            style = "-" if size == sizes[-1] else "--"
            label = f"{size:,}: dashpot {case[0]:g}, shear {case[1]:g}, torque {case[2]:g}"
            first = run[0]["rms_radius_m"]
            extent.plot(times, [r["rms_radius_m"] / first for r in run], style, color=colour,
                        label=label)  # fmt: skip
            touching.plot(times, [r["touching_per_particle"] for r in run], style, color=colour)
    for axes in (extent, touching):
        axes.set_xscale("log")
        axes.set_xlabel("simulated time (s)")
        axes.grid(alpha=0.3)
    extent.set_ylabel("rms distance from the centroid / at 0.5 s")
    touching.set_ylabel(f"neighbours within {TOUCH_M * 1000:g} mm, per particle")
    extent.legend(fontsize=7)
    figure.suptitle("The first minutes of a blob (Algorithm 5, seed 1): packed, or blown apart")
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)


def _read(path: Path) -> list[dict[str, float]]:
    with path.open(newline="") as stream:
        return [{k: float(v) for k, v in row.items()} for row in csv.DictReader(stream)]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--sizes", type=int, nargs="+", default=[10_000])
    parser.add_argument(
        "--cases", type=_case, nargs="+", metavar="DAMPING,SHEAR,TORQUE_LIMIT",
        default=[(15.0, 40.0, 0.5), (17.5, 40.0, 0.5), (10.0, 27.5, 0.7)],
        help="contact and servo numbers to run (default: 15,40,0.5 17.5,40,0.5 10,27.5,0.7)",
    )  # fmt: skip
    parser.add_argument("--until", type=float, default=300.0,
                        help="last time sampled (s, up to 600)")  # fmt: skip
    parser.add_argument("--out", type=Path, default=Path("data/studies/swarm-start.csv"))
    parser.add_argument("--plot", type=Path, help="also draw the timeline here (PNG)")
    parser.add_argument("--replot", type=Path, metavar="CSV",
                        help="only draw --plot from a CSV this tool wrote")  # fmt: skip
    args = parser.parse_args()
    if args.replot:
        if not args.plot:
            print("swarm_start: --replot needs --plot PNG", file=sys.stderr)
            return 2
        try:
            plot(_read(args.replot), args.plot)
        except (OSError, ValueError, KeyError) as error:
            print(f"swarm_start: cannot redraw from {args.replot}: {error}", file=sys.stderr)
            return 1
        print(f"drew {args.plot}")
        return 0
    if min(args.sizes) < 3 or not SAMPLES_S[0] <= args.until <= SAMPLES_S[-1]:
        print(f"swarm_start: needs sizes >= 3 and --until from {SAMPLES_S[0]} to {SAMPLES_S[-1]}",
              file=sys.stderr)  # fmt: skip
        return 2
    rows = []
    for count in args.sizes:
        for damping, shear, torque in args.cases:
            began = time.perf_counter()
            rows += (run := timeline(count, damping, shear, torque, args.until))
            last = run[-1]
            print(f"{count} particles, damping {damping:g}, shear {shear:g}, torque {torque:g}: "
                  f"at {last['time_s']:g} s {100 * last['rattling_share']:.1f} % rattling, rms "
                  f"radius {run[0]['rms_radius_m']:.2f} -> {last['rms_radius_m']:.2f} m, "
                  f"{last['touching_per_particle']:.2f} touching a particle "
                  f"({time.perf_counter() - began:.0f} s)", flush=True)  # fmt: skip
    try:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        with args.out.open("w", newline="") as stream:
            writer = csv.DictWriter(stream, fieldnames=COLUMNS)
            writer.writeheader()
            writer.writerows(rows)
    except OSError as error:
        print(f"swarm_start: cannot write {args.out}: {error.strerror}", file=sys.stderr)
        return 1
    print(f"wrote {args.out}")
    if args.plot:
        plot(rows, args.plot)
        print(f"drew {args.plot}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
