"""The world's compiled inner loops (numba): servo, motion, contacts, magnets, friction, lists.

Memory layout (structure of arrays, rows of 2-D arrays, particles in *internal* order): the
particles are kept sorted by neighbour-grid cell so that a particle's neighbours sit close to it
in memory; `ext[i]` is the caller's index of internal slot i. Passive objects (few, possibly
huge discs) live in their own arrays and meet every particle directly, outside the lists.

    pos   float64 (2, N)  x, y             ref  float64 (2, N)  x, y at the last list build
    vel   F       (2, N)  vx, vy           vel2 F (2, N)        the next step's (double buffer)
    body  F       (4, N)  r, contact-force sum, attraction sum (both from the last force pass),
                          magnet factor (1, or 0 for a detached particle)
    flags uint8   (5, N)  kind (MEMBER / FREE / DETACHED), acting, joined, alive, held
    nbr   int32   (N, M)  neighbour lists (full: j in i's list and i in j's), counts in ncount

F is float64 or float32 (the World's `precision`). Every pass works on a contiguous chunk of
particles and writes only that chunk (plus one row of a per-chunk reduction), so chunks run in
parallel without atomics and results do not depend on the number of threads.
"""

from __future__ import annotations

import math

import numba
import numpy as np
import numpy.typing as npt

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
BODY_ROWS = 4

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

# Per-chunk reduction of what particles do to object m: fx, fy, contact sum, attraction sum.
ACC_COLS = 4

# Status codes of advance().
DONE = 0
LIST_FULL = 1

FloatArray = npt.NDArray[np.float64]


@numba.njit(cache=True, inline="always")
def _magnet(gap: float, strength: float, prm: FloatArray) -> float:
    """Magnet pull (N) across a gap (m) with A = strength x attraction: the clamp below the clamp
    gap, a linear blend up to the blend gap, A / gap^2 beyond."""
    clamp_gap = prm[P_CLAMP_GAP]
    blend_gap = prm[P_BLEND_GAP]
    a = prm[P_ATTRACTION] * strength
    if gap < clamp_gap:
        return prm[P_CLAMP_FORCE] * strength
    if gap < blend_gap:
        top = a / (blend_gap * blend_gap)
        low = prm[P_CLAMP_FORCE] * strength
        return low + (gap - clamp_gap) / (blend_gap - clamp_gap) * (top - low)
    return a / (gap * gap)


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


@numba.njit(cache=True)
def _kinematics(
    lo: int,
    hi: int,
    step: int,
    targets: FloatArray,
    ext: npt.NDArray[np.int64],
    pos: FloatArray,
    ref: FloatArray,
    vel: FloatArray,
    vel_old: FloatArray,
    body: FloatArray,
    flags: npt.NDArray[np.uint8],
    prm: FloatArray,
) -> float:
    """First half of a step for particles lo..hi: joins from the last step take effect, the
    servo moves the radius, positions advance by the old velocity, walls reflect, and the
    velocity is kept in vel_old for the force pass (which writes the new one into vel). Returns
    the largest squared displacement since the last list build."""
    dt = prm[P_DT]
    wall = prm[P_HALF_WIDTH]
    worst = 0.0
    for i in range(lo, hi):
        if flags[F_JOINED, i]:
            flags[F_JOINED, i] = 0
            flags[F_KIND, i] = MEMBER
            flags[F_ACTING, i] = flags[F_ALIVE, i] & (1 - flags[F_HELD, i])
        r = body[B_R, i]
        if flags[F_ACTING, i]:
            target = targets[step, ext[i]]
            if not math.isnan(target):  # NaN: the controller lets the servo hold
                r = _servo(r, target, body[B_FR, i], body[B_FA, i], prm)
                body[B_R, i] = r
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
        vel_old[0, i] = vel[0, i]
        vel_old[1, i] = vel[1, i]
        dx = x - ref[0, i]
        dy = y - ref[1, i]
        worst = max(worst, dx * dx + dy * dy)
    return worst


@numba.njit(cache=True, inline="always")
def _contact(
    nx: float,
    ny: float,
    overlap: float,
    spring: float,
    dvx: float,
    dvy: float,
    prm: FloatArray,
) -> tuple[float, float]:
    """Spring along -n, dashpot on the whole relative velocity, shear on its tangential part."""
    vn = dvx * nx + dvy * ny
    fx = -spring * overlap * nx + prm[P_DAMPING] * dvx + prm[P_SHEAR] * (dvx - vn * nx)
    fy = -spring * overlap * ny + prm[P_DAMPING] * dvy + prm[P_SHEAR] * (dvy - vn * ny)
    return fx, fy


@numba.njit(cache=True, inline="always")
def _obstacle_push(
    x: float, y: float, r: float, rects: FloatArray, circles: FloatArray
) -> tuple[float, float, float]:
    """The deepest obstacle overlap of a disc: unit normal (out of the obstacle) and depth
    summed per obstacle as (nx * depth, ny * depth, total depth); the caller applies the spring."""
    px = 0.0
    py = 0.0
    total = 0.0
    for o in range(rects.shape[0]):
        x1 = rects[o, 0]
        x2 = rects[o, 1]
        y1 = rects[o, 2]
        y2 = rects[o, 3]
        if x < x1 - r or x > x2 + r or y < y1 - r or y > y2 + r:
            continue
        qx = min(max(x, x1), x2)
        qy = min(max(y, y1), y2)
        dx = x - qx
        dy = y - qy
        d2 = dx * dx + dy * dy
        if d2 > 0.0:
            d = math.sqrt(d2)
            if d < r:
                depth = r - d
                px += dx / d * depth
                py += dy / d * depth
                total += depth
        else:
            # Centre inside: out through the nearest face, the shortest way.
            left = x - x1
            right = x2 - x
            below = y - y1
            above = y2 - y
            least = min(min(left, right), min(below, above))
            depth = least + r
            if least == left:
                px -= depth
            elif least == right:
                px += depth
            elif least == below:
                py -= depth
            else:
                py += depth
            total += depth
    for o in range(circles.shape[0]):
        dx = x - circles[o, 0]
        dy = y - circles[o, 1]
        reach = r + circles[o, 2]
        d2 = dx * dx + dy * dy
        if d2 < reach * reach and d2 > 0.0:
            d = math.sqrt(d2)
            depth = reach - d
            px += dx / d * depth
            py += dy / d * depth
            total += depth
    return px, py, total


@numba.njit(cache=True)
def _forces(
    lo: int,
    hi: int,
    pos: FloatArray,
    vel: FloatArray,
    vel2: FloatArray,
    body: FloatArray,
    flags: npt.NDArray[np.uint8],
    nbr: npt.NDArray[np.int32],
    ncount: npt.NDArray[np.int32],
    rects: FloatArray,
    circles: FloatArray,
    objects: FloatArray,
    acc: FloatArray,
    prm: FloatArray,
) -> None:
    """Second half of a step for particles lo..hi: forces from the new positions and the old
    velocities (pairs, obstacles, passive objects), then the velocity with ground friction into
    vel2; the contact and attraction sums for the next servo update. What the particles do to
    each passive object is added to acc (this chunk's row)."""
    dt = prm[P_DT]
    spring = prm[P_SPRING]
    cutoff = prm[P_CUTOFF]
    touch = prm[P_TOUCH_GAP]
    friction_dv = prm[P_FRICTION] * dt
    static = prm[P_STATIC]
    rest = prm[P_REST_SPEED]
    wall_spring = prm[P_SPRING] * prm[P_OBSTACLE_SPRING]
    damping = prm[P_DAMPING]
    shear = prm[P_SHEAR]
    acc[:, :] = 0.0
    for i in range(lo, hi):
        xi = pos[0, i]
        yi = pos[1, i]
        vxi = vel[0, i]
        vyi = vel[1, i]
        ri = body[B_R, i]
        magi = body[B_MAG, i]
        free = flags[F_KIND, i] == FREE
        joined = False
        fx = 0.0
        fy = 0.0
        f_contact = 0.0
        f_attract = 0.0
        for k in range(ncount[i]):
            j = nbr[i, k]
            dx = pos[0, j] - xi
            dy = pos[1, j] - yi
            c = ri + body[B_R, j]
            d2 = dx * dx + dy * dy
            reach = c + cutoff
            if d2 >= reach * reach or d2 == 0.0:
                continue
            d = math.sqrt(d2)
            nx = dx / d
            ny = dy / d
            if d < c:
                px, py = _contact(nx, ny, c - d, spring, vel[0, j] - vxi, vel[1, j] - vyi, prm)
                fx += px
                fy += py
                f_contact += math.sqrt(px * px + py * py)
                if free and flags[F_KIND, j] == MEMBER:
                    joined = True
            else:
                gap = d - c
                strength = magi * body[B_MAG, j]
                if strength > 0.0:
                    pull = _magnet(gap, strength, prm)
                    fx += pull * nx
                    fy += pull * ny
                    f_attract += pull
                if free and gap < touch and flags[F_KIND, j] == MEMBER:
                    joined = True
        # Fixed obstacles push with twice the spring, and damp the particle's own velocity.
        ox, oy, depth = _obstacle_push(xi, yi, ri, rects, circles)
        if depth > 0.0:
            norm = math.sqrt(ox * ox + oy * oy)
            nx = ox / norm if norm > 0.0 else 0.0
            ny = oy / norm if norm > 0.0 else 0.0
            vn = -vxi * nx - vyi * ny
            px = wall_spring * ox - damping * vxi + shear * (-vxi - vn * nx)
            py = wall_spring * oy - damping * vyi + shear * (-vyi - vn * ny)
            fx += px
            fy += py
            f_contact += math.sqrt(px * px + py * py)
        # Passive objects: the same pair laws, their magnets scaled by their factor.
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
                fx += px
                fy += py
                size = math.sqrt(px * px + py * py)
                f_contact += size
                acc[m, 0] -= px
                acc[m, 1] -= py
                acc[m, 2] += size
            else:
                strength = magi * objects[m, O_MAG]
                if strength > 0.0:
                    pull = _magnet(d - c, strength, prm)
                    fx += pull * nx
                    fy += pull * ny
                    f_attract += pull
                    acc[m, 0] -= pull * nx
                    acc[m, 1] -= pull * ny
                    acc[m, 3] += pull
        body[B_FR, i] = f_contact
        body[B_FA, i] = f_attract
        if joined:
            flags[F_JOINED, i] = 1
        # Ground friction: static below the threshold at rest, then sliding deceleration.
        if vxi * vxi + vyi * vyi < rest * rest and fx * fx + fy * fy < static * static:
            fx = 0.0
            fy = 0.0
        vx = vxi + fx * dt
        vy = vyi + fy * dt
        speed = math.sqrt(vx * vx + vy * vy)
        if speed < friction_dv:
            vx = 0.0
            vy = 0.0
        else:
            scale = 1.0 - friction_dv / speed
            vx *= scale
            vy *= scale
        vel2[0, i] = vx
        vel2[1, i] = vy


@numba.njit(cache=True)
def _objects_step(
    objects: FloatArray,
    acc: FloatArray,
    chunks: int,
    rects: FloatArray,
    circles: FloatArray,
    prm: FloatArray,
) -> None:
    """Passive objects' velocities from the particles' pushes (acc), each other, obstacles and
    friction; called after the particles' force pass, positions already advanced."""
    dt = prm[P_DT]
    count = objects.shape[0]
    fxs = np.zeros(count)
    fys = np.zeros(count)
    for m in range(count):
        for c in range(chunks):
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
        ox, oy, depth = _obstacle_push(xm, ym, rm, rects, circles)
        if depth > 0.0:
            norm = math.sqrt(ox * ox + oy * oy)
            nx = ox / norm
            ny = oy / norm
            vn = -vxm * nx - vym * ny
            k2 = prm[P_SPRING] * prm[P_OBSTACLE_SPRING]
            fxs[m] += k2 * ox - prm[P_DAMPING] * vxm + prm[P_SHEAR] * (-vxm - vn * nx)
            fys[m] += k2 * oy - prm[P_DAMPING] * vym + prm[P_SHEAR] * (-vym - vn * ny)
    for m in range(count):
        vx = objects[m, O_VX]
        vy = objects[m, O_VY]
        fx = fxs[m]
        fy = fys[m]
        rest = prm[P_REST_SPEED]
        static = objects[m, O_STATIC]
        if vx * vx + vy * vy < rest * rest and fx * fx + fy * fy < static * static:
            fx = 0.0
            fy = 0.0
        vx += fx * objects[m, O_INV_MASS] * dt
        vy += fy * objects[m, O_INV_MASS] * dt
        speed = math.sqrt(vx * vx + vy * vy)
        slow = objects[m, O_FRICTION] * dt
        if speed < slow:
            vx = 0.0
            vy = 0.0
        else:
            vx *= 1.0 - slow / speed
            vy *= 1.0 - slow / speed
        objects[m, O_VX] = vx
        objects[m, O_VY] = vy


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


# ---- neighbour lists ------------------------------------------------------------------------


@numba.njit(cache=True)
def _grid(
    pos: FloatArray, radius: float
) -> tuple[
    float,
    float,
    float,
    int,
    int,
    npt.NDArray[np.int64],
    npt.NDArray[np.int64],
    npt.NDArray[np.int64],
]:
    """Bins particles into square cells at least `radius` wide over their bounding box (cells are
    widened so that there are at most about 2 per particle); returns the grid's origin, cell size,
    shape, each particle's cell, and the particles cell by cell (start offsets and members, in
    index order within a cell: a stable counting sort)."""
    n = pos.shape[1]
    x0 = pos[0, 0]
    x1 = x0
    y0 = pos[1, 0]
    y1 = y0
    for i in range(n):
        x0 = min(x0, pos[0, i])
        x1 = max(x1, pos[0, i])
        y0 = min(y0, pos[1, i])
        y1 = max(y1, pos[1, i])
    width = x1 - x0 + radius
    height = y1 - y0 + radius
    size = max(radius, math.sqrt(width * height / (2.0 * n + 64.0)))
    ncx = int(width / size) + 1
    ncy = int(height / size) + 1
    cells = np.empty(n, dtype=np.int64)
    start = np.zeros(ncx * ncy + 1, dtype=np.int64)
    for i in range(n):
        c = int((pos[1, i] - y0) / size) * ncx + int((pos[0, i] - x0) / size)
        cells[i] = c
        start[c + 1] += 1
    for c in range(ncx * ncy):
        start[c + 1] += start[c]
    fill = start[:-1].copy()
    members = np.empty(n, dtype=np.int64)
    for i in range(n):
        members[fill[cells[i]]] = i
        fill[cells[i]] += 1
    return x0, y0, size, ncx, ncy, cells, start, members


@numba.njit(cache=True)
def _fill_lists(
    lo: int,
    hi: int,
    pos: FloatArray,
    cells: npt.NDArray[np.int64],
    start: npt.NDArray[np.int64],
    members: npt.NDArray[np.int64],
    ncx: int,
    ncy: int,
    radius: float,
    nbr: npt.NDArray[np.int32],
    ncount: npt.NDArray[np.int32],
) -> int:
    """Neighbour lists of particles lo..hi from the grid (3 x 3 cells); returns the longest list
    found, which may exceed nbr's width (then the lists are incomplete and must be redone)."""
    width = nbr.shape[1]
    longest = 0
    r2 = radius * radius
    for i in range(lo, hi):
        cx = cells[i] % ncx
        cy = cells[i] // ncx
        xi = pos[0, i]
        yi = pos[1, i]
        count = 0
        for gy in range(max(cy - 1, 0), min(cy + 2, ncy)):
            for gx in range(max(cx - 1, 0), min(cx + 2, ncx)):
                c = gy * ncx + gx
                for p in range(start[c], start[c + 1]):
                    j = members[p]
                    if j == i:
                        continue
                    dx = pos[0, j] - xi
                    dy = pos[1, j] - yi
                    if dx * dx + dy * dy < r2:
                        if count < width:
                            nbr[i, count] = j
                        count += 1
        ncount[i] = min(count, width)
        longest = max(longest, count)
    return longest


@numba.njit(cache=True)
def _permute_rows(rows: npt.NDArray, order: npt.NDArray[np.int64], lo: int, hi: int) -> None:
    """rows[:, lo:hi] = rows[:, order[lo:hi]] through a scratch copy of the whole array."""
    scratch = rows.copy()
    for r in range(rows.shape[0]):
        for p in range(lo, hi):
            rows[r, p] = scratch[r, order[p]]


@numba.njit(parallel=True, cache=True)
def _fill_chunks(
    bounds: npt.NDArray[np.int64],
    pos: FloatArray,
    cells: npt.NDArray[np.int64],
    start: npt.NDArray[np.int64],
    members: npt.NDArray[np.int64],
    ncx: int,
    ncy: int,
    radius: float,
    nbr: npt.NDArray[np.int32],
    ncount: npt.NDArray[np.int32],
) -> int:
    """_fill_lists over every chunk in parallel; the longest list found."""
    chunks = bounds.shape[0] - 1
    longest = np.zeros(chunks, dtype=np.int64)
    for c in numba.prange(chunks):
        longest[c] = _fill_lists(
            bounds[c], bounds[c + 1], pos, cells, start, members, ncx, ncy, radius, nbr, ncount
        )
    most = 0
    for c in range(chunks):
        most = max(most, longest[c])
    return most


@numba.njit(cache=True)
def build_lists(
    pos: FloatArray,
    ref: FloatArray,
    vel: FloatArray,
    vel_old: FloatArray,
    body: FloatArray,
    flags: npt.NDArray[np.uint8],
    ext: npt.NDArray[np.int64],
    nbr: npt.NDArray[np.int32],
    ncount: npt.NDArray[np.int32],
    bounds: npt.NDArray[np.int64],
    prm: FloatArray,
    sort: bool,
) -> npt.NDArray[np.int32]:
    """Rebuilds every neighbour list from the current positions, first putting the particles in
    grid-cell order when `sort` (every per-particle row and `ext` follow); the positions become
    the lists' reference. Returns the lists' array (a wider one if some list did not fit)."""
    radius = prm[P_LIST_RADIUS]
    chunks = bounds.shape[0] - 1
    n = pos.shape[1]
    _, _, _, ncx, ncy, cells, start, members = _grid(pos, radius)
    if sort:
        _permute_rows(pos, members, 0, n)
        _permute_rows(vel, members, 0, n)
        _permute_rows(vel_old, members, 0, n)
        _permute_rows(body, members, 0, n)
        _permute_rows(flags, members, 0, n)
        scratch = ext.copy()
        for p in range(n):
            ext[p] = scratch[members[p]]
        _, _, _, ncx, ncy, cells, start, members = _grid(pos, radius)
    for i in range(n):
        ref[0, i] = pos[0, i]
        ref[1, i] = pos[1, i]
    while True:
        if chunks == 1:
            need = _fill_lists(0, n, pos, cells, start, members, ncx, ncy, radius, nbr, ncount)
        else:
            need = _fill_chunks(bounds, pos, cells, start, members, ncx, ncy, radius, nbr, ncount)
        if need <= nbr.shape[1]:
            return nbr
        nbr = np.empty((n, need + 8), dtype=np.int32)


# ---- the step loop ----------------------------------------------------------------------------


@numba.njit(parallel=True, cache=True)
def _kinematics_chunks(
    bounds: npt.NDArray[np.int64],
    step: int,
    targets: FloatArray,
    ext: npt.NDArray[np.int64],
    pos: FloatArray,
    ref: FloatArray,
    vel: FloatArray,
    vel_old: FloatArray,
    body: FloatArray,
    flags: npt.NDArray[np.uint8],
    prm: FloatArray,
) -> float:
    """_kinematics over every chunk in parallel; the largest squared displacement."""
    chunks = bounds.shape[0] - 1
    worst = np.zeros(chunks)
    for c in numba.prange(chunks):
        worst[c] = _kinematics(
            bounds[c], bounds[c + 1], step, targets, ext, pos, ref, vel, vel_old, body, flags, prm
        )
    most = 0.0
    for c in range(chunks):
        most = max(most, worst[c])
    return most


@numba.njit(parallel=True, cache=True)
def _forces_chunks(
    bounds: npt.NDArray[np.int64],
    pos: FloatArray,
    vel_old: FloatArray,
    vel: FloatArray,
    body: FloatArray,
    flags: npt.NDArray[np.uint8],
    nbr: npt.NDArray[np.int32],
    ncount: npt.NDArray[np.int32],
    rects: FloatArray,
    circles: FloatArray,
    objects: FloatArray,
    acc: FloatArray,
    prm: FloatArray,
) -> None:
    """_forces over every chunk in parallel."""
    for c in numba.prange(bounds.shape[0] - 1):
        _forces(
            bounds[c], bounds[c + 1], pos, vel_old, vel, body, flags, nbr, ncount, rects,
            circles, objects, acc[c], prm,
        )  # fmt: skip


@numba.njit(cache=True)
def advance(
    steps: int,
    targets: FloatArray,
    ext: npt.NDArray[np.int64],
    pos: FloatArray,
    ref: FloatArray,
    vel: FloatArray,
    vel_old: FloatArray,
    body: FloatArray,
    flags: npt.NDArray[np.uint8],
    nbr: npt.NDArray[np.int32],
    ncount: npt.NDArray[np.int32],
    rects: FloatArray,
    circles: FloatArray,
    objects: FloatArray,
    acc: FloatArray,
    bounds: npt.NDArray[np.int64],
    prm: FloatArray,
) -> tuple[npt.NDArray[np.int32], int]:
    """Runs `steps` steps; step s commands the radii targets[s, ext[i]] (NaN: hold). One chunk
    runs inline (no parallel region to start), several in parallel. Returns the neighbour lists'
    array (possibly a new, wider one) and how many times the lists were rebuilt."""
    chunks = bounds.shape[0] - 1
    n = pos.shape[1]
    limit = 0.25 * prm[P_SKIN] * prm[P_SKIN]  # (skin / 2)^2
    rebuilds = 0
    for s in range(steps):
        if chunks == 1:
            moved = _kinematics(0, n, s, targets, ext, pos, ref, vel, vel_old, body, flags, prm)
        else:
            moved = _kinematics_chunks(
                bounds, s, targets, ext, pos, ref, vel, vel_old, body, flags, prm
            )
        _objects_move(objects, prm)
        if moved > limit:
            nbr = build_lists(
                pos, ref, vel, vel_old, body, flags, ext, nbr, ncount, bounds, prm, True
            )
            rebuilds += 1
        if chunks == 1:
            _forces(
                0, n, pos, vel_old, vel, body, flags, nbr, ncount, rects, circles, objects,
                acc[0], prm,
            )  # fmt: skip
        else:
            _forces_chunks(
                bounds, pos, vel_old, vel, body, flags, nbr, ncount, rects, circles, objects,
                acc, prm,
            )  # fmt: skip
        if objects.shape[0] > 0:
            _objects_step(objects, acc, chunks, rects, circles, prm)
    return nbr, rebuilds
