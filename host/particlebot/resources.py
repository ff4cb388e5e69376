"""Where build artefacts and package data live, in a clone of the repository or an installed wheel.

This is the one module that knows the file layout; everything else asks it. Two layouts exist:

- A clone (or an editable install of one): the repository root holds the Makefile, and the
  artefacts are what `make native firmware harness` builds under build/:
  build/native/libparticle.so, build/firmware/particle.hex and .elf (and particle-faults.elf),
  build/sim/particle_sim. The example scenarios are scenarios/.
- An installed wheel: the native library is the package's own particlebot/firmware/libparticle.so,
  the firmware images and example scenarios are package data under particlebot/_data/, and the
  simavr harness is compiled on first use from the source the package carries
  (particlebot/sim/particles/emulated/particle_sim.c) into the user's cache.

In a clone the build/ artefacts come first, so that `make` keeps what runs in step with the
sources. Environment variables override the defaults:

- PARTICLEBOT_NATIVE_LIB: the firmware logic's shared library (e.g. the sanitized
  build/native-asan/libparticle.so the firmware tests load).
- PARTICLEBOT_FIRMWARE_DIR: a folder holding particle.hex / particle.elf (and particle-faults.elf)
  to flash and emulate instead of the default images.
- PARTICLEBOT_SIM_HARNESS: a ready-built simavr harness executable.
- PARTICLEBOT_CACHE_DIR: where the harness is built on first use (default
  $XDG_CACHE_HOME/particlebot, i.e. ~/.cache/particlebot).
"""

from __future__ import annotations

import hashlib
import os
import tomllib
from dataclasses import dataclass
from pathlib import Path

ENV_NATIVE_LIB = "PARTICLEBOT_NATIVE_LIB"
ENV_FIRMWARE_DIR = "PARTICLEBOT_FIRMWARE_DIR"
ENV_SIM_HARNESS = "PARTICLEBOT_SIM_HARNESS"
ENV_CACHE_DIR = "PARTICLEBOT_CACHE_DIR"

PACKAGE_DIR = Path(__file__).resolve().parent
DATA_DIR = PACKAGE_DIR / "_data"
"""Package data a wheel carries (firmware images, example scenarios); absent in a clone."""

NATIVE_LIBRARY_NAME = "libparticle.so"
HARNESS_SOURCE = PACKAGE_DIR / "sim" / "particles" / "emulated" / "particle_sim.c"
FIRMWARE_MANIFEST = "particle.toml"
"""Written beside a wheel's firmware image: the definition hash it was built from, its sha256."""


def source_root() -> Path | None:
    """The repository root when the package runs from a clone (host/particlebot), else None."""
    root = PACKAGE_DIR.parents[1]
    if (root / "Makefile").is_file() and (root / "firmware" / "lib").is_dir():
        return root
    return None


def _override(variable: str) -> Path | None:
    value = os.environ.get(variable)
    return Path(value) if value else None


def native_library() -> Path:
    """Where the firmware logic's shared library is looked for (it may not exist yet)."""
    override = _override(ENV_NATIVE_LIB)
    if override is not None:
        return override
    root = source_root()
    if root is not None:
        return root / "build" / "native" / NATIVE_LIBRARY_NAME
    return PACKAGE_DIR / "firmware" / NATIVE_LIBRARY_NAME


def firmware_dir() -> Path:
    """The folder of the default firmware images (particle.hex, particle.elf)."""
    override = _override(ENV_FIRMWARE_DIR)
    if override is not None:
        return override
    root = source_root()
    if root is not None:
        return root / "build" / "firmware"
    return DATA_DIR / "firmware"


def firmware_image(*, faults: bool = False, suffix: str = ".hex") -> Path:
    """The default image to flash (.hex) or emulate (.elf); faults: the fault-injection build,
    which only a clone builds (`make firmware-faults`)."""
    name = "particle-faults" if faults else "particle"
    return firmware_dir() / f"{name}{suffix}"


@dataclass(frozen=True)
class FirmwareManifest:
    """What a wheel records about the firmware image it carries."""

    definition_hash: int
    sha256: str


def firmware_manifest() -> FirmwareManifest | None:
    """The shipped image's manifest, or None (a clone's build/ has none; `make firmware` builds
    the image from the same definition as the host's generated module)."""
    path = firmware_dir() / FIRMWARE_MANIFEST
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
        return FirmwareManifest(int(data["definition_hash"]), str(data["sha256"]))
    except (OSError, tomllib.TOMLDecodeError, KeyError, TypeError, ValueError):
        return None


def cache_dir() -> Path:
    """The user's cache folder for what particlebot builds on first use."""
    override = _override(ENV_CACHE_DIR)
    if override is not None:
        return override
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "particlebot"


def harness() -> Path:
    """Where the simavr harness executable is looked for (it may not exist yet): the override,
    the clone's build/sim/particle_sim, or a build of this package's source in the cache, named by
    the source's hash so that an upgraded package never runs an old harness."""
    override = _override(ENV_SIM_HARNESS)
    if override is not None:
        return override
    root = source_root()
    if root is not None:
        return root / "build" / "sim" / "particle_sim"
    digest = hashlib.sha256(HARNESS_SOURCE.read_bytes()).hexdigest()[:12]
    return cache_dir() / f"particle_sim-{digest}"


def scenarios_dir() -> Path:
    """The example scenarios (blob-to-lamp.toml, carry.toml, ...)."""
    root = source_root()
    if root is not None:
        return root / "scenarios"
    return DATA_DIR / "scenarios"
