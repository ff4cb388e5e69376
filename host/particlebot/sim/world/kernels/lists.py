"""The half neighbour lists: built from the grid (binning), rebuilt when a body has moved half
the skin since the last build, and restored as they were for a resumed world."""

from __future__ import annotations

import numba
import numpy as np
import numpy.typing as npt

from particlebot.sim.world.kernels.binning import (
    GRID_PARTS,
    _grid,
    _grid_split,
    _reorder,
    _reorder_split,
    _row_bounds,
)
from particlebot.sim.world.kernels.layout import (
    P_LIST_RADIUS,
    P_SKIN,
    ByteArray,
    FloatArray,
    IntArray,
    ListArray,
    _slot,
)

SORT_EVERY = 12
"""A large swarm that rebuilds its lists at every step (a boiling one) puts its particles in
cell order at every SORT_EVERY-th build only, and reaches them through the grid's order in
between: the re-ordering moves every row of every particle, 17 of 60 ns a particle-step on two
threads at 200,000 particles, while in between the particles stay close to their places. 8-16
measured alike (a boiling step 20-25 % quicker on two threads, 10-25 % on one; README, "Re-
ordering at every 12th build"); 32 and 64 lose part of it as the order drifts. (numba compiles
this value into the kernels and its cache does not see it change: clear the cache when trying
others.)"""


@numba.njit(cache=True)
def _fill_lists(
    lo: int, hi: int, pos: FloatArray, cells: IntArray, start: IntArray, ncx: int, ncy: int,
    radius: float, nbr: ListArray, ncount: npt.NDArray[np.int32],
) -> int:  # fmt: skip
    """Half lists of particles lo..hi, the particles being in cell order: the later ones of its
    own cell and the cell to its right (one run of indices), then the three cells above (another
    run). Returns the longest list found, which may exceed nbr's width (then redo wider)."""
    # Branch-free: every candidate is written at the list's end and kept only if close (the
    # test is a coin toss a branch predictor loses); the last column is that scratch slot.
    width = nbr.shape[1] - 1
    longest = 0
    r2 = radius * radius
    for i in range(lo, hi):
        cx = cells[i] % ncx
        cy = cells[i] // ncx
        xi = pos[0, i]
        yi = pos[1, i]
        count = 0
        row = cy * ncx
        right = min(cx + 1, ncx - 1)
        for j in range(i + 1, start[row + right + 1]):
            u = _slot(j)
            dx = pos[0, u] - xi
            dy = pos[1, u] - yi
            nbr[i, _slot(min(count, width))] = j
            count += dx * dx + dy * dy < r2
        if cy + 1 < ncy:
            above = row + ncx
            for j in range(start[above + max(cx - 1, 0)], start[above + right + 1]):
                u = _slot(j)
                dx = pos[0, u] - xi
                dy = pos[1, u] - yi
                nbr[i, _slot(min(count, width))] = j
                count += dx * dx + dy * dy < r2
        ncount[i] = min(count, width)
        longest = max(longest, count)
    return longest


@numba.njit(parallel=True, cache=True)
def _fill_chunks(
    bounds: IntArray, pos: FloatArray, cells: IntArray, start: IntArray, ncx: int, ncy: int,
    radius: float, nbr: ListArray, ncount: npt.NDArray[np.int32],
) -> int:  # fmt: skip
    """_fill_lists over every chunk in parallel; the longest list found."""
    chunks = bounds.shape[0] - 1
    longest = np.zeros(chunks, dtype=np.int64)
    for c in numba.prange(chunks):
        longest[c] = _fill_lists(
            bounds[c], bounds[c + 1], pos, cells, start, ncx, ncy, radius, nbr, ncount
        )
    most = 0
    for c in range(chunks):
        most = max(most, longest[c])
    return most


@numba.njit(cache=True)
def _prepare(
    pos: FloatArray, ref: FloatArray, vel: FloatArray, body: FloatArray,
    flags: ByteArray, ext: IntArray, bounds: IntArray, prm: FloatArray, sort: bool, splits: int,
    radius: float,
) -> tuple[int, int, IntArray, IntArray, IntArray]:  # fmt: skip
    """The first half of a list build: grid the particles in cells `radius` wide, put them in
    grid-cell order when `sort` (every per-particle row and `ext` follow), make the positions
    the lists' reference and re-cut the chunk bounds on grid rows. A large swarm (several
    chunks) does the binning and re-ordering in parts in parallel (`splits`: one per thread;
    the same result however many). Returns the grid (shape, each slot's cell, the cells' start
    offsets in cell order) and each cell-order place's slot: the identity after a re-ordering;
    without one, the slots in the stable order of the cells (as after a restore from the
    lists' reference positions, where the particles already are in that order, also the
    identity)."""
    n = pos.shape[1]
    splits = min(splits, n)
    # A large swarm on several threads bins in up to GRID_PARTS parts and re-orders in one part
    # per thread. (On one thread the serial passes are quicker: 12 against 15 ns a particle to
    # re-order 200,000.)
    if bounds.shape[0] > 2 and splits > 1:
        parts = min(splits, GRID_PARTS)
        ncx, ncy, cells, start, members = _grid_split(pos, radius, parts)
        if sort:
            cells = _reorder_split(members, cells, pos, ref, vel, body, flags, ext, splits)
    else:
        ncx, ncy, cells, start, members = _grid(pos, radius)
        if sort:
            _reorder(members, pos, ref, vel, body, flags, ext)
            for c in range(ncx * ncy):  # the same grid, now in cell order
                for p in range(start[c], start[c + 1]):
                    cells[p] = c
    if sort:
        members = np.arange(n)
    else:
        ref[:, :] = pos
    _row_bounds(start, ncx, ncy, bounds)
    return ncx, ncy, cells, start, members


@numba.njit(cache=True)
def _fill(
    pos: FloatArray, cells: IntArray, start: IntArray, ncx: int, ncy: int, nbr: ListArray,
    ncount: npt.NDArray[np.int32], bounds: IntArray, prm: FloatArray,
) -> ListArray:  # fmt: skip
    """The second half: the half lists, in a wider array if some list did not fit."""
    radius = prm[P_LIST_RADIUS]
    n = pos.shape[1]
    while True:
        if bounds.shape[0] == 2:
            need = _fill_lists(0, n, pos, cells, start, ncx, ncy, radius, nbr, ncount)
        else:
            need = _fill_chunks(bounds, pos, cells, start, ncx, ncy, radius, nbr, ncount)
        if need < nbr.shape[1]:
            return nbr
        nbr = np.empty((n, need + 5), dtype=np.int32)


@numba.njit(cache=True)
def build_lists(
    pos: FloatArray, ref: FloatArray, vel: FloatArray, body: FloatArray,
    flags: ByteArray, ext: IntArray, nbr: ListArray, ncount: npt.NDArray[np.int32],
    bounds: IntArray, prm: FloatArray, sort: bool, splits: int,
) -> ListArray:  # fmt: skip
    """Rebuilds the half neighbour lists from the current positions (see _prepare). Returns the
    lists' array (a wider one if some list did not fit)."""
    ncx, ncy, cells, start, _ = _prepare(
        pos, ref, vel, body, flags, ext, bounds, prm, sort, splits, prm[P_LIST_RADIUS]
    )
    return _fill(pos, cells, start, ncx, ncy, nbr, ncount, bounds, prm)


@numba.njit(cache=True, inline="always")
def _unsorted_radius(prm: FloatArray) -> float:
    """The cell width of a build that does not re-order (see advance): it fills no lists, so
    its cells need only the reach of a pair (2 r_max + cutoff), not the skin."""
    return prm[P_LIST_RADIUS] - prm[P_SKIN]


@numba.njit(cache=True)
def restore_lists(
    ref: FloatArray, vel: FloatArray, body: FloatArray, flags: ByteArray,
    ext: IntArray, nbr: ListArray, ncount: npt.NDArray[np.int32], bounds: IntArray,
    prm: FloatArray, unsorted: int, splits: int,
) -> tuple[ListArray, bool]:  # fmt: skip
    """A restored world's last build as it was, from the positions it was made at (ref): after
    a re-ordering, its lists (the particles are in its order); `unsorted` builds later, only its
    grid's chunk bounds (such a build had no lists). Returns the lists' array and whether it
    holds them (advance's `listed`)."""
    if unsorted:
        _prepare(
            ref.copy(), ref, vel, body, flags, ext, bounds, prm, False, splits,
            _unsorted_radius(prm),
        )  # fmt: skip
        return nbr, False
    nbr = build_lists(
        ref.copy(), ref, vel, body, flags, ext, nbr, ncount, bounds, prm, False, splits
    )
    return nbr, True


@numba.njit(cache=True)
def _lists_from_ref(
    ref: FloatArray, nbr: ListArray, ncount: npt.NDArray[np.int32], bounds: IntArray,
    prm: FloatArray,
) -> ListArray:  # fmt: skip
    """The lists of the last build, which its step skipped (_pairs_cells): the same grid and
    lists, from the positions it was made at (ref; the particles are still in its order)."""
    ncx, ncy, cells, start, _ = _grid(ref, prm[P_LIST_RADIUS])
    return _fill(ref, cells, start, ncx, ncy, nbr, ncount, bounds, prm)
