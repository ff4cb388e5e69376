"""The world's laws as CUDA device functions: the same arithmetic, in the same order, as the CPU's.

Each function mirrors its namesake in particlebot.sim.world.kernels operation for operation, so
that in float64 a lone pair, a disc against a wall or a particle held by friction gives the same
bits on either backend (tests/sim/world/cuda check it in numba-cuda's simulator). A real GPU may
still differ in the last bits: NVVM contracts a * b + c into one fused multiply-add unless told
not to (see the package's description).

Obstacles and passive objects are given as index ranges into arrays shared by an ensemble's
swarms (rects[lo:hi], ...), so one kernel serves every swarm.
"""

from __future__ import annotations

import math
from typing import Any

from numba import cuda

from particlebot.sim.world import kernels as k

# Parameter slots the laws read (the CPU's vector layout, so one `prm` row serves both).
_P_DT = k.P_DT
_P_RMIN = k.P_RMIN
_P_RMAX = k.P_RMAX
_P_SPRING = k.P_SPRING
_P_DAMPING = k.P_DAMPING
_P_SHEAR = k.P_SHEAR
_P_OBSTACLE_SPRING = k.P_OBSTACLE_SPRING
_P_ATTRACTION = k.P_ATTRACTION
_P_CLAMP_FORCE = k.P_CLAMP_FORCE
_P_CLAMP_GAP = k.P_CLAMP_GAP
_P_BLEND_GAP = k.P_BLEND_GAP
_P_REST_SPEED = k.P_REST_SPEED
_P_MAX_SPEED = k.P_MAX_SPEED
_P_TORQUE = k.P_TORQUE
_P_CONSTRAINED = k.P_CONSTRAINED
_P_CONTRACTION = k.P_CONTRACTION

device = cuda.jit(device=True)
"""A device function (inlined into the kernels that call it)."""


@device
def magnet_law(
    gap: float, strength: float, low: float, clamp_gap: float, blend_gap: float, a: float
) -> float:
    """Magnet pull (N) across a gap: the clamp below the clamp gap, a linear blend up to the
    blend gap, A / gap^2 beyond (kernels._magnet_law)."""
    top = a / (blend_gap * blend_gap)
    clamp = low * strength
    blend = strength * (low + (gap - clamp_gap) / (blend_gap - clamp_gap) * (top - low))
    far_gap = max(gap, blend_gap)
    far = strength * a / (far_gap * far_gap)
    return clamp if gap < clamp_gap else (blend if gap < blend_gap else far)


@device
def magnet(gap: float, strength: float, prm: Any) -> float:
    """magnet_law with the swarm's parameters."""
    return magnet_law(
        gap, strength, prm[_P_CLAMP_FORCE], prm[_P_CLAMP_GAP], prm[_P_BLEND_GAP],
        prm[_P_ATTRACTION],
    )  # fmt: skip


@device
def contact(
    nx: float, ny: float, overlap: float, spring: float, dvx: float, dvy: float, prm: Any
) -> tuple[float, float]:
    """Force on the first body: spring along -n, dashpot on the relative velocity (second minus
    first), shear on its tangential part (kernels._contact_law)."""
    damping = prm[_P_DAMPING]
    shear = prm[_P_SHEAR]
    vn = dvx * nx + dvy * ny
    fx = -spring * overlap * nx + damping * dvx + shear * (dvx - vn * nx)
    fy = -spring * overlap * ny + damping * dvy + shear * (dvy - vn * ny)
    return fx, fy


@device
def cycle_radius(
    clock: float, offset: float, cycle: float, rise: float, r_min: float, stroke: float
) -> float:
    """The published cycle's commanded radius at a clock in [0, cycle) for a phase offset in
    [0, cycle): rising, falling, or NaN (rest: hold) (published._radius_at)."""
    tau = clock + offset
    if tau >= cycle:
        tau -= cycle
    if tau < rise:
        return r_min + stroke * tau / rise
    if tau < 2.0 * rise:
        return r_min + stroke * (2.0 - tau / rise)
    return math.nan


@device
def servo(r: float, target: float, fr: float, fa: float, prm: Any) -> float:
    """The published servo with its stall limit: the new radius for a commanded one."""
    r_min = prm[_P_RMIN]
    r_max = prm[_P_RMAX]
    dt = prm[_P_DT]
    target = min(max(target, r_min), r_max)
    dr1 = target - r
    if dr1 > 0.0:
        c = prm[_P_TORQUE]
        speed = prm[_P_MAX_SPEED] * r_max
        torque = min(dr1 * c * r / (speed * dt), c)
        dr = speed / c * (torque / r - fr) * dt if torque / r > fr else 0.0
    elif prm[_P_CONSTRAINED] != 0.0:
        cc = prm[_P_CONTRACTION]
        dr = (cc * dr1 + fa * r) / cc if -cc * dr1 > fa * r else 0.0
        dr = max(dr, -r_max * dt)
    else:
        dr = dr1
    return min(max(r + dr, r_min), r_max)


@device
def wall_push(
    nx: float, ny: float, depth: float, vx: float, vy: float, prm: Any
) -> tuple[float, float]:
    """Force of one obstacle on a disc it cuts into by `depth` along the outward normal n."""
    vn = -vx * nx - vy * ny
    spring = prm[_P_SPRING] * prm[_P_OBSTACLE_SPRING]
    fx = spring * depth * nx - prm[_P_DAMPING] * vx + prm[_P_SHEAR] * (-vx - vn * nx)
    fy = spring * depth * ny - prm[_P_DAMPING] * vy + prm[_P_SHEAR] * (-vy - vn * ny)
    return fx, fy


@device
def obstacle_force(
    x: float, y: float, r: float, vx: float, vy: float, rects: Any, rect_lo: int, rect_hi: int,
    circles: Any, circle_lo: int, circle_hi: int, prm: Any,
) -> tuple[float, float, float]:  # fmt: skip
    """Force of every obstacle of the swarm a disc overlaps, each on its own, and the sum of
    their magnitudes (kernels._obstacle_force over the swarm's ranges)."""
    fx = 0.0
    fy = 0.0
    total = 0.0
    for o in range(rect_lo, rect_hi):
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
            left = x - x1
            right = x2 - x
            below = y - y1
            above = y2 - y
            least = min(min(left, right), min(below, above))
            depth = least + r
            nx = -1.0 if least == left else (1.0 if least == right else 0.0)
            ny = 0.0 if nx != 0.0 else (-1.0 if least == below else 1.0)
        px, py = wall_push(nx, ny, depth, vx, vy, prm)
        fx += px
        fy += py
        total += math.sqrt(px * px + py * py)
    for o in range(circle_lo, circle_hi):
        dx = x - circles[o, 0]
        dy = y - circles[o, 1]
        reach = r + circles[o, 2]
        d2 = dx * dx + dy * dy
        if d2 < reach * reach and d2 > 0.0:
            d = math.sqrt(d2)
            px, py = wall_push(dx / d, dy / d, reach - d, vx, vy, prm)
            fx += px
            fy += py
            total += math.sqrt(px * px + py * py)
    return fx, fy, total


@device
def friction(
    vx: float, vy: float, fx: float, fy: float, inv_mass: float, slide: float, static: float,
    prm: Any,
) -> tuple[float, float]:  # fmt: skip
    """The new velocity: static friction holds a body at rest below its threshold, then
    v += F / m dt, then sliding friction takes slide x dt off the speed (kernels._friction)."""
    dt = prm[_P_DT]
    rest = prm[_P_REST_SPEED]
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
