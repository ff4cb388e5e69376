"""Passive objects (few, possibly huge discs): their own position update and their velocity from
what the particles, each other, obstacles and friction do to them."""

from __future__ import annotations

import math

import numba
import numpy as np

from particlebot.sim.world.kernels.laws import _contact, _friction, _magnet, _obstacle_force
from particlebot.sim.world.kernels.layout import (
    O_FRICTION,
    O_INV_MASS,
    O_MAG,
    O_R,
    O_STATIC,
    O_VX,
    O_VY,
    O_X,
    O_Y,
    P_CUTOFF,
    P_DT,
    P_HALF_WIDTH,
    P_SPRING,
    FloatArray,
)


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
