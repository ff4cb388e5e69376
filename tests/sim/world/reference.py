"""A plain numpy transcription of the published step, all pairs, for checking the kernels."""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from particlebot.sim.particles.model.published import PublishedController
from particlebot.sim.world import World
from particlebot.sim.world.params import PhysicsParams

FloatArray = npt.NDArray[np.float64]


def magnet(gap: FloatArray, p: PhysicsParams) -> FloatArray:
    top = p.attraction / p.blend_gap**2
    blend = p.magnet_clamp_force + (gap - p.clamp_gap) / (p.blend_gap - p.clamp_gap) * (
        top - p.magnet_clamp_force
    )
    with np.errstate(divide="ignore"):
        far = p.attraction / gap**2
    return np.where(
        gap < p.clamp_gap, p.magnet_clamp_force, np.where(gap < p.blend_gap, blend, far)
    )


class ReferenceSwarm:
    """Particles of unit mass, no obstacles, no objects; every particle actuates."""

    def __init__(self, x: FloatArray, y: FloatArray, p: PhysicsParams) -> None:
        self.p = p
        self.pos = np.stack([x, y], axis=1).astype(float)
        self.vel = np.zeros_like(self.pos)
        self.r = np.full(len(x), p.r_min)
        self.fr = np.zeros(len(x))
        self.fa = np.zeros(len(x))

    def step(self, target: FloatArray) -> None:
        p = self.p
        dt = p.dt
        # Servo with the stall limit (NaN: hold).
        r = self.r
        tgt = np.clip(target, p.r_min, p.r_max)
        dr1 = tgt - r
        speed = p.max_speed * p.r_max
        torque = np.minimum(dr1 * p.torque_limit * r / (speed * dt), p.torque_limit)
        grow = np.where(
            torque / r > self.fr, speed / p.torque_limit * (torque / r - self.fr) * dt, 0.0
        )
        dr = np.where(dr1 > 0, grow, dr1)
        self.r = np.where(np.isnan(target), r, np.clip(r + dr, p.r_min, p.r_max))
        # Positions, walls.
        self.pos += self.vel * dt
        w = p.half_width
        for axis in (0, 1):
            high = self.pos[:, axis] > w - self.r
            low = self.pos[:, axis] < self.r - w
            self.pos[high, axis] = (w - self.r)[high]
            self.pos[low, axis] = (self.r - w)[low]
            self.vel[high | low, axis] *= -1
        # Pair forces on i from j (rel = pj - pi).
        rel = self.pos[None, :, :] - self.pos[:, None, :]
        d = np.sqrt(rel[..., 0] * rel[..., 0] + rel[..., 1] * rel[..., 1])
        np.fill_diagonal(d, np.inf)
        n = rel / d[..., None]
        c = self.r[:, None] + self.r[None, :]
        dv = self.vel[None, :, :] - self.vel[:, None, :]
        vn = (dv * n).sum(-1, keepdims=True)
        with np.errstate(invalid="ignore"):  # the diagonal (d = inf) is masked out below
            contact = -p.spring * (c - d)[..., None] * n + p.damping * dv + p.shear * (dv - vn * n)
        gap = d - c
        pull = magnet(gap, p)[..., None] * n
        touching = (d < c)[..., None]
        near = ((gap < p.magnet_cutoff) & (d >= c))[..., None]
        pair = np.where(touching, contact, np.where(near, pull, 0.0))
        force = pair.sum(axis=1)
        self.fr = np.where(touching[..., 0], np.hypot(contact[..., 0], contact[..., 1]), 0).sum(1)
        self.fa = np.where(near[..., 0], np.hypot(pull[..., 0], pull[..., 1]), 0).sum(1)
        # Friction.
        slow = np.hypot(*self.vel.T) < p.rest_speed
        weak = np.hypot(*force.T) < p.static_force
        force[slow & weak] = 0.0
        v = self.vel + force * dt
        speed_now = np.hypot(*v.T)
        decel = p.mu * p.gravity * dt
        with np.errstate(invalid="ignore", divide="ignore"):
            scaled = v * (1 - decel / speed_now)[:, None]
        self.vel = np.where((speed_now < decel)[:, None], 0.0, scaled)


def lockstep(
    world: World, controller: PublishedController, steps: int
) -> tuple[float, ReferenceSwarm]:
    """Steps `world` (run by `controller`) and a ReferenceSwarm from the same start side by side,
    the reference given the published profile's radii for the controller's phases; returns the
    largest position difference seen (m) and the reference as it ends."""
    params = world.params
    x, y = world.positions()
    reference = ReferenceSwarm(x, y, params)
    settings = controller.settings
    worst = 0.0
    for step in range(steps):
        world.step(1)
        tau = np.mod(step * params.dt + controller.phases, settings.cycle_s)
        rising = params.r_min + (params.r_max - params.r_min) * tau / settings.rise_s
        falling = params.r_min + (params.r_max - params.r_min) * (2 - tau / settings.rise_s)
        target = np.where(
            tau < settings.rise_s, rising, np.where(tau < 2 * settings.rise_s, falling, math.nan)
        )
        reference.step(target)
        xs, ys = world.positions()
        worst = max(
            worst, np.abs(xs - reference.pos[:, 0]).max(), np.abs(ys - reference.pos[:, 1]).max()
        )
    return worst, reference
