"""A step's first and last passes over particles lo..hi: the servo and the position update
(kinematics), then obstacles, passive objects and ground friction setting the new velocity
(settle)."""

from __future__ import annotations

import math

import numba

from particlebot.sim.world.kernels.laws import _contact, _friction, _magnet, _obstacle_force
from particlebot.sim.world.kernels.layout import (
    B_FA,
    B_FR,
    B_FX,
    B_FY,
    B_MAG,
    B_R,
    F_ACTING,
    F_ALIVE,
    F_HELD,
    F_JOINED,
    F_KIND,
    MEMBER,
    O_MAG,
    O_R,
    O_VX,
    O_VY,
    O_X,
    O_Y,
    P_CONSTRAINED,
    P_CONTRACTION,
    P_CUTOFF,
    P_DT,
    P_FRICTION,
    P_HALF_WIDTH,
    P_MAX_SPEED,
    P_RMAX,
    P_RMIN,
    P_SPRING,
    P_STATIC,
    P_TORQUE,
    ByteArray,
    FloatArray,
    IntArray,
    _slot,
)


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
