#!/usr/bin/env python3
"""The CUDA backend's figures in one run: speed by size (boiling, calm), the CPU beside it, peak
GPU memory, and Table S3's 10,000-particle row (99 runs) as one ensemble.

    python benchmarks/bench_gpu.py            # on a machine with a CUDA GPU (~8 minutes at most)
    python benchmarks/bench_gpu.py --smoke    # tiny sizes; without a GPU in numba-cuda's simulator

Everything printed also goes to benchmarks/results/gpu-<GPU>-<UTC time>.txt, and the figures as
JSON beside it. --cap-s bounds the whole run: each measurement gets its share, the largest sizes
step only as long as their share allows (and are skipped past 60 % of the cap), and Table S3's
row is built as far as the cap allows (scaled down, and labelled so, when not all 99 runs fit),
timed over as many steps as fit and extrapolated to its 720,000 (labelled so in the output).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from collections.abc import Callable
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

if "--smoke" in sys.argv:
    # The smoke run needs no GPU: numba-cuda's simulator, unless there is a GPU.
    from particlebot.sim.world.cuda.device import gpu_present, use_simulator

    if not gpu_present():
        use_simulator()

import numpy as np
from numba import cuda

from particlebot.sim.particles.model.published import PublishedController
from particlebot.sim.world import Lamp, PhysicsParams, World
from particlebot.sim.world.cuda.device import simulated

RESULTS = Path(__file__).resolve().parent / "results"
SIZES = (10_000, 200_000, 1_000_000, 10_000_000)
CPU_UP_TO = 200_000
"""The CPU is measured beside the GPU for sizes up to this (larger ones take minutes a step)."""
SHEARS = {"boiling": 40.0, "calm": 20.0}
"""The published shear makes packed blobs boil at dt = 0.01 s; 20 does not (README)."""
TABLE_S3_RUNS = 99
TABLE_S3_STEPS = 720_000
WARM_STEPS = 20


def hex_blob(count: int, spacing: float) -> tuple[np.ndarray, np.ndarray]:
    """The `count` points of a hexagonal lattice `spacing` apart nearest the origin."""
    m = int(math.sqrt(count / 0.9) * 0.6) + 3
    i, j = np.meshgrid(np.arange(-m, m + 1), np.arange(-m, m + 1))
    x = (i + 0.5 * j).ravel() * spacing
    y = (j * math.sqrt(3) / 2).ravel() * spacing
    nearest = np.argsort(x * x + y * y, kind="stable")[:count]
    return x[nearest], y[nearest]


def blob_world(count: int, shear: float, device: str) -> World:
    """A packed, actuating blob of `count` contracted particles, walls widened to hold it."""
    base = PhysicsParams(shear=shear)
    x, y = hex_blob(count, 2 * base.r_min)
    reach = float(np.abs(np.concatenate([x, y])).max())
    params = PhysicsParams(shear=shear, half_width=max(base.half_width, reach * 1.5 + 5.0))
    lamp = Lamp(-reach - 20.0, 0.0)
    return World(x, y, controller=PublishedController(), params=params, lamp=lamp, seed=1,
                 device=device)  # fmt: skip


def gpu_used_bytes() -> int:
    """Bytes in use on the GPU now (every process's; the simulator has no such figure: 0)."""
    if simulated():
        return 0
    free, total = cuda.current_context().get_memory_info()
    return int(total - free)


def timed(world: World, budget_s: float, sync: Callable[[], None]) -> tuple[int, float]:
    """Steps `world` in growing chunks until budget_s is spent; (steps, wall seconds)."""
    steps = 0
    chunk = 1
    began = time.perf_counter()
    while True:
        world.step(chunk)
        sync()
        steps += chunk
        took = time.perf_counter() - began
        if took >= budget_s:
            return steps, took
        chunk = max(1, min(chunk * 2, int(steps * (budget_s - took) / max(took, 1e-9)) + 1))


class Report:
    """Prints each line and keeps it for the results file."""

    def __init__(self) -> None:
        self.lines: list[str] = []
        self.figures: dict[str, Any] = {"rows": []}

    def say(self, line: str) -> None:
        print(line, flush=True)
        self.lines.append(line)


def speeds(report: Report, sizes: tuple[int, ...], share_s: float, until: float) -> None:
    """Particle-steps/s by size and regime on the GPU (each timed for share_s), and on the CPU
    for the smaller sizes (half that); sizes not begun by `until` (perf_counter) are skipped."""
    sync = cuda.synchronize
    report.say("particles | regime | GPU particle-steps/s | x real time | CPU particle-steps/s "
               "| GPU memory in use (MB)")  # fmt: skip
    baseline = gpu_used_bytes()
    peak = 0
    for count in sizes:
        for regime, shear in SHEARS.items():
            if time.perf_counter() > until:
                report.say(f"{count:,} | {regime} | skipped: the time cap")
                continue
            try:
                built = time.perf_counter()
                world = blob_world(count, shear, "cuda")
                build_s = time.perf_counter() - built
                used = gpu_used_bytes() - baseline
                world.step(WARM_STEPS)
                sync()
                steps, wall = timed(world, share_s, sync)
                used = max(used, gpu_used_bytes() - baseline)
                peak = max(peak, used)
            except Exception as exc:  # out of memory, a launch failure: say so and go on
                report.say(f"{count:,} | {regime} | failed: {type(exc).__name__}: {exc}")
                continue
            gpu_rate = count * steps / wall
            cpu_rate = math.nan
            if count <= CPU_UP_TO:
                cpu = blob_world(count, shear, "cpu")
                cpu.step(WARM_STEPS)
                cpu_steps, cpu_wall = timed(cpu, share_s / 2, lambda: None)
                cpu_rate = count * cpu_steps / cpu_wall
                del cpu
            realtime = steps * world.params.dt / wall
            report.say(f"{count:,} | {regime} | {gpu_rate:.3g} | {realtime:.3g} | "
                       f"{cpu_rate:.3g} | {used / 1e6:.0f}")  # fmt: skip
            report.figures["rows"].append({
                "particles": count, "regime": regime, "gpu_particle_steps_per_s": gpu_rate,
                "gpu_steps": steps, "gpu_wall_s": wall, "realtime_factor": realtime,
                "cpu_particle_steps_per_s": cpu_rate, "gpu_bytes_in_use": used,
                "build_s": build_s,
            })  # fmt: skip
            del world
    report.figures["peak_gpu_bytes"] = peak
    report.say(f"peak GPU memory in use by these worlds: {peak / 1e6:.0f} MB")


def table_s3_row(report: Report, runs: int, particles: int, build_s: float, share_s: float) -> None:
    """Table S3's 10,000-particle row (99 runs at 0-80 % dead, 7,200 s each) as one ensemble,
    built as `particlebot study dead --device cuda` builds it. Runs are built (on the CPU) until
    build_s is spent: with fewer than all, the row is SCALED DOWN and its wall time extrapolated
    by particles; the ensemble is timed for share_s and the 720,000 steps extrapolated from the
    rate. The line says which figures are measured and which extrapolated."""
    import tempfile

    from particlebot.sim.world.cuda.ensemble import Ensemble
    from particlebot.studies import seam
    from particlebot.studies.definitions import STUDIES, RawOptions, resolve

    study = STUDIES["dead"]
    options = resolve(study, RawOptions(sizes=str(particles)))
    specs = study.specs(options)[:runs]
    with tempfile.TemporaryDirectory(prefix="bench-gpu-") as scratch:
        began = time.perf_counter()
        opened = []
        for spec in specs:
            opened.append(seam.open_run(spec.setup, Path(scratch) / spec.run_id, False)[1])
            if time.perf_counter() - began > build_s:
                break
        ensemble = Ensemble([run.world for run in opened])
        built_s = time.perf_counter() - began
        ensemble.step(WARM_STEPS)
        cuda.synchronize()
        steps = 0
        chunk = 10
        timing = time.perf_counter()
        while time.perf_counter() - timing < share_s:
            ensemble.step(chunk)
            cuda.synchronize()
            steps += chunk
            chunk = min(chunk * 2, 500)
        wall = time.perf_counter() - timing
    total = opened[0].total_steps
    scale = len(specs) / len(opened)
    per_step = wall / steps * scale
    estimate = built_s * scale + per_step * total
    rate = ensemble.count * steps / wall
    scaled = "" if scale == 1.0 else f" SCALED DOWN: {len(opened)} of {len(specs)} runs built;"
    report.say(
        f"Table S3, {particles:,}-particle row as one ensemble:{scaled} {len(opened)} runs, "
        f"{ensemble.count:,} particles, built in {built_s:.1f} s; {steps} steps timed in "
        f"{wall:.1f} s ({rate:.3g} particle-steps/s); EXTRAPOLATED to all {len(specs)} runs "
        f"x {total:,} steps: {estimate / 60:.1f} min wall"
    )
    report.figures["table_s3"] = {
        "runs": len(opened), "runs_in_row": len(specs), "particles_each": particles,
        "build_s": built_s, "timed_steps": steps, "timed_wall_s": wall,
        "steps_per_run": total, "extrapolated_wall_s": estimate,
        "particle_steps_per_s": rate,
    }  # fmt: skip


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--smoke",
        action="store_true",
        help="tiny sizes (runs in numba-cuda's simulator without a GPU)",
    )
    parser.add_argument(
        "--cap-s",
        type=float,
        default=480.0,
        help="wall-time bound of the whole run (default 480 s)",
    )
    parser.add_argument("--out", type=Path, default=RESULTS, help="where the raw output goes")
    args = parser.parse_args()  # fmt: skip
    if not cuda.is_available():
        print("bench_gpu: no CUDA GPU here (try --smoke: the simulator)", file=sys.stderr)
        return 1
    sizes = (20, 40) if args.smoke else SIZES
    runs, particles = (3, 10) if args.smoke else (TABLE_S3_RUNS, 10_000)
    report = Report()
    if simulated():
        name = "numba-cuda simulator"
    else:
        raw = cuda.get_current_device().name
        name = raw.decode() if isinstance(raw, bytes) else str(raw)
    stamp = datetime.now(UTC).strftime("%Y%m%dT%H%M%SZ")
    report.figures.update({"gpu": name, "utc": stamp, "smoke": args.smoke})
    report.say(f"bench_gpu on {name}, {stamp}{' (smoke: tiny sizes)' if args.smoke else ''}")
    # The cap: speeds until 60 % of it (15 s a GPU measurement, 7.5 s for the CPU beside the
    # smaller sizes, the rest building), then Table S3's row: building until 80 %, timing 10 %.
    # (The smoke run builds one run of its row: the scaled-down path.)
    began = time.perf_counter()
    cap = args.cap_s
    speeds(report, sizes, 2.0 if args.smoke else min(15.0, cap / 30), began + 0.6 * cap)
    left = cap - (time.perf_counter() - began)
    table_s3_row(report, runs, particles, max(0.0, left - 0.3 * cap) if not args.smoke else 0.0,
                 2.0 if args.smoke else max(10.0, 0.1 * cap))  # fmt: skip
    report.say(f"bench_gpu took {time.perf_counter() - began:.0f} s (cap {cap:g} s)")
    args.out.mkdir(parents=True, exist_ok=True)
    slug = "".join(c if c.isalnum() else "-" for c in name).strip("-")
    base = args.out / f"gpu-{slug}-{stamp}"
    base.with_suffix(".txt").write_text("\n".join(report.lines) + "\n")
    base.with_suffix(".json").write_text(json.dumps(report.figures, indent=1) + "\n")
    print(f"raw output: {base.with_suffix('.txt')}, {base.with_suffix('.json')}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
