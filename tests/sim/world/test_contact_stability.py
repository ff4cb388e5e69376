"""tools/contact_stability.py: the linearised explicit step of a touching patch (why packed
swarms boil with the published numbers, and not without shear)."""

from __future__ import annotations

import importlib.util
import math
import sys
from dataclasses import replace
from pathlib import Path
from types import ModuleType

import numpy as np
import pytest

from particlebot.sim.world import PhysicsParams

TOOL = Path(__file__).resolve().parents[3] / "tools" / "contact_stability.py"


def _tool() -> ModuleType:
    spec = importlib.util.spec_from_file_location("contact_stability", TOOL)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # (its dataclasses look their module up there)
    spec.loader.exec_module(module)
    return module


def test_a_lone_touching_pair_is_stable_and_a_packed_patch_is_not() -> None:
    tool = _tool()
    params = PhysicsParams()
    pair = np.array([[0.0, 0.0], [2 * params.r_min, 0.0]])
    values = np.linalg.eigvals(tool.step_matrix(pair, params.r_min, params))
    assert np.abs(values).max() < 1 + 1e-9
    patch = tool.stability(params, rings=2)  # 19 discs
    assert patch.spectral_radius > 1.5
    assert patch.dominant.real < 0 and abs(patch.dominant.imag) < 1e-9  # flips every step
    assert 0 < patch.threshold_speed < params.mu * params.gravity * params.dt


def test_less_shear_is_more_stable_and_none_is_stable() -> None:
    tool = _tool()
    params = PhysicsParams()
    growth = [tool.stability(replace(params, shear=s), rings=2).spectral_radius for s in (40, 20)]
    assert growth[0] > growth[1]
    calm = tool.stability(replace(params, shear=0.0), rings=2)
    assert calm.spectral_radius < 1 + 1e-6 and math.isinf(calm.threshold_speed)


def test_bad_options_exit_2_naming_the_problem(capsys: pytest.CaptureFixture[str]) -> None:
    tool = _tool()
    cases = (["--rings", "0"], "--rings"), (["--shears", "x"], "'x'"), (["--dampings", "-1"], "-1")
    for argv, named in cases:
        with pytest.raises(SystemExit) as stop:
            tool.main(argv)
        assert stop.value.code == 2
        assert named in capsys.readouterr().err.strip().splitlines()[-1]
