"""The force laws, one body or one pair at a time: magnets, contacts, obstacles, ground friction,
and the joining of a free particle that touches the robot."""

from __future__ import annotations

import math

import numba

from particlebot.sim.world.kernels.layout import (
    _FAST,
    B_MAG,
    F_JOINED,
    F_KIND,
    FREE,
    MEMBER,
    P_ATTRACTION,
    P_BLEND_GAP,
    P_CLAMP_FORCE,
    P_CLAMP_GAP,
    P_DAMPING,
    P_DT,
    P_OBSTACLE_SPRING,
    P_REST_SPEED,
    P_SHEAR,
    P_SPRING,
    P_TOUCH_GAP,
    ByteArray,
    FloatArray,
)


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
