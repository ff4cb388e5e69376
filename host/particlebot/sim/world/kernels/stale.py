"""The published code's stale grid (NeighbourSearch.PUBLISHED_STALE_GRID): its listing, its
one-sided pair pass and its serial step loop, for measuring what the stale search changes."""

from __future__ import annotations

import math

import numba
import numpy as np

from particlebot.sim.world.kernels.laws import _join, _law
from particlebot.sim.world.kernels.layout import (
    _FAST,
    B_FA,
    B_FR,
    B_FX,
    B_FY,
    B_MAG,
    B_R,
    F_KIND,
    P_CUTOFF,
    ByteArray,
    FloatArray,
    IntArray,
)
from particlebot.sim.world.kernels.motion import _kinematics, _settle, _targets_here
from particlebot.sim.world.kernels.objects import _objects_move, _objects_settle

STALE_GRID = 512
"""The published grid: STALE_GRID x STALE_GRID cells (a power of two: cell indices wrap)."""


STALE_REACH = 2
"""A particle meets the particles listed in the cells up to this many cells away (5 x 5)."""


@numba.njit(cache=True, inline="always")
def _stale_cell(x: float, y: float, origin: float, cell: float) -> tuple[int, int]:
    """Unwrapped grid column and row of a point (the published floor((p - origin) / cell))."""
    return math.floor((x - origin) / cell), math.floor((y - origin) / cell)


@numba.njit(cache=True, inline="always")
def _stale_hash(cx: int, cy: int) -> int:
    """Wrapped cell index of a column and row (negative ones wrap as two's complement does)."""
    mask = STALE_GRID - 1
    return (cy & mask) * STALE_GRID + (cx & mask)


@numba.njit(cache=True)
def stale_index(hashes: IntArray, members: IntArray, start: IntArray) -> None:
    """The listing from each particle's listed cell: members holds the particles cell by cell
    (index order within a cell, a stable sort as the published radix sort), cell h's run is
    members[start[h]:start[h + 1]]."""
    start[:] = 0
    for i in range(hashes.shape[0]):
        start[hashes[i] + 1] += 1
    for h in range(start.shape[0] - 1):
        start[h + 1] += start[h]
    fill = start[:-1].copy()
    for i in range(hashes.shape[0]):
        members[fill[hashes[i]]] = i
        fill[hashes[i]] += 1


@numba.njit(cache=True)
def stale_list(
    pos: FloatArray, origin: float, cell: float, hashes: IntArray, members: IntArray,
    start: IntArray,
) -> None:  # fmt: skip
    """Lists every particle in the cell it is in now (the published sort)."""
    for i in range(pos.shape[1]):
        cx, cy = _stale_cell(pos[0, i], pos[1, i], origin, cell)
        hashes[i] = _stale_hash(cx, cy)
    stale_index(hashes, members, start)


@numba.njit(cache=True, fastmath=_FAST)
def _stale_pairs(
    pos: FloatArray, vel: FloatArray, body: FloatArray, flags: ByteArray, members: IntArray,
    start: IntArray, origin: float, cell: float, prm: FloatArray,
) -> None:  # fmt: skip
    """The pair pass as published: each particle i, in the cell it is in NOW, meets every
    particle LISTED in the 5 x 5 cells around it (within the magnet cutoff) and takes only its
    own side of each pair, so a pair whose partner was listed too far away acts on one of the
    two or on neither."""
    cutoff = prm[P_CUTOFF]
    for i in range(pos.shape[1]):
        xi = pos[0, i]
        yi = pos[1, i]
        vxi = vel[0, i]
        vyi = vel[1, i]
        ri = body[B_R, i]
        magi = body[B_MAG, i]
        kind_i = flags[F_KIND, i]
        fx = 0.0
        fy = 0.0
        f_contact = 0.0
        f_attract = 0.0
        cx, cy = _stale_cell(xi, yi, origin, cell)
        for oy in range(-STALE_REACH, STALE_REACH + 1):
            for ox in range(-STALE_REACH, STALE_REACH + 1):
                h = _stale_hash(cx + ox, cy + oy)
                for slot in range(start[h], start[h + 1]):
                    j = members[slot]
                    if j == i:
                        continue
                    dx = pos[0, j] - xi
                    dy = pos[1, j] - yi
                    d2 = dx * dx + dy * dy
                    c = ri + body[B_R, j]
                    reach = c + cutoff
                    if d2 >= reach * reach or d2 == 0.0:
                        continue
                    px, py, contact, attract, touching = _law(
                        j, dx, dy, d2, c, vxi, vyi, magi, vel, body, prm
                    )
                    fx += px
                    fy += py
                    f_contact += contact
                    f_attract += attract
                    if touching and kind_i != flags[F_KIND, j]:
                        _join(i, j, kind_i, flags)
        body[B_FX, i] += fx
        body[B_FY, i] += fy
        body[B_FR, i] += f_contact
        body[B_FA, i] += f_attract


@numba.njit(cache=True)
def advance_stale(
    steps: int, first: int, sort_steps: int, targets: FloatArray, ext: IntArray, pos: FloatArray,
    ref: FloatArray, vel: FloatArray, body: FloatArray, flags: ByteArray,
    rects: FloatArray, circles: FloatArray, objects: FloatArray, acc: FloatArray,
    hashes: IntArray, members: IntArray, start: IntArray, origin: float, cell: float,
    prm: FloatArray,
) -> int:  # fmt: skip
    """`advance` with the published code's search, serial (for small swarms): the particles are
    re-listed after the position update of every step whose number (`first` + s) is a multiple
    of sort_steps. Passive objects still meet every particle directly. Returns the listings."""
    n = pos.shape[1]
    here = np.empty(n, dtype=targets.dtype)
    listings = 0
    for s in range(steps):
        _targets_here(0, n, targets[s], ext, here)
        _kinematics(0, n, here, pos, ref, vel, body, flags, prm)
        _objects_move(objects, prm)
        if (first + s) % sort_steps == 0:
            stale_list(pos, origin, cell, hashes, members, start)
            listings += 1
        _stale_pairs(pos, vel, body, flags, members, start, origin, cell, prm)
        _settle(0, n, pos, vel, body, rects, circles, objects, acc[0], prm)
        if objects.shape[0] > 0:
            _objects_settle(objects, acc, rects, circles, prm)
    return listings
