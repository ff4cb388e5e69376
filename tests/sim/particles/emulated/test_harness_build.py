"""The simavr harness built on first use from the package's own source, as an installed wheel
does in the user's cache."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from particlebot.sim.particles.emulated import harness
from particlebot.sim.particles.emulated.harness import HarnessBuildError, ParticleSim
from tests.sim.conftest import avr_tools_missing


@pytest.mark.simavr
def test_first_use_builds_a_harness_that_runs_the_firmware(
    built_images: None, tmp_path: Path
) -> None:
    missing = avr_tools_missing()
    if missing is not None:
        pytest.skip(f"{missing} is not installed")
    built = harness.ensure_harness(tmp_path / "cache" / "particle_sim-test")
    assert built.exists() and not list(built.parent.glob("*.partial"))
    with ParticleSim(harness=built) as sim:
        sim.run_for(20_000)  # 20 ms of the firmware's boot
        assert sim.cycle >= 20_000 * 8


def test_missing_system_packages_are_named_in_one_line(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    monkeypatch.delenv("PARTICLEBOT_SIM_HARNESS", raising=False)
    monkeypatch.setattr(shutil, "which", lambda _tool: None)
    with pytest.raises(HarnessBuildError) as raised:
        harness.ensure_harness(tmp_path / "particle_sim")
    message = str(raised.value)
    assert "\n" not in message
    assert "libsimavr-dev" in message and "libelf-dev" in message and "gcc" in message
    assert not (tmp_path / "particle_sim").exists()


def test_emulated_radio_without_the_build_tools_says_what_to_install(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    from particlebot import resources
    from particlebot.radio import RadioError, open_radio

    monkeypatch.delenv("PARTICLEBOT_SIM_HARNESS", raising=False)
    monkeypatch.setattr(resources, "harness", lambda: tmp_path / "particle_sim")
    monkeypatch.setattr(shutil, "which", lambda _tool: None)
    with pytest.raises(RadioError) as raised:
        open_radio("emulated://1?speed=max")
    message = str(raised.value)
    assert message.startswith("emulated particles need the simavr harness")
    assert "sudo apt-get install gcc pkg-config libsimavr-dev libelf-dev" in message
