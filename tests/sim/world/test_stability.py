"""sim/world/stability.py: the linearised explicit step of a touching patch (why packed swarms
boil with the published numbers, and not without shear)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import numpy.typing as npt

from particlebot.sim.world import PhysicsParams
from particlebot.sim.world.stability import hexagonal_patch, stability, step_matrix

EPS = float(np.finfo(np.float64).eps)
# Why no test here compares an eigenvalue of modulus 1 with 1 + 1e-9: the rigid motions of a
# contact (translation at constant velocity) make the step matrix defective, a Jordan block of
# eigenvalue 1 (x_n = x_0 + n dt v). An eigensolver's backward error of eps * ||A|| moves the
# eigenvalues of a 2x2 Jordan block by about sqrt(eps * ||A||) (~7e-8 here), and how far depends
# on the LAPACK, its kernels and the CPU. The tests therefore check what stability means: that
# powers of the step grow at most linearly (the Jordan block's n), not geometrically.
PROPAGATED_STEPS = 2**16


def _growth_over_a_doubling(step: npt.NDArray[np.float64]) -> float:
    """||A^2n|| / ||A^n|| for n = PROPAGATED_STEPS: 2 when the fastest growth is the rigid
    motions' linear one, about 2 rho^n when a mode of modulus rho > 1 exists (rho = 1 + 3.4e-6
    already gives 2.5 at n = 65,536). Norms of powers are as well conditioned as the products, so
    this ratio is the same to many digits on any BLAS."""
    once = np.linalg.matrix_power(step, PROPAGATED_STEPS)
    twice = once @ once
    return float(np.linalg.norm(twice, 2) / np.linalg.norm(once, 2))


def test_a_lone_touching_pair_is_stable_and_a_packed_patch_is_not() -> None:
    params = PhysicsParams()
    pair = np.array([[0.0, 0.0], [2 * params.r_min, 0.0]])
    step = step_matrix(pair, params.r_min, params)
    assert _growth_over_a_doubling(step) < 2.5  # no mode grows over 131,072 steps
    # And its eigenvalues are 1 to within what a defective eigenvalue allows (see EPS above).
    jordan_error = math.sqrt(EPS * np.linalg.norm(step, 2))
    assert np.abs(np.linalg.eigvals(step)).max() < 1 + 16 * jordan_error
    patch = stability(params, rings=2)  # 19 discs
    assert patch.spectral_radius > 1.5
    # The dominant eigenvalue is real and negative: a mode that flips every step. The hexagon's
    # symmetry makes it double (semisimple), so a LAPACK may return it as a pair whose imaginary
    # parts are rounding: allow sqrt(eps) of its modulus, far below the 0.1 that would be a
    # rotation of the mode from one step to the next.
    assert patch.dominant.real < 0
    assert abs(patch.dominant.imag) < math.sqrt(EPS) * patch.spectral_radius
    assert 0 < patch.threshold_speed < params.mu * params.gravity * params.dt


def test_less_shear_is_more_stable_and_none_is_stable() -> None:
    params = PhysicsParams()
    growth = [stability(replace(params, shear=s), rings=2).spectral_radius for s in (40, 20)]
    assert growth[0] > growth[1]
    calm_params = replace(params, shear=0.0)
    calm = stability(calm_params, rings=2)
    step = step_matrix(hexagonal_patch(2, 2 * params.r_min), params.r_min, calm_params)
    assert _growth_over_a_doubling(step) < 2.5
    # The tool calls a patch stable below 1 + 1e-6: about ten times sqrt(eps ||A||) (1.1e-7
    # here), the scale of the rigid motions' rounding, and far below the 1.5 of a packed patch.
    assert calm.spectral_radius < 1 + 1e-6 and math.isinf(calm.threshold_speed)


def test_the_patch_is_hexagonal_and_its_discs_touch() -> None:
    centres = hexagonal_patch(2, 1.0)
    assert len(centres) == 19  # 1 + 6 + 12
    gaps = np.hypot(*(centres[:, None, :] - centres[None, :, :]).transpose(2, 0, 1))
    nearest = np.sort(gaps, axis=1)[:, 1]
    assert np.allclose(nearest, 1.0)
