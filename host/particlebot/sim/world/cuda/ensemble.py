"""Many independent Worlds stepped side by side on one GPU: one launch per pass serves them all."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from particlebot.sim.world.cuda.device import DeviceError, resolve

if TYPE_CHECKING:
    from particlebot.sim.world.world import World

TARGET_BUDGET = 1 << 23
"""Commanded radii an ensemble uploads per block of steps (floats, 64 MB): 8 steps of the 99
10,000-particle runs of Table S3's row, 400 of a single 10,000-particle swarm."""


class Ensemble:
    """Worlds built on the CPU (device "cpu"), moved to the GPU together: their particles are
    concatenated, each keeps its own parameters, arena, lamp, controller, dead particles,
    observers and random streams, and step() advances every one by the same number of steps.
    A World of an ensemble is read as usual (its arrays come back from the GPU when read); it is
    stepped only through its ensemble. Each World's trajectory is the one it would take alone on
    the GPU: the swarms meet nothing of each other (own cells, own objects)."""

    def __init__(self, worlds: Sequence[World]) -> None:
        from particlebot.sim.world.cuda.swarms import DeviceSwarms

        if not worlds:
            raise ValueError("an ensemble needs at least one world")
        if resolve("cuda") != "cuda":  # (raises DeviceError without a GPU or the simulator)
            raise DeviceError("no CUDA device")
        for w in worlds:
            if w._gpu is not None:
                raise ValueError("an ensemble takes worlds built on the CPU (device='cpu')")
            if w._stale:
                raise DeviceError("the published stale grid (neighbour_search) runs on the CPU")
        self.worlds = tuple(worlds)
        self.count = sum(w.count for w in worlds)
        swarms = DeviceSwarms(self.worlds)
        rows = max(1, min(TARGET_BUDGET // self.count, 8192))
        for s, w in enumerate(self.worlds):
            w.device = "cuda"
            w._gpu = swarms
            w._gpu_index = s
            w._targets = np.full((rows, w.count), np.nan)
        self._swarms = swarms
        self._targets = np.full((rows, self.count), np.nan)

    @property
    def steps(self) -> int:
        """Steps every world has taken since its run began (the fewest, if they started apart)."""
        return min(w.steps for w in self.worlds)

    def step(self, n: int = 1) -> None:
        """Advances every world n steps, in blocks as long as every controller and observer
        allows (each world's controller commands its own rows; the block is the shortest)."""
        ends = [w.steps + n for w in self.worlds]
        first = self._swarms.first
        while self.worlds[0].steps < ends[0]:
            rows = min(w._begin_block(end) for w, end in zip(self.worlds, ends, strict=True))
            for s, w in enumerate(self.worlds):
                if w._cycle is None:
                    self._targets[:rows, first[s] : first[s + 1]] = w._targets[:rows]
            self._swarms.advance(rows, self._targets, [w._cycle for w in self.worlds])
            for w in self.worlds:
                w._end_block(rows, rows)

    def run(self, seconds: float) -> None:
        """Steps every world `seconds` of simulated time (rounded to whole steps of the first
        world's dt)."""
        self.step(round(seconds / self.worlds[0].params.dt))
