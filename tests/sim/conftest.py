"""Fixtures of the firmware-in-the-loop tests: the firmware images and harness, built once."""

from __future__ import annotations

import shutil
import subprocess

import pytest

from particlebot.sim.particles.emulated.harness import default_elf, default_harness
from tests.support.repo import REPO_ROOT

REPO = REPO_ROOT


def avr_tools_missing() -> str | None:
    """The first tool the emulator tests need that is not installed, or None."""
    for tool in ("avr-gcc", "avr-g++", "pkg-config", "make"):
        if shutil.which(tool) is None:
            return tool
    if subprocess.run(["pkg-config", "--exists", "simavr"], check=False).returncode != 0:
        return "libsimavr-dev"
    return None


@pytest.fixture(scope="session")
def built_images() -> None:
    """build/firmware/particle.elf, particle-faults.elf and build/sim/particle_sim, up to date;
    skips the test when the AVR toolchain or simavr is not installed."""
    missing = avr_tools_missing()
    if missing is not None:
        pytest.skip(f"{missing} is not installed (`make system-deps` installs the AVR tools)")
    # `make pytest` has built them already; this keeps a bare `pytest tests/sim` honest too.
    result = subprocess.run(
        ["make", "-s", "firmware", "firmware-faults", "harness"],
        cwd=REPO,
        capture_output=True,
        text=True,
        check=False,
    )
    if result.returncode != 0:
        pytest.fail(f"building the firmware and harness failed:\n{result.stdout}{result.stderr}")
    assert default_elf().exists() and default_elf(faults=True).exists()
    assert default_harness().exists()
