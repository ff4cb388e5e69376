"""Binning the particles into grid cells (a stable counting sort, serial or in parallel parts),
re-ordering every per-particle row into cell order, and cutting the chunks on grid rows."""

from __future__ import annotations

import math

import numba
import numpy as np
import numpy.typing as npt

from particlebot.sim.world.kernels.layout import (
    B_FX,
    FLAG_ROWS,
    ByteArray,
    FloatArray,
    IntArray,
    _slot,
)


@numba.njit(cache=True, inline="always")
def _split(s: int, splits: int, n: int) -> tuple[int, int]:
    """The index range of the s-th of `splits` near-equal parts of 0..n."""
    return s * n // splits, (s + 1) * n // splits


@numba.njit(cache=True)
def _box(xs: FloatArray, ys: FloatArray, out: FloatArray) -> None:
    """The points' bounding box into out: x min, x max, y min, y max (one pass)."""
    x0 = xs[0]
    x1 = x0
    y0 = ys[0]
    y1 = y0
    for q in range(xs.shape[0]):
        x0 = min(x0, xs[q])
        x1 = max(x1, xs[q])
        y0 = min(y0, ys[q])
        y1 = max(y1, ys[q])
    out[0] = x0
    out[1] = x1
    out[2] = y0
    out[3] = y1


@numba.njit(cache=True)
def _grid_shape(box: FloatArray, radius: float, n: int) -> tuple[int, int, float]:
    """The grid over the bounding boxes of parts (rows: x min, x max, y min, y max) of n
    particles: its columns, rows and cell size."""
    width = box[:, 1].max() - box[:, 0].min() + radius
    height = box[:, 3].max() - box[:, 2].min() + radius
    size = max(radius, math.sqrt(width * height / (2.0 * n + 64.0)))
    return int(width / size) + 1, int(height / size) + 1, size


@numba.njit(cache=True)
def _offsets(offset: IntArray) -> IntArray:
    """Turns each part's per-cell counts (a row per part) into where its first member of each
    cell goes: cell by cell, part by part, so that the parts together make one stable counting
    sort. Returns the cells' start offsets."""
    parts, ncells = offset.shape
    start = np.empty(ncells + 1, dtype=np.int64)
    total = 0
    for c in range(ncells):
        start[c] = total
        for s in range(parts):
            here = offset[s, c]
            offset[s, c] = total
            total += here
    start[ncells] = total
    return start


@numba.njit(cache=True)
def _bin(
    xs: FloatArray, ys: FloatArray, x0: float, y0: float, size: float, ncx: int,
    cells: IntArray, count: IntArray,
) -> None:  # fmt: skip
    """Each particle's cell (row-major, as _grid), counted into `count`."""
    for q in range(xs.shape[0]):
        c = int((ys[q] - y0) / size) * ncx + int((xs[q] - x0) / size)
        cells[q] = c
        count[_slot(c)] += 1


@numba.njit(cache=True)
def _deal(first: int, cells: IntArray, fill: IntArray, members: IntArray) -> None:
    """Particles first, first + 1, ... into their cells' next free places."""
    for q in range(cells.shape[0]):
        c = _slot(cells[q])
        members[_slot(fill[c])] = first + q
        fill[c] += 1


@numba.njit(cache=True)
def _grid(pos: FloatArray, radius: float) -> tuple[int, int, IntArray, IntArray, IntArray]:
    """Bins particles into square cells at least `radius` wide over their bounding box (wider
    when needed to keep at most ~2 cells per particle). Returns the grid's shape, each
    particle's cell (row-major), the cells' start offsets and the particles cell by cell (a
    stable counting sort: index order within a cell). _grid_split is the same in parts."""
    n = pos.shape[1]
    box = np.empty((1, 4))
    _box(pos[0], pos[1], box[0])
    ncx, ncy, size = _grid_shape(box, radius, n)
    cells = np.empty(n, dtype=np.int64)
    offset = np.zeros((1, ncx * ncy), dtype=np.int64)
    _bin(pos[0], pos[1], box[0, 0], box[0, 2], size, ncx, cells, offset[0])
    start = _offsets(offset)
    members = np.empty(n, dtype=np.int64)
    _deal(0, cells, offset[0], members)
    return ncx, ncy, cells, start, members


GRID_PARTS = 4
"""The most parts a list build bins its particles in: each part has a row of counts for every
cell, and the rows are offset cell by cell in one serial pass, so parts cost memory and serial
time (1,000,000 particles on two threads: 6.6 ns a particle serially, 3.5 in 2 parts, 4.4 in 4,
21 in 16, whose 43 MB of counts no longer fit the cache). The re-ordering has no such rows and
takes every thread."""


@numba.njit(parallel=True, cache=True)
def _grid_split(
    pos: FloatArray, radius: float, splits: int
) -> tuple[int, int, IntArray, IntArray, IntArray]:
    """_grid with its passes over the particles cut into `splits` index ranges run in parallel,
    and the same result: the same grid, and the same stable counting sort (the ranges' counts
    are offset cell by cell, range by range), so nothing depends on the number of threads."""
    n = pos.shape[1]
    box = np.empty((splits, 4))
    for s in numba.prange(splits):
        lo, hi = _split(s, splits, n)
        _box(pos[0, lo:hi], pos[1, lo:hi], box[s])
    x0 = box[:, 0].min()
    y0 = box[:, 2].min()
    ncx, ncy, size = _grid_shape(box, radius, n)
    cells = np.empty(n, dtype=np.int64)
    # A row of counts per part (no two threads write one cache line but at the seams).
    offset = np.zeros((splits, ncx * ncy), dtype=np.int64)
    for s in numba.prange(splits):
        lo, hi = _split(s, splits, n)
        _bin(pos[0, lo:hi], pos[1, lo:hi], x0, y0, size, ncx, cells[lo:hi], offset[s])
    start = _offsets(offset)
    members = np.empty(n, dtype=np.int64)
    for s in numba.prange(splits):
        lo, hi = _split(s, splits, n)
        _deal(lo, cells[lo:hi], offset[s], members)
    return ncx, ncy, cells, start, members


BODY_KEPT = B_FX
"""Rows of `body` that carry over from step to step (r, the force sums the servo reads, the
magnet factor); force x and y are a step's own, zero between steps, so a re-ordering skips them."""


@numba.njit(cache=True, inline="always")
def _gather(source: npt.NDArray[np.generic], order: IntArray, out: npt.NDArray[np.generic]) -> None:
    """out[q] = source[order[q]]."""
    for q in range(out.shape[0]):
        out[q] = source[_slot(order[q])]


@numba.njit(cache=True)
def _reorder(
    order: IntArray, pos: FloatArray, ref: FloatArray, vel: FloatArray,
    body: FloatArray, flags: ByteArray, ext: IntArray,
) -> None:  # fmt: skip
    """Every per-particle row (but a step's own force rows) and `ext` re-ordered: slot p takes
    what slot order[p] held. Positions go through ref, which a list build then wants equal to
    them anyway; the rest through copies."""
    for axis in range(2):
        _gather(pos[axis], order, ref[axis])
    pos[:, :] = ref
    speeds = vel.copy()
    for axis in range(2):
        _gather(speeds[axis], order, vel[axis])
    had = body[:BODY_KEPT].copy()
    for r in range(BODY_KEPT):
        _gather(had[r], order, body[r])
    was = flags.copy()
    for r in range(FLAG_ROWS):
        _gather(was[r], order, flags[r])
    _gather(ext.copy(), order, ext)


@numba.njit(cache=True)
def _reorder_gather(
    lo: int, hi: int, order: IntArray, cells: IntArray, pos: FloatArray, ref: FloatArray,
    vel: FloatArray, body: FloatArray, flags: ByteArray, ext: IntArray, speeds: FloatArray,
    had: FloatArray, was: ByteArray, index: IntArray, sorted_cells: IntArray,
) -> None:  # fmt: skip
    """_reorder_split's first half for slots lo..hi: positions, velocities and cells gathered
    into rows nothing else reads, the other rows copied aside."""
    # (Slices and loops from 0: over range(lo, hi) of whole rows this took 3x as long (numba, we
    # think, cannot tell such an index is not negative and checks it on every access).)
    mine = order[lo:hi]
    for axis in range(2):
        _gather(pos[axis], mine, ref[axis, lo:hi])
        _gather(vel[axis], mine, speeds[axis, lo:hi])
    _gather(cells, mine, sorted_cells[lo:hi])
    had[:, lo:hi] = body[:BODY_KEPT, lo:hi]
    was[:, lo:hi] = flags[:, lo:hi]
    index[lo:hi] = ext[lo:hi]


@numba.njit(cache=True)
def _reorder_place(
    lo: int, hi: int, order: IntArray, pos: FloatArray, ref: FloatArray, vel: FloatArray,
    body: FloatArray, flags: ByteArray, ext: IntArray, speeds: FloatArray, had: FloatArray,
    was: ByteArray, index: IntArray,
) -> None:  # fmt: skip
    """_reorder_split's second half for slots lo..hi: every row takes its new order."""
    mine = order[lo:hi]
    pos[:, lo:hi] = ref[:, lo:hi]
    vel[:, lo:hi] = speeds[:, lo:hi]
    for r in range(BODY_KEPT):
        _gather(had[r], mine, body[r, lo:hi])
    for r in range(FLAG_ROWS):
        _gather(was[r], mine, flags[r, lo:hi])
    _gather(index, mine, ext[lo:hi])


@numba.njit(parallel=True, cache=True)
def _reorder_split(
    order: IntArray, cells: IntArray, pos: FloatArray, ref: FloatArray, vel: FloatArray,
    body: FloatArray, flags: ByteArray, ext: IntArray, splits: int,
) -> IntArray:  # fmt: skip
    """_reorder in `splits` parallel index ranges (the same result: each slot is one copy),
    which also re-orders the particles' cells. Returns the cells in the new order."""
    n = pos.shape[1]
    speeds = np.empty_like(vel)
    had = np.empty((BODY_KEPT, n), dtype=body.dtype)
    was = np.empty_like(flags)
    index = np.empty_like(ext)
    sorted_cells = np.empty_like(cells)
    for s in numba.prange(splits):
        lo, hi = _split(s, splits, n)
        _reorder_gather(lo, hi, order, cells, pos, ref, vel, body, flags, ext, speeds, had,
                        was, index, sorted_cells)  # fmt: skip
    for s in numba.prange(splits):  # (once every range has read what it gathers)
        lo, hi = _split(s, splits, n)
        _reorder_place(lo, hi, order, pos, ref, vel, body, flags, ext, speeds, had, was, index)
    return sorted_cells


@numba.njit(cache=True)
def _row_bounds(start: IntArray, ncx: int, ncy: int, bounds: IntArray) -> None:
    """Chunk bounds on grid-row boundaries, about equal in particles; with fewer rows than
    chunks the last chunks are empty. A chunk's pairs then reach no further than the next."""
    chunks = bounds.shape[0] - 1
    n = start[ncx * ncy]
    bounds[0] = 0
    c = 1
    for row in range(1, ncy):
        if c >= chunks:
            break
        offset = start[row * ncx]
        if offset >= c * n // chunks and offset > bounds[c - 1]:
            bounds[c] = offset
            c += 1
    for rest in range(c, chunks + 1):
        bounds[rest] = n
