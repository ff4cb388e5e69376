#!/usr/bin/env python3
"""Measures SI Algorithm 5's placement (sim/scenarios/placement.py) at 10^4, 10^5 and 10^6
particles: wall time (median of a few seeds) and how densely it packs; `--published` measures the
published code's version (algorithm5_published) instead."""

from __future__ import annotations

import argparse
import os
import statistics
import time

import numpy as np

from particlebot.sim.scenarios.placement import algorithm5, algorithm5_published

R_MIN = 0.0775


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--sizes", default="10000,100000,1000000")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument(
        "--published", action="store_true", help="the published code's Algorithm 5 instead"
    )
    args = parser.parse_args()
    place = algorithm5_published if args.published else algorithm5
    place(100, R_MIN, np.random.default_rng(0))  # compile (or load the cache) first
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    print("particles  placement s  span m  covered")
    for size in (int(s) for s in args.sizes.split(",")):
        times = []
        for seed in range(args.repeats):
            began = time.perf_counter()
            xy = place(size, R_MIN, np.random.default_rng(seed)).xy
            times.append(time.perf_counter() - began)
        centre = xy.mean(axis=0)
        reach = float(np.hypot(*(xy - centre).T).max()) + R_MIN
        covered = size * R_MIN**2 / reach**2
        span = float(np.ptp(xy, axis=0).max())
        print(f"{size:9d}  {statistics.median(times):11.3f}  {span:6.1f}  {covered:7.2f}")


if __name__ == "__main__":
    main()
