"""The step loop: each pass over every chunk in parallel (or inline for one chunk), the lists
rebuilt when needed, `advance` running a number of steps."""

from __future__ import annotations

import numba
import numpy as np
import numpy.typing as npt

from particlebot.sim.world.kernels.layout import (
    P_LIST_RADIUS,
    P_SKIN,
    ByteArray,
    FloatArray,
    IntArray,
    ListArray,
)
from particlebot.sim.world.kernels.lists import (
    SORT_EVERY,
    _lists_from_ref,
    _prepare,
    _unsorted_radius,
    build_lists,
)
from particlebot.sim.world.kernels.motion import _kinematics, _settle, _targets_here
from particlebot.sim.world.kernels.objects import _objects_move, _objects_settle
from particlebot.sim.world.kernels.pairs import _pairs, _pairs_cells, _pairs_each


@numba.njit(parallel=True, cache=True)
def _kinematics_chunks(
    bounds: IntArray, row: FloatArray, ext: IntArray, here: FloatArray, pos: FloatArray,
    ref: FloatArray, vel: FloatArray, body: FloatArray, flags: ByteArray,
    prm: FloatArray,
) -> float:  # fmt: skip
    """_targets_here and _kinematics over every chunk in parallel; the largest squared
    displacement."""
    chunks = bounds.shape[0] - 1
    worst = np.zeros(chunks)
    for c in numba.prange(chunks):
        _targets_here(bounds[c], bounds[c + 1], row, ext, here)
        worst[c] = _kinematics(bounds[c], bounds[c + 1], here, pos, ref, vel, body, flags, prm)
    most = 0.0
    for c in range(chunks):
        most = max(most, worst[c])
    return most


@numba.njit(parallel=True, cache=True)
def _pairs_chunks(
    bounds: IntArray, parity: int, pos: FloatArray, vel: FloatArray, body: FloatArray,
    flags: ByteArray, nbr: ListArray, ncount: npt.NDArray[np.int32], pair_index: IntArray,
    pair_values: FloatArray, prm: FloatArray,
) -> None:  # fmt: skip
    """_pairs over the even (parity 0) or odd (1) chunks in parallel: they write only their own
    chunk and the next, which no other chunk of the same parity touches."""
    chunks = bounds.shape[0] - 1
    for half in numba.prange((chunks - parity + 1) // 2):
        c = 2 * half + parity
        _pairs(
            bounds[c], bounds[c + 1], pos, vel, body, flags, nbr, ncount, pair_index[c],
            pair_values[c], prm,
        )  # fmt: skip


@numba.njit(parallel=True, cache=True)
def _pairs_cells_chunks(
    bounds: IntArray, parity: int, pos: FloatArray, vel: FloatArray, body: FloatArray,
    flags: ByteArray, members: IntArray, start: IntArray, ncx: int, ncy: int,
    pair_index: IntArray, pair_values: FloatArray, prm: FloatArray,
) -> None:  # fmt: skip
    """_pairs_cells over the even (parity 0) or odd (1) chunks in parallel, as _pairs_chunks
    (the bounds are cell-order places)."""
    chunks = bounds.shape[0] - 1
    for half in numba.prange((chunks - parity + 1) // 2):
        c = 2 * half + parity
        _pairs_cells(
            bounds[c], bounds[c + 1], pos, vel, body, flags, members, start, ncx, ncy,
            pair_index[c], pair_values[c], prm,
        )  # fmt: skip


@numba.njit(parallel=True, cache=True)
def _settle_chunks(
    bounds: IntArray, pos: FloatArray, vel: FloatArray, body: FloatArray,
    rects: FloatArray, circles: FloatArray, objects: FloatArray, acc: FloatArray,
    prm: FloatArray,
) -> None:  # fmt: skip
    """_settle over every chunk in parallel."""
    for c in numba.prange(bounds.shape[0] - 1):
        _settle(
            bounds[c], bounds[c + 1], pos, vel, body, rects, circles, objects, acc[c],
            prm,
        )  # fmt: skip


@numba.njit(cache=True)
def advance(
    steps: int, targets: FloatArray, ext: IntArray, pos: FloatArray, ref: FloatArray,
    vel: FloatArray, body: FloatArray, flags: ByteArray, nbr: ListArray,
    ncount: npt.NDArray[np.int32], listed: bool, unsorted: int, rects: FloatArray,
    circles: FloatArray, objects: FloatArray, acc: FloatArray, bounds: IntArray,
    pair_index: IntArray, pair_values: FloatArray, prm: FloatArray, splits: int,
) -> tuple[ListArray, bool, int, int]:  # fmt: skip
    """Runs `steps` steps; step s commands the radii targets[s, ext[i]] (NaN: hold). With one
    chunk everything runs inline (no parallel region to start), with several in parallel.
    pair_index and pair_values are the pair pass's scratch, one (rows, block) per chunk.

    With several chunks, a step that rebuilds the lists takes its pairs straight from the new
    grid (_pairs_cells) and leaves the lists unfilled (`listed` False); the next step that keeps
    them fills them from the build's positions first. A boiling swarm, rebuilding every step,
    never fills a list. Such a build re-orders the particles (cell order) only at every
    SORT_EVERY-th build in a row; in between (`unsorted`: the builds since the last
    re-ordering) the pairs reach the particles through the grid's order, and a step that would
    keep lists built that way rebuilds them with a re-ordering instead. One chunk (a small
    swarm) runs its pairs one at a time (_pairs_each) and re-orders at every build.
    Returns the neighbour lists' array (possibly a new, wider one), whether it holds the last
    build's lists, `unsorted`, and how many times the lists were rebuilt."""
    n = pos.shape[1]
    inline = bounds.shape[0] == 2
    limit = 0.25 * prm[P_SKIN] * prm[P_SKIN]  # (skin / 2)^2
    rebuilds = 0
    here = np.empty(n, dtype=targets.dtype)  # a step's commanded radii in slot order
    for s in range(steps):
        if inline:
            _targets_here(0, n, targets[s], ext, here)
            moved = _kinematics(0, n, here, pos, ref, vel, body, flags, prm)
        else:
            moved = _kinematics_chunks(
                bounds, targets[s], ext, here, pos, ref, vel, body, flags, prm
            )
        _objects_move(objects, prm)
        if inline:  # a small swarm: lists built whenever needed, pairs one at a time
            if moved > limit:
                nbr = build_lists(
                    pos, ref, vel, body, flags, ext, nbr, ncount, bounds, prm, True,
                    splits,
                )  # fmt: skip
                rebuilds += 1
            _pairs_each(0, n, pos, vel, body, flags, nbr, ncount, prm)
        elif moved > limit or unsorted > 0:
            sort = moved <= limit or unsorted + 1 >= SORT_EVERY
            ncx, ncy, _, start, members = _prepare(
                pos, ref, vel, body, flags, ext, bounds, prm, sort, splits,
                prm[P_LIST_RADIUS] if sort else _unsorted_radius(prm),
            )  # fmt: skip
            unsorted = 0 if sort else unsorted + 1
            rebuilds += 1
            listed = False
            for parity in (0, 1):
                _pairs_cells_chunks(
                    bounds, parity, pos, vel, body, flags, members, start, ncx, ncy,
                    pair_index, pair_values, prm,
                )  # fmt: skip
        else:
            if not listed:
                nbr = _lists_from_ref(ref, nbr, ncount, bounds, prm)
                listed = True
            for parity in (0, 1):
                _pairs_chunks(
                    bounds, parity, pos, vel, body, flags, nbr, ncount, pair_index,
                    pair_values, prm,
                )  # fmt: skip
        if inline:
            _settle(0, n, pos, vel, body, rects, circles, objects, acc[0], prm)
        else:
            _settle_chunks(bounds, pos, vel, body, rects, circles, objects, acc, prm)
        if objects.shape[0] > 0:
            _objects_settle(objects, acc, rects, circles, prm)
    return nbr, listed, unsorted, rebuilds
