"""Swarms kept on the GPU: their concatenated state, the step loop that launches the kernels, and
the copies to and from the Worlds that own them (only when a World's arrays are read or changed
on the host: between dumps and controller updates the state stays on the device)."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt
from numba import cuda

from particlebot.sim.world import kernels as k
from particlebot.sim.world.cuda import kernels as ck
from particlebot.sim.world.cuda.device import simulated

if TYPE_CHECKING:
    from particlebot.sim.particles.model.controller import CycleCommands
    from particlebot.sim.world.world import World

THREADS = 128
"""Threads a block (32 in numba-cuda's simulator, where each is a Python thread)."""


def _blocks(count: int) -> tuple[int, int]:
    threads = 32 if simulated() else THREADS
    return max(1, math.ceil(count / threads)), threads


def _launcher(kernel: Any, count: int) -> Callable[..., None]:
    """The kernel configured once for `count` threads (configuring a launch costs host time
    that a large step hides and a small one does not). The simulator configures the kernel
    object itself rather than a copy, so there it is configured at every launch."""
    config = _blocks(count)
    if simulated():
        return lambda *args: kernel[config](*args)
    return kernel[config]


def grid_sides(prm: npt.NDArray[np.float64], count: int) -> tuple[int, int]:
    """A swarm's grid: the cells across the arena (`full`), and the side of the grid it keeps
    (`side`): the full grid when that is small, else a power of two of about sqrt(count)
    cells a side (4 at least) onto which the arena wraps (cells far apart share a slot; the
    distance test sorts them out). A packed blob spans about 0.65 sqrt(count) cells, so it
    does not meet itself; a 10,000-particle one in the published 128 m arena has 128 x 128
    cells, not 523 x 523 (1.6 cells a particle: the per-cell passes stay small)."""
    width = prm[k.P_LIST_RADIUS] - prm[k.P_SKIN]
    full = int(2.0 * prm[k.P_HALF_WIDTH] / width) + 1
    wanted = 1 << max(2, math.ceil(math.log2(math.sqrt(count))))
    return full, min(full, wanted)


class PrefixSum:
    """An exclusive prefix sum of `count` integers on the device, into count + 1 (the last: the
    total), level by level: each level sums tiles of SCAN_TILE values and hands their totals to
    the next, until one tile is left; then each level's offsets are added back down."""

    def __init__(self, count: int) -> None:
        self.count = count
        self.levels = [count]
        while self.levels[-1] > 1:
            self.levels.append(math.ceil(self.levels[-1] / ck.SCAN_TILE))
        if len(self.levels) == 1:
            self.levels.append(1)
        self.sums = [cuda.device_array(size, dtype=np.int64) for size in self.levels[1:]]
        self.scanned = [cuda.device_array(size, dtype=np.int64) for size in self.levels[1:]]
        self._tiles = [_launcher(ck.scan_tiles, size) for size in self.levels[1:]]
        self._adds = [_launcher(ck.add_offsets, size) for size in self.levels]
        self._end = _launcher(ck.set_end, 1)

    def __call__(self, values: Any, out: Any) -> None:
        levels = self.levels
        source, target = values, out
        for level in range(len(levels) - 1):
            self._tiles[level](levels[level], source, target, self.sums[level])
            source, target = self.sums[level], self.scanned[level]
        for level in range(len(levels) - 3, 0, -1):
            self._adds[level](levels[level], self.scanned[level - 1], self.scanned[level])
        if len(levels) > 2:
            self._adds[0](levels[0], out, self.scanned[0])
        self._end(out, self.count, self.sums[-1])


class DeviceSwarms:
    """One or more Worlds' state on the GPU, stepped together (an ensemble of independent swarms:
    they share launches, not physics). Particles keep each World's internal order."""

    def __init__(self, worlds: Sequence[World]) -> None:
        self.worlds = tuple(worlds)
        counts = [w.count for w in self.worlds]
        self.count = int(sum(counts))
        self.first = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
        s_count = len(self.worlds)
        self.swarms = s_count
        ftype = self.worlds[0]._vel.dtype
        if any(w._vel.dtype != ftype for w in self.worlds):
            raise ValueError("an ensemble's worlds must share one precision")
        prm = np.stack([w._prm for w in self.worlds])
        sides = [grid_sides(prm[s], counts[s]) for s in range(s_count)]
        full = np.array([f for f, _ in sides], dtype=np.int64)
        side = np.array([g for _, g in sides], dtype=np.int64)
        cell_base = np.concatenate([[0], np.cumsum(side * side)]).astype(np.int64)
        self.cells = int(cell_base[-1])
        rect_n = [w._rects.shape[0] for w in self.worlds]
        circle_n = [w._circles.shape[0] for w in self.worlds]
        object_n = [w._objects.shape[0] for w in self.worlds]
        rects = np.concatenate([w._rects for w in self.worlds]).reshape(-1, 4)
        circles = np.concatenate([w._circles for w in self.worlds]).reshape(-1, 3)
        self._object_first = np.concatenate([[0], np.cumsum(object_n)]).astype(np.int64)
        rect_first = np.concatenate([[0], np.cumsum(rect_n)]).astype(np.int64)
        circle_first = np.concatenate([[0], np.cumsum(circle_n)]).astype(np.int64)
        swarm = np.repeat(np.arange(s_count, dtype=np.int32), counts)
        to = cuda.to_device
        self.d_swarm = to(swarm)
        self.d_prm = to(prm)
        self.d_full = to(full)
        self.d_side = to(side)
        self.d_cell_base = to(cell_base)
        self.d_first = to(self.first[:-1].copy())
        self.d_last = to(self.first[1:].copy())
        self.d_rects = to(rects if rects.size else np.zeros((1, 4)))
        self.d_rect_lo = to(rect_first[:-1].copy())
        self.d_rect_hi = to(rect_first[1:].copy())
        self.d_circles = to(circles if circles.size else np.zeros((1, 3)))
        self.d_circle_lo = to(circle_first[:-1].copy())
        self.d_circle_hi = to(circle_first[1:].copy())
        self.d_object_lo = to(self._object_first[:-1].copy())
        self.d_object_hi = to(self._object_first[1:].copy())
        self._has_objects = sum(object_n) > 0
        objects_total = max(1, sum(object_n))
        self.d_objects = cuda.device_array((objects_total, k.OBJECT_COLS))
        self.d_force = cuda.device_array((objects_total, 2))
        self.d_pushes = cuda.device_array((self.count if self._has_objects else 1,
                                           max(1, max(object_n)), 2))  # fmt: skip
        self.d_pos = cuda.device_array((2, self.count))
        self.d_vel = cuda.device_array((2, self.count), dtype=ftype)
        self.d_body = cuda.device_array((k.BODY_ROWS, self.count), dtype=ftype)
        self.d_flags = cuda.device_array((k.FLAG_ROWS, self.count), dtype=np.uint8)
        self.d_ext = cuda.device_array(self.count, dtype=np.int64)
        self.d_cell_of = cuda.device_array(self.count, dtype=np.int64)
        self.d_members = cuda.device_array(self.count, dtype=np.int64)
        self.d_counts = cuda.to_device(np.zeros(self.cells, dtype=np.int32))
        self.d_start = cuda.device_array(self.cells + 1, dtype=np.int64)
        self._scan = PrefixSum(self.cells)
        # The launches, configured once.
        self._kinematics = _launcher(ck.kinematics, self.count)
        self._objects_move = _launcher(ck.objects_move, self.swarms)
        self._clear = _launcher(ck.clear, self.cells)
        self._count_cells = _launcher(ck.count_cells, self.count)
        self._scatter = _launcher(ck.scatter, self.count)
        self._order_cells = _launcher(ck.order_cells, self.cells)
        self._pairs = _launcher(ck.pairs, self.count)
        self._settle = _launcher(ck.settle, self.count)
        self._objects_settle = _launcher(ck.objects_settle, self.swarms)
        self.d_targets = cuda.device_array((1, self.count))
        self._offsets = np.zeros(self.count)  # the cycles' phase offsets, caller order
        self.d_offset = cuda.to_device(self._offsets)
        self.d_cycles = cuda.to_device(np.zeros((s_count, 4)))
        self._stale = [False] * s_count  # whether a World's host arrays are behind the device
        self.dirty = [False] * s_count  # whether a World's host arrays are ahead of the device
        for s in range(s_count):
            self.push(s)

    # ---- copies between a World and its slice -----------------------------------------------

    def push(self, s: int) -> None:
        """Copies World s's host state to the device (after the host changed it)."""
        w = self.worlds[s]
        lo, hi = int(self.first[s]), int(self.first[s + 1])
        for device_rows, host_rows in self._rows(w):
            for r in range(host_rows.shape[0]):
                device_rows[r, lo:hi] = np.ascontiguousarray(host_rows[r])
        self.d_ext[lo:hi] = w._ext
        o_lo, o_hi = int(self._object_first[s]), int(self._object_first[s + 1])
        if o_hi > o_lo:
            self.d_objects[o_lo:o_hi] = np.ascontiguousarray(w._objects)
        self._stale[s] = False
        self.dirty[s] = False

    def pull(self, s: int) -> None:
        """Copies World s's state from the device into its host arrays, if they are behind."""
        if not self._stale[s]:
            return
        w = self.worlds[s]
        lo, hi = int(self.first[s]), int(self.first[s + 1])
        for device_rows, host_rows in self._rows(w):
            for r in range(host_rows.shape[0]):
                host_rows[r] = device_rows[r, lo:hi].copy_to_host()
        o_lo, o_hi = int(self._object_first[s]), int(self._object_first[s + 1])
        if o_hi > o_lo:
            w._objects[:] = self.d_objects[o_lo:o_hi].copy_to_host()
        self._stale[s] = False

    def _rows(self, w: World) -> list[tuple[Any, npt.NDArray[Any]]]:
        """The per-particle arrays, device and host (copied row by row: a row's slice is
        contiguous, a column range of a 2-D device array is not)."""
        return [
            (self.d_pos, w._pos), (self.d_vel, w._vel), (self.d_body, w._body),
            (self.d_flags, w._flags),
        ]  # fmt: skip

    # ---- stepping ------------------------------------------------------------------------------

    def advance(
        self,
        rows: int,
        targets: npt.NDArray[np.float64],
        cycles: Sequence[CycleCommands | None] = (),
    ) -> None:
        """Runs `rows` steps of every swarm; step q commands targets[q, first[s] + ext] (NaN:
        hold), the swarms' caller-order rows side by side, except for a swarm whose entry of
        `cycles` says the GPU computes its commands itself (then its columns of targets are not
        read, and none are uploaded when every swarm has one). Worlds whose host state changed
        since (dead chosen, shadows, a particle put down) are copied up first."""
        for s in range(self.swarms):
            if self.dirty[s]:
                self.push(s)
        table = np.zeros((self.swarms, 4))
        offsets = self._offsets
        for s, plan in enumerate(cycles):
            if plan is not None:
                table[s] = (1.0, float(plan.first), plan.cycle_s, plan.rise_s)
                offsets[self.first[s] : self.first[s + 1]] = plan.offset
        self.d_cycles.copy_to_device(table)  # (into the same memory: queued steps may read it)
        if table[:, 0].any():
            self.d_offset.copy_to_device(offsets)
        if not table[:, 0].all():
            if self.d_targets.shape[0] < rows:
                self.d_targets = cuda.device_array((rows, self.count))
            self.d_targets[:rows] = np.ascontiguousarray(targets[:rows])
        n = self.count
        for q in range(rows):
            self._kinematics(
                n, q, self.d_targets, self.d_first, self.d_ext, self.d_swarm, self.d_pos,
                self.d_vel, self.d_body, self.d_flags, self.d_prm, self.d_cycles, self.d_offset,
            )  # fmt: skip
            if self._has_objects:
                self._objects_move(self.swarms, self.d_objects, self.d_object_lo,
                                    self.d_object_hi, self.d_prm)  # fmt: skip
            self._clear(self.cells, self.d_counts)
            self._count_cells(n, self.d_pos, self.d_swarm, self.d_prm, self.d_side, self.d_full,
                               self.d_cell_base, self.d_cell_of, self.d_counts)  # fmt: skip
            self._scan(self.d_counts, self.d_start)
            self._clear(self.cells, self.d_counts)  # (the scatter counts into them again)
            self._scatter(n, self.d_cell_of, self.d_start, self.d_counts, self.d_members)
            self._order_cells(self.cells, self.d_start, self.d_members)
            self._pairs(n, self.d_pos, self.d_vel, self.d_body, self.d_flags, self.d_swarm,
                         self.d_prm, self.d_side, self.d_full, self.d_cell_base, self.d_cell_of,
                         self.d_start, self.d_members)  # fmt: skip
            self._settle(n, self.d_pos, self.d_vel, self.d_body, self.d_swarm, self.d_prm,
                          self.d_rects, self.d_rect_lo, self.d_rect_hi, self.d_circles,
                          self.d_circle_lo, self.d_circle_hi, self.d_objects, self.d_object_lo,
                          self.d_object_hi, self.d_pushes)  # fmt: skip
            if self._has_objects:
                self._objects_settle(self.swarms, self.d_objects, self.d_object_lo,
                                      self.d_object_hi, self.d_first, self.d_last,
                                      self.d_pushes, self.d_force, self.d_rects, self.d_rect_lo,
                                      self.d_rect_hi, self.d_circles, self.d_circle_lo,
                                      self.d_circle_hi, self.d_prm)  # fmt: skip
        self._stale = [True] * self.swarms
