"""The world's compiled inner loops (numba): servo, motion, contacts, magnets, friction, lists.

Memory layout (structure of arrays, rows of 2-D arrays, particles in *internal* order): at a
list build the particles are put in grid-cell order (row by row), so that a particle's neighbours
sit close to it in memory (a large swarm rebuilding at every step does so at every SORT_EVERY-th
build, and the pair pass reaches them through the grid's order in between); `ext[i]` is the
caller's index of internal slot i. Passive objects (few, possibly huge discs) live in their own
array and meet every particle directly.

    pos     float64 (2, N)  x, y            ref  float64 (2, N)  x, y at the last list build
    vel     F       (2, N)  vx, vy (the first pass reflects it at walls, the last sets it;
                            the force passes between read it as the step's old velocity)
    body    F       (6, N)  r, contact-force sum, attraction sum, magnet factor (1, or 0 once
                            detached), force x, force y (the last two a step's own: zero
                            between steps; the pair passes add into them, the last pass reads
                            and clears them)
    flags   uint8   (5, N)  kind (MEMBER / FREE / DETACHED), acting, joined, alive, held
    nbr     int32   (N, M)  half neighbour lists: j > i within the list radius, counts in ncount

F is float64 or float32 (the World's `precision`; positions are always float64: float32 cannot
resolve a 10 um step 100 m from the origin).

Each pair is evaluated once (Newton's third law: i gets f, j gets -f), as the published code's
two one-sided evaluations give bit-identical opposite forces. The work is cut into chunks along
grid rows: a particle's listed neighbours lie in its own chunk or the next one, so the pair pass
runs the even chunks in parallel, then the odd ones, without atomics; every other pass writes
only its own chunk. Results do not depend on the number of threads.
"""

from __future__ import annotations

import math

import numba
import numpy as np
import numpy.typing as npt

# Start numba's thread pool before any kernel is compiled or loaded. Starting it registers the
# parallel scheduler's symbols (allocate_sched, ...) with LLVM; kernels that reach a parallel
# region link against them, and a small swarm never starts the pool itself. `simulate --resume`
# of a small swarm calls restore_lists first: compiled in such a process and loaded from numba's
# cache by the next, it segfaulted; compiled against cached kernels, it failed with "LLVM ERROR:
# Symbol not found: allocate_sched" (the kind of numba issue #2439). test_compiled_afresh.py.
numba.get_num_threads()

# ---- indices into the parameter vector `prm` (float64) -------------------------------------
P_DT = 0
P_RMIN = 1
P_RMAX = 2
P_SPRING = 3
P_DAMPING = 4
P_SHEAR = 5
P_OBSTACLE_SPRING = 6
P_ATTRACTION = 7
P_CLAMP_FORCE = 8
P_CLAMP_GAP = 9
P_BLEND_GAP = 10
P_CUTOFF = 11
P_FRICTION = 12  # mu x g: sliding deceleration
P_STATIC = 13  # force a particle at rest resists
P_REST_SPEED = 14
P_MAX_SPEED = 15
P_TORQUE = 16
P_CONSTRAINED = 17
P_CONTRACTION = 18
P_HALF_WIDTH = 19
P_SKIN = 20
P_LIST_RADIUS = 21
P_TOUCH_GAP = 22
PARAM_COUNT = 23

# ---- rows ----------------------------------------------------------------------------------
B_R = 0
B_FR = 1
B_FA = 2
B_MAG = 3
B_FX = 4
B_FY = 5
BODY_ROWS = 6

F_KIND = 0
F_ACTING = 1
F_JOINED = 2
F_ALIVE = 3
F_HELD = 4
FLAG_ROWS = 5

MEMBER = 0
FREE = 1
DETACHED = 2

# Passive objects: one row per object.
O_X = 0
O_Y = 1
O_VX = 2
O_VY = 3
O_R = 4
O_INV_MASS = 5
O_FRICTION = 6  # its sliding deceleration (mu x friction factor x g x mass factor)
O_STATIC = 7  # force it resists at rest (static_factor x that x mass)
O_MAG = 8
OBJECT_COLS = 9

# Per-chunk reduction of what particles do to object m: fx, fy.
ACC_COLS = 2

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
ByteArray = npt.NDArray[np.uint8]
ListArray = npt.NDArray[np.int32]

# Pair arithmetic may be reassociated and contracted (FMA); nothing in it tests for NaN. Only
# the one-at-a-time pair pass of small swarms (_pairs_each) and the published stale grid use it.
# The block pair pass of large swarms (_pairs, _pairs_cells and what they call) is plain IEEE
# arithmetic: with fast-math it came out of a fresh compilation differently optimised than out
# of numba's cache, so a seeded 3,000-particle swarm took a different path the first time it
# ran on a machine than every time after (last bits at step 5, metres after 500 steps). Plain
# arithmetic measured as fast (200,000 particles, boiling: 105-115 ns a particle-step on one
# thread either way). Small swarms came out the same both ways (500 and 1,500 particles; tests
# pin their paths). test_compiled_afresh.py guards it.
_FAST = {"contract", "arcp", "nsz", "reassoc"}


# ---- the laws --------------------------------------------------------------------------------


@numba.njit(cache=True, inline="always", fastmath=_FAST)
def _magnet_law(
    gap: float, strength: float, low: float, clamp_gap: float, blend_gap: float, a: float
) -> float:
    """Magnet pull (N) across a gap (m), scaled by strength (the product of the two bodies'
    factors): the clamp `low` below the clamp gap, a linear blend up to the blend gap, A / gap^2.
    Branch-free (each piece computed, one chosen), so that a loop of pairs vectorises."""
    top = a / (blend_gap * blend_gap)
    clamp = low * strength
    blend = strength * (low + (gap - clamp_gap) / (blend_gap - clamp_gap) * (top - low))
    far_gap = max(gap, blend_gap)
    far = strength * a / (far_gap * far_gap)
    return clamp if gap < clamp_gap else (blend if gap < blend_gap else far)


@numba.njit(cache=True, inline="always", fastmath=_FAST)
def _magnet(gap: float, strength: float, prm: FloatArray) -> float:
    """_magnet_law with the run's parameters."""
    return _magnet_law(
        gap, strength, prm[P_CLAMP_FORCE], prm[P_CLAMP_GAP], prm[P_BLEND_GAP], prm[P_ATTRACTION]
    )


@numba.njit(cache=True, inline="always", fastmath=_FAST)
def _contact_law(
    nx: float, ny: float, overlap: float, spring: float, damping: float, shear: float,
    dvx: float, dvy: float,
) -> tuple[float, float]:  # fmt: skip
    """Force on the first body: spring along -n, dashpot on the whole relative velocity (second
    minus first), shear on its tangential part."""
    vn = dvx * nx + dvy * ny
    fx = -spring * overlap * nx + damping * dvx + shear * (dvx - vn * nx)
    fy = -spring * overlap * ny + damping * dvy + shear * (dvy - vn * ny)
    return fx, fy


@numba.njit(cache=True, inline="always", fastmath=_FAST)
def _contact(
    nx: float, ny: float, overlap: float, spring: float, dvx: float, dvy: float, prm: FloatArray
) -> tuple[float, float]:
    """_contact_law with the dashpot and shear of the run's parameters."""
    return _contact_law(nx, ny, overlap, spring, prm[P_DAMPING], prm[P_SHEAR], dvx, dvy)


@numba.njit(cache=True, inline="always")
def _servo(r: float, target: float, fr: float, fa: float, prm: FloatArray) -> float:
    """The published servo with its stall limit: the new radius for a commanded one."""
    r_min = prm[P_RMIN]
    r_max = prm[P_RMAX]
    dt = prm[P_DT]
    target = min(max(target, r_min), r_max)
    dr1 = target - r
    if dr1 > 0.0:
        c = prm[P_TORQUE]
        speed = prm[P_MAX_SPEED] * r_max
        torque = min(dr1 * c * r / (speed * dt), c)
        dr = speed / c * (torque / r - fr) * dt if torque / r > fr else 0.0
    elif prm[P_CONSTRAINED] != 0.0:
        cc = prm[P_CONTRACTION]
        dr = (cc * dr1 + fa * r) / cc if -cc * dr1 > fa * r else 0.0
        dr = max(dr, -r_max * dt)
    else:
        dr = dr1
    return min(max(r + dr, r_min), r_max)


@numba.njit(cache=True, inline="always")
def _wall_push(
    nx: float, ny: float, depth: float, vx: float, vy: float, prm: FloatArray
) -> tuple[float, float]:
    """Force of one obstacle on a disc it cuts into by `depth` along the outward normal n:
    2k x depth, with damping and shear against the disc's own velocity."""
    vn = -vx * nx - vy * ny
    spring = prm[P_SPRING] * prm[P_OBSTACLE_SPRING]
    fx = spring * depth * nx - prm[P_DAMPING] * vx + prm[P_SHEAR] * (-vx - vn * nx)
    fy = spring * depth * ny - prm[P_DAMPING] * vy + prm[P_SHEAR] * (-vy - vn * ny)
    return fx, fy


@numba.njit(cache=True, inline="always")
def _obstacle_force(
    x: float, y: float, r: float, vx: float, vy: float, rects: FloatArray, circles: FloatArray,
    prm: FloatArray,
) -> tuple[float, float, float]:  # fmt: skip
    """Force of every obstacle a disc overlaps, each on its own (as the published code adds
    them), and the sum of their magnitudes for the contact-force sum. A rectangle pushes out the
    shortest way: off the nearest face, or radially off a corner."""
    fx = 0.0
    fy = 0.0
    total = 0.0
    for o in range(rects.shape[0]):
        x1 = rects[o, 0]
        x2 = rects[o, 1]
        y1 = rects[o, 2]
        y2 = rects[o, 3]
        if x <= x1 - r or x >= x2 + r or y <= y1 - r or y >= y2 + r:
            continue
        dx = x - min(max(x, x1), x2)
        dy = y - min(max(y, y1), y2)
        d2 = dx * dx + dy * dy
        if d2 > 0.0:
            if d2 >= r * r:
                continue
            d = math.sqrt(d2)
            nx = dx / d
            ny = dy / d
            depth = r - d
        else:
            # Centre inside: out through the nearest face.
            left = x - x1
            right = x2 - x
            below = y - y1
            above = y2 - y
            least = min(min(left, right), min(below, above))
            depth = least + r
            nx = -1.0 if least == left else (1.0 if least == right else 0.0)
            ny = 0.0 if nx != 0.0 else (-1.0 if least == below else 1.0)
        px, py = _wall_push(nx, ny, depth, vx, vy, prm)
        fx += px
        fy += py
        total += math.sqrt(px * px + py * py)
    for o in range(circles.shape[0]):
        dx = x - circles[o, 0]
        dy = y - circles[o, 1]
        reach = r + circles[o, 2]
        d2 = dx * dx + dy * dy
        if d2 < reach * reach and d2 > 0.0:
            d = math.sqrt(d2)
            px, py = _wall_push(dx / d, dy / d, reach - d, vx, vy, prm)
            fx += px
            fy += py
            total += math.sqrt(px * px + py * py)
    return fx, fy, total


@numba.njit(cache=True, inline="always")
def _friction(
    vx: float, vy: float, fx: float, fy: float, inv_mass: float, slide: float, static: float,
    prm: FloatArray,
) -> tuple[float, float]:  # fmt: skip
    """The new velocity: static friction holds a body at rest below its threshold, then
    v += F / m dt, then sliding friction takes slide x dt off the speed (to zero at most)."""
    dt = prm[P_DT]
    rest = prm[P_REST_SPEED]
    if vx * vx + vy * vy < rest * rest and fx * fx + fy * fy < static * static:
        fx = 0.0
        fy = 0.0
    vx += fx * inv_mass * dt
    vy += fy * inv_mass * dt
    speed = math.sqrt(vx * vx + vy * vy)
    slow = slide * dt
    if speed < slow:
        return 0.0, 0.0
    scale = 1.0 - slow / speed
    return vx * scale, vy * scale


# ---- the passes of a step (each over particles lo..hi) -----------------------------------------


@numba.njit(cache=True, inline="always")
def _slot(i: int) -> int:
    """A particle's slot as an unsigned index. Numba checks every signed index for a negative
    value (to count it from the end), on every access: a loop over range(lo, hi) cannot tell it
    never is. An unsigned index it takes as is (a plain copy loop: 0.64 -> 0.33 ns an element).
    Only for indexing: uint64 mixed with int64 arithmetic gives float64 in numba."""
    return numba.uint64(i)  # type: ignore[return-value]


@numba.njit(cache=True)
def _targets_here(lo: int, hi: int, row: FloatArray, ext: IntArray, here: FloatArray) -> None:
    """Slots lo..hi's commanded radii (row: the caller's order) in slot order. In a loop of its
    own: the reads go all over a row as long as the swarm (1.6 MB at 200,000 particles), and
    inside the kinematics loop they cost 12 ns a particle on one thread (the loads wait behind
    the servo's work); here many are in flight at once."""
    for signed in range(lo, hi):
        i = _slot(signed)
        here[i] = row[_slot(ext[i])]


@numba.njit(cache=True)
def _kinematics(
    lo: int, hi: int, here: FloatArray, pos: FloatArray, ref: FloatArray, vel: FloatArray,
    body: FloatArray, flags: ByteArray, prm: FloatArray,
) -> float:  # fmt: skip
    """First pass: joins from the last step take effect, the servo moves the radius toward
    here[i] (from the last step's force sums, which are then cleared), positions advance by the
    old velocity and walls reflect it. From here to the last pass nothing writes the velocity
    (the force passes read it as the step's old velocity), and the force rows are zero (the last
    pass cleared them as it read them: here their cache lines would be fetched only to be zeroed).
    Returns the largest squared displacement since the last list build."""
    dt = prm[P_DT]
    wall = prm[P_HALF_WIDTH]
    worst = 0.0
    for signed in range(lo, hi):
        i = _slot(signed)
        if flags[F_JOINED, i]:
            flags[F_JOINED, i] = 0
            flags[F_KIND, i] = MEMBER
            flags[F_ACTING, i] = flags[F_ALIVE, i] & (1 - flags[F_HELD, i])
        r = body[B_R, i]
        if flags[F_ACTING, i]:
            target = here[i]
            if not math.isnan(target):  # NaN: the controller lets the servo hold
                r = _servo(r, target, body[B_FR, i], body[B_FA, i], prm)
                body[B_R, i] = r
        body[B_FR, i] = 0.0
        body[B_FA, i] = 0.0
        x = pos[0, i] + vel[0, i] * dt
        y = pos[1, i] + vel[1, i] * dt
        if x > wall - r:
            x = wall - r
            vel[0, i] = -vel[0, i]
        elif x < r - wall:
            x = r - wall
            vel[0, i] = -vel[0, i]
        if y > wall - r:
            y = wall - r
            vel[1, i] = -vel[1, i]
        elif y < r - wall:
            y = r - wall
            vel[1, i] = -vel[1, i]
        pos[0, i] = x
        pos[1, i] = y
        dx = x - ref[0, i]
        dy = y - ref[1, i]
        worst = max(worst, dx * dx + dy * dy)
    return worst


@numba.njit(cache=True, inline="always", fastmath=_FAST)
def _law(
    j: int, dx: float, dy: float, d2: float, c: float, vxi: float, vyi: float, magi: float,
    vel: FloatArray, body: FloatArray, prm: FloatArray,
) -> tuple[float, float, float, float, bool]:  # fmt: skip
    """Force on i from j (rel = pj - pi at squared distance d2 > 0, contact distance c), for a
    pair within reach: contact (spring, dashpot, shear) when they overlap, else the magnets.
    Returns f, its contact and attraction magnitudes, and whether they touch (overlap, or a gap
    below the magnets' lock)."""
    d = math.sqrt(d2)
    nx = dx / d
    ny = dy / d
    if d < c:
        px, py = _contact(nx, ny, c - d, prm[P_SPRING], vel[0, j] - vxi, vel[1, j] - vyi, prm)
        return px, py, math.sqrt(px * px + py * py), 0.0, True
    strength = magi * body[B_MAG, j]
    if strength > 0.0:
        attract = _magnet(d - c, strength, prm)
        return attract * nx, attract * ny, 0.0, attract, d - c < prm[P_TOUCH_GAP]
    return 0.0, 0.0, 0.0, 0.0, d - c < prm[P_TOUCH_GAP]


@numba.njit(cache=True, inline="always")
def _join(i: int, j: int, kind_i: int, flags: ByteArray) -> None:
    """A free particle touching a member is marked to join the robot."""
    kind_j = flags[F_KIND, j]
    if kind_i == FREE and kind_j == MEMBER:
        flags[F_JOINED, i] = 1
    elif kind_i == MEMBER and kind_j == FREE:
        flags[F_JOINED, j] = 1


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


@numba.njit(cache=True)
def _pairs(
    lo: int, hi: int, pos: FloatArray, vel: FloatArray, body: FloatArray, flags: ByteArray,
    nbr: ListArray, ncount: npt.NDArray[np.int32], pair_index: IntArray, pair_values: FloatArray,
    prm: FloatArray,
) -> None:  # fmt: skip
    """Second pass: every listed pair (i in lo..hi, j > i) within reach once, from the new
    positions and old velocities; i gets f and j gets -f, both get |f| in their contact or
    attraction sum. The pairs within reach are picked out first (_pick) into the scratch
    pair_index (PAIR_INDEX_ROWS, 2 block), then evaluated a block at a time (_pair_block, with
    pair_values (PAIR_VALUE_ROWS, block))."""
    cutoff = prm[P_CUTOFF]
    block = pair_values.shape[1]
    count = 0
    for i in range(lo, hi):
        if ncount[i] > block:
            count = _pick_each(
                i, nbr[i, : ncount[i]].astype(np.int64), count, pair_index, pair_values, pos,
                vel, body, flags, prm,
            )  # fmt: skip
            continue
        xi = pos[0, i]
        yi = pos[1, i]
        ri = body[B_R, i]
        for k in range(ncount[i]):
            count = _pick(i, nbr[i, k], xi, yi, ri, cutoff, count, pair_index, pos, body)
        if count >= block:
            count = _block_full(count, pair_index, pair_values, pos, vel, body, flags, prm)
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
    cutoff = prm[P_CUTOFF]
    block = pair_values.shape[1]
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
        i = members[_slot(p)]
        if end - p - 1 + above_hi - above_lo > block:
            runs = np.concatenate((members[p + 1 : end], members[above_lo:above_hi]))
            count = _pick_each(i, runs, count, pair_index, pair_values, pos, vel, body, flags, prm)
            continue
        u = _slot(i)
        xi = pos[0, u]
        yi = pos[1, u]
        ri = body[B_R, u]
        for q in range(p + 1, end):
            count = _pick(i, members[_slot(q)], xi, yi, ri, cutoff, count, pair_index, pos, body)
        for q in range(above_lo, above_hi):
            count = _pick(i, members[_slot(q)], xi, yi, ri, cutoff, count, pair_index, pos, body)
        if count >= block:
            count = _block_full(count, pair_index, pair_values, pos, vel, body, flags, prm)
    _pair_block(count, pair_index, pair_values, pos, vel, body, flags, prm)


@numba.njit(cache=True)
def _settle(
    lo: int, hi: int, pos: FloatArray, vel: FloatArray, body: FloatArray,
    rects: FloatArray, circles: FloatArray, objects: FloatArray, acc: FloatArray,
    prm: FloatArray,
) -> None:  # fmt: skip
    """Third pass: obstacles and passive objects act on particles lo..hi (what the particles do
    to object m goes to acc[m]), then every particle's velocity with ground friction; the
    force rows are cleared for the next step."""
    spring = prm[P_SPRING]
    cutoff = prm[P_CUTOFF]
    slide = prm[P_FRICTION]
    static = prm[P_STATIC]
    acc[:, :] = 0.0
    check_obstacles = rects.shape[0] + circles.shape[0] > 0
    for signed in range(lo, hi):
        i = _slot(signed)
        xi = pos[0, i]
        yi = pos[1, i]
        vxi = vel[0, i]
        vyi = vel[1, i]
        ri = body[B_R, i]
        fx = body[B_FX, i]
        fy = body[B_FY, i]
        body[B_FX, i] = 0.0
        body[B_FY, i] = 0.0
        if check_obstacles:
            px, py, size = _obstacle_force(xi, yi, ri, vxi, vyi, rects, circles, prm)
            fx += px
            fy += py
            body[B_FR, i] += size
        for m in range(objects.shape[0]):
            dx = objects[m, O_X] - xi
            dy = objects[m, O_Y] - yi
            c = ri + objects[m, O_R]
            d2 = dx * dx + dy * dy
            reach = c + cutoff
            if d2 >= reach * reach or d2 == 0.0:
                continue
            d = math.sqrt(d2)
            nx = dx / d
            ny = dy / d
            if d < c:
                dvx = objects[m, O_VX] - vxi
                dvy = objects[m, O_VY] - vyi
                px, py = _contact(nx, ny, c - d, spring, dvx, dvy, prm)
                body[B_FR, i] += math.sqrt(px * px + py * py)
            else:
                strength = body[B_MAG, i] * objects[m, O_MAG]
                if strength <= 0.0:
                    continue
                pull = _magnet(d - c, strength, prm)
                px = pull * nx
                py = pull * ny
                body[B_FA, i] += pull
            fx += px
            fy += py
            acc[m, 0] -= px
            acc[m, 1] -= py
        vel[0, i], vel[1, i] = _friction(vxi, vyi, fx, fy, 1.0, slide, static, prm)


@numba.njit(cache=True)
def _objects_move(objects: FloatArray, prm: FloatArray) -> None:
    """Passive objects' positions from their velocities, reflected by the walls."""
    dt = prm[P_DT]
    wall = prm[P_HALF_WIDTH]
    for m in range(objects.shape[0]):
        r = objects[m, O_R]
        for axis, speed in ((O_X, O_VX), (O_Y, O_VY)):
            value = objects[m, axis] + objects[m, speed] * dt
            if value > wall - r:
                value = wall - r
                objects[m, speed] = -objects[m, speed]
            elif value < r - wall:
                value = r - wall
                objects[m, speed] = -objects[m, speed]
            objects[m, axis] = value


@numba.njit(cache=True)
def _objects_settle(
    objects: FloatArray, acc: FloatArray, rects: FloatArray, circles: FloatArray, prm: FloatArray
) -> None:
    """Passive objects' velocities from the particles' pushes (acc, summed over chunks in
    order), each other, obstacles and their own friction."""
    count = objects.shape[0]
    fxs = np.zeros(count)
    fys = np.zeros(count)
    for m in range(count):
        for c in range(acc.shape[0]):
            fxs[m] += acc[c, m, 0]
            fys[m] += acc[c, m, 1]
        xm = objects[m, O_X]
        ym = objects[m, O_Y]
        vxm = objects[m, O_VX]
        vym = objects[m, O_VY]
        rm = objects[m, O_R]
        for n in range(count):
            if n == m:
                continue
            dx = objects[n, O_X] - xm
            dy = objects[n, O_Y] - ym
            c = rm + objects[n, O_R]
            d = math.sqrt(dx * dx + dy * dy)
            if d == 0.0 or d >= c + prm[P_CUTOFF]:
                continue
            nx = dx / d
            ny = dy / d
            if d < c:
                dvx = objects[n, O_VX] - vxm
                dvy = objects[n, O_VY] - vym
                px, py = _contact(nx, ny, c - d, prm[P_SPRING], dvx, dvy, prm)
            else:
                strength = objects[m, O_MAG] * objects[n, O_MAG]
                pull = _magnet(d - c, strength, prm) if strength > 0.0 else 0.0
                px = pull * nx
                py = pull * ny
            fxs[m] += px
            fys[m] += py
        px, py, _ = _obstacle_force(xm, ym, rm, vxm, vym, rects, circles, prm)
        fxs[m] += px
        fys[m] += py
    for m in range(count):
        vx, vy = _friction(
            objects[m, O_VX], objects[m, O_VY], fxs[m], fys[m], objects[m, O_INV_MASS],
            objects[m, O_FRICTION], objects[m, O_STATIC], prm,
        )  # fmt: skip
        objects[m, O_VX] = vx
        objects[m, O_VY] = vy


# ---- the published code's stale grid (NeighbourSearch.PUBLISHED_STALE_GRID) ---------------------

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


# ---- neighbour lists ---------------------------------------------------------------------------


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


SORT_EVERY = 12
"""A large swarm that rebuilds its lists at every step (a boiling one) puts its particles in
cell order at every SORT_EVERY-th build only, and reaches them through the grid's order in
between: the re-ordering moves every row of every particle, 17 of 60 ns a particle-step on two
threads at 200,000 particles, while in between the particles stay close to their places. 8-16
measured alike (a boiling step 20-25 % quicker on two threads, 10-25 % on one; README, "Re-
ordering at every 12th build"); 32 and 64 lose part of it as the order drifts. (numba compiles
this value into the kernels and its cache does not see it change: clear the cache when trying
others.)"""

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


BODY_KEPT = B_FX
"""Rows of `body` that carry over from step to step (r, the force sums the servo reads, the
magnet factor); force x and y are a step's own, zero between steps, so a re-ordering skips them."""


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


@numba.njit(cache=True, inline="always")
def _gather(source: npt.NDArray[np.generic], order: IntArray, out: npt.NDArray[np.generic]) -> None:
    """out[q] = source[order[q]]."""
    for q in range(out.shape[0]):
        out[q] = source[_slot(order[q])]


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


# ---- the step loop ----------------------------------------------------------------------------


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
