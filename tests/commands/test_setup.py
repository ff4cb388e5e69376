"""`particlebot setup` and the compile notice: a cold numba cache is found and said, with how long
compiling usually takes, before any run's progress starts; a warm one is left alone."""

from __future__ import annotations

import io
import os
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest

from particlebot.commands import _kernels
from particlebot.sim import warmup

REPO = Path(__file__).resolve().parents[2]


def _particlebot(cache: Path, *argv: str, timeout_s: float) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache), "PYTHONPATH": str(REPO / "host")}
    return subprocess.run(
        [sys.executable, "-m", "particlebot.cli", *argv], env=env, capture_output=True,
        text=True, timeout=timeout_s, check=False,
    )  # fmt: skip


def test_a_cold_cache_is_announced_with_its_usual_time_and_then_compiled(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    stages: list[str] = []

    def warm_up(report: Callable[[int, int, str], None]) -> None:
        for done, stage in enumerate(("placement", "parallel path")):
            report(done, 2, stage)
            stages.append(stage)
        report(2, 2, "done")

    monkeypatch.setattr(warmup, "kernels_cached", lambda: False)
    monkeypatch.setattr(warmup, "warm_up", warm_up)
    stream = io.StringIO()
    assert _kernels.prepare_kernels(stream) is True
    lines = stream.getvalue().splitlines()
    assert lines[0] == (
        f"compiling the simulator's kernels (once, about {warmup.COMPILE_USUAL_S:.0f} s)"
    )
    assert stages == ["placement", "parallel path"]
    assert lines[-1].startswith("kernels compiled in ") and "cached in " in lines[-1]


def test_a_warm_cache_is_left_alone(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(warmup, "kernels_cached", lambda: True)
    stream = io.StringIO()
    assert _kernels.prepare_kernels(stream) is False
    assert stream.getvalue() == ""


def test_an_empty_numba_cache_is_seen_as_cold(tmp_path: Path) -> None:
    # Nothing compiled: only numba's index files are looked at.
    done = _particlebot(tmp_path, "setup", "--check", timeout_s=300)
    assert done.returncode == 1, done.stderr
    assert "not compiled yet: run `particlebot setup`" in done.stdout
    assert not list(tmp_path.rglob("*.nbc"))  # and compiled nothing


@pytest.mark.slow
@pytest.mark.timeout(3 * 1800 + 60)  # three commands, each far from its typical time
def test_setup_fills_an_empty_cache_once_and_a_run_then_compiles_nothing(tmp_path: Path) -> None:
    cache = tmp_path / "cache"
    cache.mkdir()
    first = _particlebot(cache, "setup", timeout_s=1800)
    assert first.returncode == 0, first.stderr
    assert "compiling the simulator's kernels (once, about" in first.stderr
    assert f"cached in {cache}" in first.stderr
    assert _particlebot(cache, "setup", "--check", timeout_s=1800).returncode == 0
    run = _particlebot(
        cache, "simulate", "--particles", "3", "--duration", "0.2", "-o", str(tmp_path / "run"),
        timeout_s=1800,
    )  # fmt: skip
    assert run.returncode == 0, run.stderr
    assert "compiling" not in run.stderr
    assert f"Run folder: {tmp_path / 'run'}" in run.stdout
