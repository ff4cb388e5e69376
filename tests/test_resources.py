"""particlebot.resources: where a clone keeps its build artefacts, and what overrides them."""

from __future__ import annotations

from pathlib import Path

import pytest

from particlebot import resources

REPO = Path(__file__).resolve().parents[1]


def test_a_clone_finds_its_build_folder() -> None:
    assert resources.source_root() == REPO
    assert resources.native_library() == REPO / "build" / "native" / "libparticle.so"
    assert resources.firmware_image() == REPO / "build" / "firmware" / "particle.hex"
    assert resources.firmware_image(faults=True, suffix=".elf") == (
        REPO / "build" / "firmware" / "particle-faults.elf"
    )
    assert resources.harness() == REPO / "build" / "sim" / "particle_sim"
    assert (resources.scenarios_dir() / "blob-to-lamp.toml").is_file()
    assert resources.HARNESS_SOURCE.is_file()


def test_environment_variables_override_the_defaults(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    monkeypatch.setenv(resources.ENV_NATIVE_LIB, str(tmp_path / "lib.so"))
    monkeypatch.setenv(resources.ENV_FIRMWARE_DIR, str(tmp_path / "fw"))
    monkeypatch.setenv(resources.ENV_SIM_HARNESS, str(tmp_path / "sim"))
    assert resources.native_library() == tmp_path / "lib.so"
    assert resources.firmware_image(suffix=".elf") == tmp_path / "fw" / "particle.elf"
    assert resources.harness() == tmp_path / "sim"


def test_an_installed_package_uses_its_data_and_the_cache(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    monkeypatch.setattr(resources, "source_root", lambda: None)
    monkeypatch.setenv(resources.ENV_CACHE_DIR, str(tmp_path))
    assert resources.native_library() == resources.PACKAGE_DIR / "firmware" / "libparticle.so"
    assert resources.firmware_image() == resources.DATA_DIR / "firmware" / "particle.hex"
    assert resources.scenarios_dir() == resources.DATA_DIR / "scenarios"
    harness = resources.harness()
    assert harness.parent == tmp_path and harness.name.startswith("particle_sim-")


def test_a_wheels_firmware_manifest_is_read(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    monkeypatch.setenv(resources.ENV_FIRMWARE_DIR, str(tmp_path))
    assert resources.firmware_manifest() is None
    (tmp_path / resources.FIRMWARE_MANIFEST).write_text(
        'definition_hash = 0xF1AAC96B\nsha256 = "ab"\n', encoding="utf-8"
    )
    assert resources.firmware_manifest() == resources.FirmwareManifest(0xF1AAC96B, "ab")
