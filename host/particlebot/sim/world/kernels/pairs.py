"""The pair pass: every pair within reach once (Newton's third law: i gets f, j gets -f), one at
a time for small swarms, or picked into blocks that the force law runs over as a vector loop
for large ones, with the candidates taken from the neighbour lists or straight from a grid."""

from __future__ import annotations

import math

import numba
import numpy as np
import numpy.typing as npt

from particlebot.sim.world.kernels.laws import _contact_law, _join, _law, _magnet_law
from particlebot.sim.world.kernels.layout import (
    _FAST,
    B_FA,
    B_FR,
    B_FX,
    B_FY,
    B_MAG,
    B_R,
    F_KIND,
    P_ATTRACTION,
    P_BLEND_GAP,
    P_CLAMP_FORCE,
    P_CLAMP_GAP,
    P_CUTOFF,
    P_DAMPING,
    P_SHEAR,
    P_SPRING,
    P_TOUCH_GAP,
    ByteArray,
    FloatArray,
    IntArray,
    ListArray,
    _slot,
)


@numba.njit(cache=True, inline="always", fastmath=_FAST)
def _pair(
    i: int, j: int, dx: float, dy: float, d2: float, vxi: float, vyi: float, ri: float,
    magi: float, kind_i: int, vel: FloatArray, body: FloatArray, flags: ByteArray,
    prm: FloatArray,
) -> tuple[float, float, float, float]:  # fmt: skip
    """One listed pair (j > i, rel = pj - pi) within the cutoff: j gets -f and |f| in its sum
    at once; returns what i gets (f and its contact and attraction magnitudes)."""
    c = ri + body[B_R, j]
    reach = c + prm[P_CUTOFF]
    if d2 >= reach * reach or d2 == 0.0:
        return 0.0, 0.0, 0.0, 0.0
    px, py, contact, attract, touching = _law(j, dx, dy, d2, c, vxi, vyi, magi, vel, body, prm)
    body[B_FR, j] += contact
    body[B_FA, j] += attract
    body[B_FX, j] -= px
    body[B_FY, j] -= py
    if touching and kind_i != flags[F_KIND, j]:
        _join(i, j, kind_i, flags)
    return px, py, contact, attract


@numba.njit(cache=True, fastmath=_FAST)
def _pairs_each(
    lo: int, hi: int, pos: FloatArray, vel: FloatArray, body: FloatArray, flags: ByteArray,
    nbr: ListArray, ncount: npt.NDArray[np.int32], prm: FloatArray,
) -> None:  # fmt: skip
    """Second pass, one pair at a time, for small swarms (one inline chunk): every listed pair
    (i in lo..hi, j > i) once, from the new positions and old velocities; i gets f and j gets
    -f, both get |f| in their contact or attraction sum. Bit for bit what small swarms have
    always run (tests pin their trajectories); large swarms take _pairs_cells and _pairs."""
    for signed in range(lo, hi):
        i = _slot(signed)
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
        for k in range(ncount[i]):
            j = _slot(nbr[i, k])
            dx = pos[0, j] - xi
            dy = pos[1, j] - yi
            px, py, contact, attract = _pair(
                i, j, dx, dy, dx * dx + dy * dy, vxi, vyi, ri, magi, kind_i, vel, body,
                flags, prm,
            )  # fmt: skip
            fx += px
            fy += py
            f_contact += contact
            f_attract += attract
        body[B_FX, i] += fx
        body[B_FY, i] += fy
        body[B_FR, i] += f_contact
        body[B_FA, i] += f_attract


PAIR_BLOCK = 1024
"""Pairs gathered before they are evaluated together: the force law then runs as one loop over
contiguous arrays, which the compiler vectorises (no branch to mispredict, several pairs per
instruction)."""


PAIR_INDEX_ROWS = 2  # a pair block's integers (2 blocks wide): second body, first body


PAIR_INPUTS = 6  # its floats: dx, dy, contact distance, dvx, dvy, magnet strength (the inputs),


PAIR_VALUE_ROWS = PAIR_INPUTS + 5  # then fx, fy, contact, attraction magnitudes, touching (0 / 1)


@numba.njit(cache=True, error_model="numpy")
def _pair_forces(
    count: int, dx: FloatArray, dy: FloatArray, c: FloatArray, dvx: FloatArray, dvy: FloatArray,
    strength: FloatArray, law: tuple[float, float, float, float, float, float, float, float],
    fx: FloatArray, fy: FloatArray, contact: FloatArray, attract: FloatArray,
    touching: FloatArray,
) -> None:  # fmt: skip
    """The law of `count` pairs within reach (force on the first body from the second, rel =
    second - first at distance > 0): contact (spring, dashpot, shear) when they overlap, else the
    magnets; the contact and attraction magnitudes; whether they touch (overlap, or a gap below
    the magnets' lock). Branch-free and over plain arrays (the numpy error model: no division
    check), so that it vectorises. law: spring, damping, shear, clamp force, clamp gap, blend
    gap, A, touch gap."""
    spring, damping, shear, low, clamp_gap, blend_gap, a, touch_gap = law
    for q in range(count):
        d = math.sqrt(dx[q] * dx[q] + dy[q] * dy[q])
        nx = dx[q] / d
        ny = dy[q] / d
        overlap = c[q] - d
        px, py = _contact_law(nx, ny, overlap, spring, damping, shear, dvx[q], dvy[q])
        pull = _magnet_law(-overlap, strength[q], low, clamp_gap, blend_gap, a)
        pressed = overlap > 0.0
        fx[q] = px if pressed else pull * nx
        fy[q] = py if pressed else pull * ny
        contact[q] = math.sqrt(px * px + py * py) if pressed else 0.0
        attract[q] = 0.0 if pressed else pull
        touching[q] = 1.0 if -overlap < touch_gap else 0.0


@numba.njit(cache=True, error_model="numpy")
def _pair_block(
    count: int, index: IntArray, values: FloatArray, pos: FloatArray, vel: FloatArray,
    body: FloatArray, flags: ByteArray, prm: FloatArray,
) -> None:  # fmt: skip
    """Evaluates the `count` gathered pairs (i = index[1, q], j = index[0, q]) and adds them up
    in their order: i gets f and j gets -f, both |f| in their contact or attraction sum."""
    partner = index[0]
    inputs = values[:PAIR_INPUTS]
    outputs = values[PAIR_INPUTS:]
    for q in range(count):
        j = _slot(partner[q])
        i = _slot(index[1, q])
        inputs[0, q] = pos[0, j] - pos[0, i]
        inputs[1, q] = pos[1, j] - pos[1, i]
        inputs[2, q] = body[B_R, i] + body[B_R, j]
        inputs[3, q] = vel[0, j] - vel[0, i]
        inputs[4, q] = vel[1, j] - vel[1, i]
        inputs[5, q] = body[B_MAG, i] * body[B_MAG, j]
    law = (
        prm[P_SPRING], prm[P_DAMPING], prm[P_SHEAR], prm[P_CLAMP_FORCE], prm[P_CLAMP_GAP],
        prm[P_BLEND_GAP], prm[P_ATTRACTION], prm[P_TOUCH_GAP],
    )  # fmt: skip
    _pair_forces(
        count, inputs[0], inputs[1], inputs[2], inputs[3], inputs[4], inputs[5], law,
        outputs[0], outputs[1], outputs[2], outputs[3], outputs[4],
    )  # fmt: skip
    for q in range(count):
        j = _slot(partner[q])
        i = _slot(index[1, q])
        px = outputs[0, q]
        py = outputs[1, q]
        contact = outputs[2, q]
        attract = outputs[3, q]
        body[B_FX, i] += px
        body[B_FY, i] += py
        body[B_FR, i] += contact
        body[B_FA, i] += attract
        body[B_FX, j] -= px
        body[B_FY, j] -= py
        body[B_FR, j] += contact
        body[B_FA, j] += attract
        kind_i = flags[F_KIND, i]
        if outputs[4, q] != 0.0 and kind_i != flags[F_KIND, j]:
            _join(i, j, kind_i, flags)


@numba.njit(cache=True, inline="always")
def _pick(
    i: int, j: int, xi: float, yi: float, ri: float, cutoff: float, count: int, index: IntArray,
    pos: FloatArray, body: FloatArray,
) -> int:  # fmt: skip
    """Puts the pair (i, j) at the end of the block and keeps it if it is within reach
    (branch-free: the test is a coin toss a branch predictor loses). Returns the new count."""
    u = _slot(j)
    dx = pos[0, u] - xi
    dy = pos[1, u] - yi
    d2 = dx * dx + dy * dy
    reach = ri + body[B_R, u] + cutoff
    at = _slot(count)  # (signed, it cost 4 of the scan's 28 instructions a candidate: see _slot)
    index[0, at] = j
    index[1, at] = i
    return count + ((d2 < reach * reach) & (d2 != 0.0))


@numba.njit(cache=True)
def _block_full(
    count: int, index: IntArray, values: FloatArray, pos: FloatArray, vel: FloatArray,
    body: FloatArray, flags: ByteArray, prm: FloatArray,
) -> int:  # fmt: skip
    """Once a particle's pairs are in (and at least `block`, values' width, of them): evaluates
    the first `block` pairs and moves the rest to the front. Blocks thus always end at the same
    pairs of a chunk, whichever pass picked them. (Under fast-math a pair's bits depended on
    where in a block it fell, vector or scalar instructions; the law is plain IEEE arithmetic
    now, the same either way, and the blocks still end where they did.)"""
    block = values.shape[1]
    if count < block:  # (callers test first: a call per particle costs)
        return count
    _pair_block(block, index, values, pos, vel, body, flags, prm)
    for q in range(block, count):
        index[0, q - block] = index[0, q]
        index[1, q - block] = index[1, q]
    return count - block


@numba.njit(cache=True)
def _pick_each(
    i: int, candidates: IntArray, count: int, index: IntArray, values: FloatArray,
    pos: FloatArray, vel: FloatArray, body: FloatArray, flags: ByteArray, prm: FloatArray,
) -> int:  # fmt: skip
    """_pick for more candidates than a block holds (never in a real swarm: a thousand
    particles within the list radius), evaluating a block whenever one is full."""
    for j in candidates:
        count = _pick(
            i, j, pos[0, i], pos[1, i], body[B_R, i], prm[P_CUTOFF], count, index, pos, body
        )
        count = _block_full(count, index, values, pos, vel, body, flags, prm)
    return count


@numba.njit(cache=True, inline="always")
def _pick_runs(
    i: int, via: IntArray, a_lo: int, a_hi: int, b_lo: int, b_hi: int, count: int,
    pair_index: IntArray, pair_values: FloatArray, pos: FloatArray, vel: FloatArray,
    body: FloatArray, flags: ByteArray, prm: FloatArray,
) -> int:  # fmt: skip
    """The pair loop, for both sources of candidates: particle i meets via[a_lo:a_hi], then
    via[b_lo:b_hi] (a list: its row, one run; a grid: the later ones of its own cell and the
    cell to its right, then the three cells above), in that order. The pairs within reach are
    picked out first (_pick) into the scratch pair_index (PAIR_INDEX_ROWS, 2 block), and a block
    is evaluated (_pair_block, with pair_values (PAIR_VALUE_ROWS, block)) whenever one is full.
    Returns the pairs picked and not yet evaluated."""
    block = pair_values.shape[1]
    if a_hi - a_lo + b_hi - b_lo > block:
        runs = np.concatenate((via[a_lo:a_hi], via[b_lo:b_hi])).astype(np.int64)
        return _pick_each(i, runs, count, pair_index, pair_values, pos, vel, body, flags, prm)
    cutoff = prm[P_CUTOFF]
    u = _slot(i)
    xi = pos[0, u]
    yi = pos[1, u]
    ri = body[B_R, u]
    for q in range(a_lo, a_hi):
        count = _pick(i, via[_slot(q)], xi, yi, ri, cutoff, count, pair_index, pos, body)
    for q in range(b_lo, b_hi):
        count = _pick(i, via[_slot(q)], xi, yi, ri, cutoff, count, pair_index, pos, body)
    if count >= block:
        count = _block_full(count, pair_index, pair_values, pos, vel, body, flags, prm)
    return count


@numba.njit(cache=True)
def _pairs(
    lo: int, hi: int, pos: FloatArray, vel: FloatArray, body: FloatArray, flags: ByteArray,
    nbr: ListArray, ncount: npt.NDArray[np.int32], pair_index: IntArray, pair_values: FloatArray,
    prm: FloatArray,
) -> None:  # fmt: skip
    """Second pass: every listed pair (i in lo..hi, j > i) within reach once, from the new
    positions and old velocities; i gets f and j gets -f, both get |f| in their contact or
    attraction sum (_pick_runs over each particle's list, then the last block)."""
    count = 0
    for i in range(lo, hi):
        count = _pick_runs(
            i, nbr[i], 0, ncount[i], 0, 0, count, pair_index, pair_values, pos, vel, body,
            flags, prm,
        )  # fmt: skip
    _pair_block(count, pair_index, pair_values, pos, vel, body, flags, prm)


@numba.njit(cache=True)
def _pairs_cells(
    lo: int, hi: int, pos: FloatArray, vel: FloatArray, body: FloatArray, flags: ByteArray,
    members: IntArray, start: IntArray, ncx: int, ncy: int, pair_index: IntArray,
    pair_values: FloatArray, prm: FloatArray,
) -> None:  # fmt: skip
    """_pairs straight from a grid a list build has just made, for a step that builds the
    lists: the particles at cell-order places lo..hi (members[p] is the slot of place p; the
    identity when the build re-ordered the particles) meet the candidates _fill_lists would
    list, in the same order, so the same pairs within reach come in the same order and blocks
    as from the lists, and the sums are bit for bit the same. The lists themselves are filled
    later, only if a step needs them (see advance)."""
    count = 0
    c = int(np.searchsorted(start, lo, side="right")) - 1  # the cell holding place lo
    for p in range(lo, hi):
        while start[c + 1] <= p:
            c += 1
        cx = c % ncx
        cy = c // ncx
        row = cy * ncx
        right = min(cx + 1, ncx - 1)
        end = start[row + right + 1]  # the later ones of its own cell and the cell to its right
        above_lo = 0  # the three cells above
        above_hi = 0
        if cy + 1 < ncy:
            above_lo = start[row + ncx + max(cx - 1, 0)]
            above_hi = start[row + ncx + right + 1]
        count = _pick_runs(
            members[_slot(p)], members, p + 1, end, above_lo, above_hi, count, pair_index,
            pair_values, pos, vel, body, flags, prm,
        )  # fmt: skip
    _pair_block(count, pair_index, pair_values, pos, vel, body, flags, prm)
