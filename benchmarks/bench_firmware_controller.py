#!/usr/bin/env python3
"""Measures what the vectorised `firmware` controller costs per world step and per round."""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import time

import numpy as np

from particlebot.protocol import Method
from particlebot.sim.particles.model.firmware import FirmwareController, FirmwareSettings
from particlebot.sim.particles.model.static_view import StaticView
from particlebot.sim.world.light import Lamp, LightField

WORLD_STEP_S = 0.01
R_MIN = 0.0775
# The world's goal: 4e7 particle-steps/s, i.e. 5 ms per step at 200,000 particles.
WORLD_STEP_BUDGET_NS_PER_PARTICLE = 1e9 / 4e7


def blob(count: int, seed: int) -> StaticView:
    """A packed disc of particles 1 m from a lamp 28 cm up, lit per eq. 11."""
    rng = np.random.default_rng(seed)
    radius = math.sqrt(count / 0.9) * R_MIN  # 90 % of the disc's area covered
    r = radius * np.sqrt(rng.random(count))
    angle = rng.uniform(0.0, 2 * math.pi, count)
    x, y = 1.0 + radius + r * np.cos(angle), r * np.sin(angle)
    readings = LightField(Lamp()).sensor_matrix(x, y)[:, 0].astype(np.float64)
    return StaticView(x, y, readings)


def per_step_ms(controller: FirmwareController, view: StaticView, steps: int) -> float:
    """Median wall time of command() over `steps` steps inside an epoch (no round starts)."""
    out = np.empty(view.count)
    times = []
    for _ in range(steps):
        view.t += WORLD_STEP_S
        began = time.perf_counter()
        controller.command(view, out)
        times.append(time.perf_counter() - began)
    return statistics.median(times) * 1e3


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--sizes", type=int, nargs="+", default=[10_000, 200_000, 1_000_000])
    parser.add_argument("--steps", type=int, default=500)
    args = parser.parse_args()
    print(
        f"{'particles':>10} {'method':>9} {'round ms':>9} {'step ms':>8} {'ns/particle':>11}"
        f" {'share of a 4e7/s step':>22}"
    )
    warm_up = FirmwareController()  # numba compiles (or loads its cache) once, not in a figure
    warm_up.bind(1, np.random.default_rng(0))
    warm_up.command(blob(1, seed=0), np.empty(1))
    for count in args.sizes:
        view = blob(count, seed=1)
        for method in Method:
            settings = FirmwareSettings(method=method, wave_size=5, update_interval_s=600)
            controller = FirmwareController(settings)
            controller.bind(count, np.random.default_rng(0))
            view.t = 0.0
            began = time.perf_counter()
            controller.command(view, np.empty(count))  # the first round's estimate, and a step
            round_ms = (time.perf_counter() - began) * 1e3
            view.t = settings.round_ms / 1000  # cycling from here on
            step_ms = per_step_ms(controller, view, args.steps)
            ns = step_ms * 1e6 / count
            print(
                f"{count:>10} {method.name:>9} {round_ms:>9.1f} {step_ms:>8.3f} {ns:>11.2f}"
                f" {ns / WORLD_STEP_BUDGET_NS_PER_PARTICLE:>21.1%}"
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
