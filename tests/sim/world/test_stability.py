"""sim/world/stability.py: the linearised explicit step of a touching patch (why packed swarms
boil with the published numbers, and not without shear)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from particlebot.sim.world import PhysicsParams
from particlebot.sim.world.stability import hexagonal_patch, stability, step_matrix


def test_a_lone_touching_pair_is_stable_and_a_packed_patch_is_not() -> None:
    params = PhysicsParams()
    pair = np.array([[0.0, 0.0], [2 * params.r_min, 0.0]])
    values = np.linalg.eigvals(step_matrix(pair, params.r_min, params))
    assert np.abs(values).max() < 1 + 1e-9
    patch = stability(params, rings=2)  # 19 discs
    assert patch.spectral_radius > 1.5
    assert patch.dominant.real < 0 and abs(patch.dominant.imag) < 1e-9  # flips every step
    assert 0 < patch.threshold_speed < params.mu * params.gravity * params.dt


def test_less_shear_is_more_stable_and_none_is_stable() -> None:
    params = PhysicsParams()
    growth = [stability(replace(params, shear=s), rings=2).spectral_radius for s in (40, 20)]
    assert growth[0] > growth[1]
    calm = stability(replace(params, shear=0.0), rings=2)
    assert calm.spectral_radius < 1 + 1e-6 and math.isinf(calm.threshold_speed)


def test_the_patch_is_hexagonal_and_its_discs_touch() -> None:
    centres = hexagonal_patch(2, 1.0)
    assert len(centres) == 19  # 1 + 6 + 12
    gaps = np.hypot(*(centres[:, None, :] - centres[None, :, :]).transpose(2, 0, 1))
    nearest = np.sort(gaps, axis=1)[:, 1]
    assert np.allclose(nearest, 1.0)
