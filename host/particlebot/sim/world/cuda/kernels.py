"""The passes of a step as CUDA kernels, one thread per particle (or per cell, object, swarm).

Every kernel serves an ensemble: the swarms' particles are concatenated, `swarm[i]` says whose
particle i is, and each swarm has its own row of parameters, its own grid cells, obstacles and
passive objects (index ranges into shared arrays). A swarm of one is the single World's case.

A step: kinematics (servo, motion, walls) -> the objects move -> a counting sort of the particles
into grid cells (count with atomics, scan, scatter, each cell's few members put in index order so
that the order is the same every run) -> pairs (thread i walks the 3 x 3 cells around its own and
sums what every neighbour does to it: no atomics, each pair evaluated from both sides, which
gives exactly opposite forces) -> settle (obstacles, passive objects, friction) -> the objects
settle (one thread per swarm, summing what its particles did to each object in index order).
"""

from __future__ import annotations

import math
from typing import Any

from numba import cuda

from particlebot.sim.world import kernels as k
from particlebot.sim.world.cuda import laws

_B_R = k.B_R
_B_FR = k.B_FR
_B_FA = k.B_FA
_B_MAG = k.B_MAG
_B_FX = k.B_FX
_B_FY = k.B_FY
_F_KIND = k.F_KIND
_F_ACTING = k.F_ACTING
_F_JOINED = k.F_JOINED
_F_ALIVE = k.F_ALIVE
_F_HELD = k.F_HELD
_MEMBER = k.MEMBER
_FREE = k.FREE
_O_X = k.O_X
_O_Y = k.O_Y
_O_VX = k.O_VX
_O_VY = k.O_VY
_O_R = k.O_R
_O_INV_MASS = k.O_INV_MASS
_O_FRICTION = k.O_FRICTION
_O_STATIC = k.O_STATIC
_O_MAG = k.O_MAG
_P_DT = k.P_DT
_P_RMIN = k.P_RMIN
_P_RMAX = k.P_RMAX
_P_SPRING = k.P_SPRING
_P_CUTOFF = k.P_CUTOFF
_P_FRICTION = k.P_FRICTION
_P_STATIC = k.P_STATIC
_P_HALF_WIDTH = k.P_HALF_WIDTH
_P_SKIN = k.P_SKIN
_P_LIST_RADIUS = k.P_LIST_RADIUS
_P_TOUCH_GAP = k.P_TOUCH_GAP

kernel = cuda.jit(cache=True)
"""A kernel, kept in numba's on-disk cache (each process of a study would compile it again)."""

SCAN_TILE = 64
"""Values one thread sums at each level of the grid's prefix sum (levels until one tile is
left: 11 million cells take four)."""


@laws.device
def _thread() -> int:
    """This thread's index in the launch (cuda.grid(1), typed: numba's stubs do not say)."""
    return cuda.grid(1)  # type: ignore[call-arg]


@laws.device
def _atomic_add(array: Any, index: int, value: int) -> int:
    """cuda.atomic.add, typed (numba's stubs do not say); the value array[index] had."""
    return cuda.atomic.add(array, index, value)  # type: ignore[call-arg, return-value]


@laws.device
def cell_width(prm: Any) -> float:
    """A grid cell is as wide as the longest reach of a pair (2 r_max + magnet cutoff): every
    partner of a particle lies in the 3 x 3 cells around its own."""
    return prm[_P_LIST_RADIUS] - prm[_P_SKIN]


@kernel
def kinematics(
    n: int, row: int, targets: Any, base: Any, ext: Any, swarm: Any, pos: Any, vel: Any,
    body: Any, flags: Any, prm: Any, cycles: Any, offset: Any,
) -> None:  # fmt: skip
    """First pass (kernels._kinematics): joins take effect, the servo moves toward the commanded
    radius (from last step's force sums, then cleared), positions advance by the old velocity
    and walls reflect it. The command: for a swarm whose cycles[s, 0] is 1, the published cycle
    at step cycles[s, 1] + row (period cycles[s, 2], rise cycles[s, 3], particle offsets
    offset[base + ext[i]]); else targets[row, base + ext[i]]."""
    i = _thread()
    if i >= n:
        return
    s = swarm[i]
    p = prm[s]
    dt = p[_P_DT]
    wall = p[_P_HALF_WIDTH]
    if flags[_F_JOINED, i]:
        flags[_F_JOINED, i] = 0
        flags[_F_KIND, i] = _MEMBER
        flags[_F_ACTING, i] = flags[_F_ALIVE, i] & (1 - flags[_F_HELD, i])
    r = body[_B_R, i]
    if flags[_F_ACTING, i]:
        if cycles[s, 0] != 0.0:
            r_min = p[_P_RMIN]
            clock = ((cycles[s, 1] + row) * dt) % cycles[s, 2]
            target = laws.cycle_radius(clock, offset[base[s] + ext[i]], cycles[s, 2],
                                       cycles[s, 3], r_min, p[_P_RMAX] - r_min)  # fmt: skip
        else:
            target = targets[row, base[s] + ext[i]]
        if not math.isnan(target):
            r = laws.servo(r, target, body[_B_FR, i], body[_B_FA, i], p)
            body[_B_R, i] = r
    body[_B_FR, i] = 0.0
    body[_B_FA, i] = 0.0
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


@laws.device
def _axis_cell(v: float, wall: float, width: float, full: int, side: int) -> int:
    """A coordinate's grid column (or row): from the wall, clamped into the grid, wrapped when
    the swarm's grid is narrower than the arena."""
    c = int((v + wall) / width)
    c = min(max(c, 0), full - 1)
    return c % side


@kernel
def count_cells(
    n: int, pos: Any, swarm: Any, prm: Any, side: Any, full: Any, cell_base: Any,
    cell_of: Any, counts: Any,
) -> None:  # fmt: skip
    """Each particle's cell, counted (the first pass of the counting sort)."""
    i = _thread()
    if i >= n:
        return
    s = swarm[i]
    p = prm[s]
    width = cell_width(p)
    wall = p[_P_HALF_WIDTH]
    cx = _axis_cell(pos[0, i], wall, width, full[s], side[s])
    cy = _axis_cell(pos[1, i], wall, width, full[s], side[s])
    c = cell_base[s] + cy * side[s] + cx
    cell_of[i] = c
    _atomic_add(counts, c, 1)


@kernel
def scan_tiles(count: int, values: Any, out: Any, sums: Any) -> None:
    """One level of the grid's prefix sum: exclusive sums within tiles of SCAN_TILE values, and
    each tile's total (which the next level sums the same way)."""
    t = _thread()
    lo = t * SCAN_TILE
    if lo >= count:
        return
    hi = min(lo + SCAN_TILE, count)
    total = 0
    for c in range(lo, hi):
        out[c] = total
        total += values[c]
    sums[t] = total


@kernel
def add_offsets(count: int, out: Any, offsets: Any) -> None:
    """Adds each tile's offset (the next level's exclusive sum) to its values."""
    c = _thread()
    if c < count:
        out[c] += offsets[c // SCAN_TILE]


@kernel
def set_end(start: Any, cells: int, top: Any) -> None:
    """The end of the last cell: every particle (the last level's single total)."""
    if _thread() == 0:
        start[cells] = top[0]


@kernel
def clear(cells: int, counts: Any) -> None:
    """Zeroes the cells' counts."""
    c = _thread()
    if c < cells:
        counts[c] = 0


@kernel
def scatter(n: int, cell_of: Any, start: Any, fill: Any, members: Any) -> None:
    """Each particle into the next free place of its cell (in whatever order the atomics give)."""
    i = _thread()
    if i >= n:
        return
    c = cell_of[i]
    members[start[c] + _atomic_add(fill, c, 1)] = i


@kernel
def order_cells(cells: int, start: Any, members: Any) -> None:
    """Each cell's members in index order (an insertion sort of a handful): the pair sums then
    add in the same order every run, whatever order the scatter's atomics came in."""
    c = _thread()
    if c >= cells:
        return
    lo = start[c]
    hi = start[c + 1]
    for a in range(lo + 1, hi):
        value = members[a]
        b = a - 1
        while b >= lo and members[b] > value:
            members[b + 1] = members[b]
            b -= 1
        members[b + 1] = value


@kernel
def pairs(
    n: int, pos: Any, vel: Any, body: Any, flags: Any, swarm: Any, prm: Any, side: Any,
    full: Any, cell_base: Any, cell_of: Any, start: Any, members: Any,
) -> None:  # fmt: skip
    """Second pass, one thread per particle: what every particle within reach does to i, from
    the new positions and old velocities (contact: spring, dashpot, shear; else the magnets),
    summed in cell order; a free particle touching a member is marked to join."""
    i = _thread()
    if i >= n:
        return
    s = swarm[i]
    p = prm[s]
    g = side[s]
    wrap = g < full[s]
    cutoff = p[_P_CUTOFF]
    spring = p[_P_SPRING]
    touch_gap = p[_P_TOUCH_GAP]
    xi = pos[0, i]
    yi = pos[1, i]
    vxi = vel[0, i]
    vyi = vel[1, i]
    ri = body[_B_R, i]
    magi = body[_B_MAG, i]
    kind_i = flags[_F_KIND, i]
    local = cell_of[i] - cell_base[s]
    cy = local // g
    cx = local - cy * g
    fx = 0.0
    fy = 0.0
    f_contact = 0.0
    f_attract = 0.0
    joins = False
    for oy in range(-1, 2):
        ry = cy + oy
        if wrap:
            ry = (ry + g) % g
        elif ry < 0 or ry >= g:
            continue
        for ox in range(-1, 2):
            rx = cx + ox
            if wrap:
                rx = (rx + g) % g
            elif rx < 0 or rx >= g:
                continue
            c = cell_base[s] + ry * g + rx
            for q in range(start[c], start[c + 1]):
                j = members[q]
                if j == i:
                    continue
                dx = pos[0, j] - xi
                dy = pos[1, j] - yi
                d2 = dx * dx + dy * dy
                reach_c = ri + body[_B_R, j]
                reach = reach_c + cutoff
                if d2 >= reach * reach or d2 == 0.0:
                    continue
                d = math.sqrt(d2)
                nx = dx / d
                ny = dy / d
                if d < reach_c:
                    px, py = laws.contact(
                        nx, ny, reach_c - d, spring, vel[0, j] - vxi, vel[1, j] - vyi, p
                    )
                    fx += px
                    fy += py
                    f_contact += math.sqrt(px * px + py * py)
                    touching = True
                else:
                    strength = magi * body[_B_MAG, j]
                    if strength > 0.0:
                        attract = laws.magnet(d - reach_c, strength, p)
                        fx += attract * nx
                        fy += attract * ny
                        f_attract += attract
                    touching = d - reach_c < touch_gap
                if touching and kind_i == _FREE and flags[_F_KIND, j] == _MEMBER:
                    joins = True
    if joins:
        flags[_F_JOINED, i] = 1
    body[_B_FX, i] = fx
    body[_B_FY, i] = fy
    body[_B_FR, i] += f_contact
    body[_B_FA, i] += f_attract


@kernel
def settle(
    n: int, pos: Any, vel: Any, body: Any, swarm: Any, prm: Any, rects: Any, rect_lo: Any,
    rect_hi: Any, circles: Any, circle_lo: Any, circle_hi: Any, objects: Any, object_lo: Any,
    object_hi: Any, pushes: Any,
) -> None:  # fmt: skip
    """Third pass (kernels._settle): obstacles and the swarm's passive objects act on i (what i
    does to its swarm's m-th object goes to pushes[i, m]), then its velocity with ground
    friction; the force rows are cleared for the next step."""
    i = _thread()
    if i >= n:
        return
    s = swarm[i]
    p = prm[s]
    spring = p[_P_SPRING]
    cutoff = p[_P_CUTOFF]
    xi = pos[0, i]
    yi = pos[1, i]
    vxi = vel[0, i]
    vyi = vel[1, i]
    ri = body[_B_R, i]
    fx = body[_B_FX, i]
    fy = body[_B_FY, i]
    body[_B_FX, i] = 0.0
    body[_B_FY, i] = 0.0
    if rect_hi[s] > rect_lo[s] or circle_hi[s] > circle_lo[s]:
        px, py, size = laws.obstacle_force(
            xi, yi, ri, vxi, vyi, rects, rect_lo[s], rect_hi[s], circles, circle_lo[s],
            circle_hi[s], p,
        )  # fmt: skip
        fx += px
        fy += py
        body[_B_FR, i] += size
    first = object_lo[s]
    for m in range(first, object_hi[s]):
        pushes[i, m - first, 0] = 0.0
        pushes[i, m - first, 1] = 0.0
        dx = objects[m, _O_X] - xi
        dy = objects[m, _O_Y] - yi
        c = ri + objects[m, _O_R]
        d2 = dx * dx + dy * dy
        reach = c + cutoff
        if d2 >= reach * reach or d2 == 0.0:
            continue
        d = math.sqrt(d2)
        nx = dx / d
        ny = dy / d
        if d < c:
            dvx = objects[m, _O_VX] - vxi
            dvy = objects[m, _O_VY] - vyi
            px, py = laws.contact(nx, ny, c - d, spring, dvx, dvy, p)
            body[_B_FR, i] += math.sqrt(px * px + py * py)
        else:
            strength = body[_B_MAG, i] * objects[m, _O_MAG]
            if strength <= 0.0:
                continue
            pull = laws.magnet(d - c, strength, p)
            px = pull * nx
            py = pull * ny
            body[_B_FA, i] += pull
        fx += px
        fy += py
        pushes[i, m - first, 0] = -px
        pushes[i, m - first, 1] = -py
    vx, vy = laws.friction(vxi, vyi, fx, fy, 1.0, p[_P_FRICTION], p[_P_STATIC], p)
    vel[0, i] = vx
    vel[1, i] = vy


@kernel
def objects_move(swarms: int, objects: Any, object_lo: Any, object_hi: Any, prm: Any) -> None:
    """Passive objects' positions from their velocities, reflected by the walls (one thread per
    swarm, kernels._objects_move)."""
    s = _thread()
    if s >= swarms:
        return
    p = prm[s]
    dt = p[_P_DT]
    wall = p[_P_HALF_WIDTH]
    for m in range(object_lo[s], object_hi[s]):
        r = objects[m, _O_R]
        for axis in range(2):
            speed = _O_VX + axis
            value = objects[m, _O_X + axis] + objects[m, speed] * dt
            if value > wall - r:
                value = wall - r
                objects[m, speed] = -objects[m, speed]
            elif value < r - wall:
                value = r - wall
                objects[m, speed] = -objects[m, speed]
            objects[m, _O_X + axis] = value


@kernel
def objects_settle(
    swarms: int, objects: Any, object_lo: Any, object_hi: Any, first: Any, last: Any,
    pushes: Any, force: Any, rects: Any, rect_lo: Any, rect_hi: Any, circles: Any,
    circle_lo: Any, circle_hi: Any, prm: Any,
) -> None:  # fmt: skip
    """Passive objects' velocities (kernels._objects_settle), one thread per swarm: the pushes
    of its particles first..last summed in index order, each other, obstacles, friction. (A
    serial sum over the swarm: passive objects are rare, and the order stays fixed.)"""
    s = _thread()
    if s >= swarms:
        return
    p = prm[s]
    cutoff = p[_P_CUTOFF]
    lo = object_lo[s]
    hi = object_hi[s]
    for m in range(lo, hi):
        fx = 0.0
        fy = 0.0
        for i in range(first[s], last[s]):
            fx += pushes[i, m - lo, 0]
            fy += pushes[i, m - lo, 1]
        xm = objects[m, _O_X]
        ym = objects[m, _O_Y]
        vxm = objects[m, _O_VX]
        vym = objects[m, _O_VY]
        rm = objects[m, _O_R]
        for o in range(lo, hi):
            if o == m:
                continue
            dx = objects[o, _O_X] - xm
            dy = objects[o, _O_Y] - ym
            c = rm + objects[o, _O_R]
            d = math.sqrt(dx * dx + dy * dy)
            if d == 0.0 or d >= c + cutoff:
                continue
            nx = dx / d
            ny = dy / d
            if d < c:
                dvx = objects[o, _O_VX] - vxm
                dvy = objects[o, _O_VY] - vym
                px, py = laws.contact(nx, ny, c - d, p[_P_SPRING], dvx, dvy, p)
            else:
                strength = objects[m, _O_MAG] * objects[o, _O_MAG]
                pull = laws.magnet(d - c, strength, p) if strength > 0.0 else 0.0
                px = pull * nx
                py = pull * ny
            fx += px
            fy += py
        px, py, _ = laws.obstacle_force(
            xm, ym, rm, vxm, vym, rects, rect_lo[s], rect_hi[s], circles, circle_lo[s],
            circle_hi[s], p,
        )  # fmt: skip
        force[m, 0] = fx + px
        force[m, 1] = fy + py
    for m in range(lo, hi):
        vx, vy = laws.friction(
            objects[m, _O_VX], objects[m, _O_VY], force[m, 0], force[m, 1],
            objects[m, _O_INV_MASS], objects[m, _O_FRICTION], objects[m, _O_STATIC], p,
        )  # fmt: skip
        objects[m, _O_VX] = vx
        objects[m, _O_VY] = vy
