"""The platform wheel as a pip user gets it: built from the clone, installed with its dependencies
into a fresh venv, and run from a folder that is not the clone."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import venv
import zipfile
from pathlib import Path

import pytest

from particlebot import resources
from particlebot.protocol import DEFINITION_HASH
from tests.sim.conftest import avr_tools_missing

REPO = Path(__file__).resolve().parents[1]

SWARM_SCRIPT = """
import particlebot
with particlebot.Swarm.open("virtual://3?speed=max", log_dir="logs") as swarm:
    heard = swarm.wait_for(count=3, timeout=15)
    swarm.start(method="A")
    swarm.sleep(5)
    report = swarm.stop()
    print("particles", len(heard), "stopped", len(report.stopped))
"""


def run(command: list[str], cwd: Path, env: dict[str, str], timeout: float = 1200) -> str:
    result = subprocess.run(
        command, cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout, check=False
    )
    assert result.returncode == 0, f"{command} failed:\n{result.stdout}\n{result.stderr}"
    return result.stdout


@pytest.fixture(scope="module")
def installed(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, dict[str, str]]:
    """(the venv's bin folder, a working folder outside the clone, the environment to run in)."""
    if not resources.firmware_image().is_file():
        pytest.skip("no build/firmware/particle.hex: `make firmware` builds it")
    root = tmp_path_factory.mktemp("wheel")
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    env["PIP_DISABLE_PIP_VERSION_CHECK"] = "1"
    # numba compiles the world's kernels once for all the commands below.
    env["NUMBA_CACHE_DIR"] = str(root / "numba-cache")
    env["PARTICLEBOT_CACHE_DIR"] = str(root / "cache")
    dist = root / "dist"
    run(
        [sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", "-w", str(dist), str(REPO)],
        cwd=root,
        env=env,
    )
    (wheel,) = dist.glob("particlebot-*.whl")
    names = zipfile.ZipFile(wheel).namelist()
    for carried in (
        "particlebot/firmware/libparticle.so",
        "particlebot/_data/firmware/particle.hex",
        "particlebot/_data/firmware/particle.toml",
        "particlebot/_data/scenarios/blob-to-lamp.toml",
        "particlebot/sim/particles/emulated/particle_sim.c",
    ):
        assert carried in names
    target = root / "venv"
    venv.EnvBuilder(with_pip=True).create(target)
    bin_dir = target / "bin"
    run([str(bin_dir / "pip"), "install", "-q", str(wheel)], cwd=root, env=env)
    work = root / "work"
    work.mkdir()
    return bin_dir, work, env


# Installing the dependencies and numba's first compile of the world take minutes on a loaded
# machine; nothing here waits on a clock, so a long limit only guards against a hang.
@pytest.mark.e2e
@pytest.mark.timeout(3600)
def test_the_installed_package_uses_its_own_artefacts(
    installed: tuple[Path, Path, dict[str, str]],
) -> None:
    bin_dir, work, env = installed
    where = run(
        [
            str(bin_dir / "python"),
            "-c",
            "from particlebot import resources as r; import particlebot;"
            "print(particlebot.__file__); print(r.source_root()); print(r.native_library());"
            "print(r.firmware_manifest())",
        ],
        cwd=work,
        env=env,
    ).splitlines()
    assert not where[0].startswith(str(REPO)) and where[1] == "None"
    assert where[2].endswith("particlebot/firmware/libparticle.so")
    assert f"definition_hash={DEFINITION_HASH}" in where[3]
    version = run([str(bin_dir / "particlebot"), "--version"], cwd=work, env=env)
    assert f"{DEFINITION_HASH:08X}" in version


@pytest.mark.e2e
@pytest.mark.timeout(3600)
def test_demo_simulate_a_swarm_script_and_flash_help_run_outside_the_clone(
    installed: tuple[Path, Path, dict[str, str]],
) -> None:
    bin_dir, work, env = installed
    particlebot = str(bin_dir / "particlebot")
    demo = run(
        [
            particlebot,
            "demo",
            "--no-ui",
            "--json",
            "--particles",
            "3",
            "--run-s",
            "90",
            "--no-animation",
            "--no-log",
        ],
        cwd=work,
        env=env,
    )
    figures = json.loads(demo.strip().splitlines()[-1])
    assert figures["particles"] == 3 and figures["simulated_s"] >= 90

    scenario = run(
        [
            str(bin_dir / "python"),
            "-c",
            "from particlebot import resources; print(resources.scenarios_dir() / 'carry.toml')",
        ],
        cwd=work,
        env=env,
    ).strip()
    assert Path(scenario).is_file()
    simulate = [particlebot, "simulate", scenario, "--duration", "30"]
    simulate += ["--dump-interval", "10", "--gsd", "-o", "run"]
    run(simulate, cwd=work, env=env)
    tables = run(
        [
            str(bin_dir / "python"),
            "-c",
            "import particlebot; t = particlebot.read_run('run');"
            "print(t.source, len(t.track), sorted(set(t.frames['kind'])))",
        ],
        cwd=work,
        env=env,
    )
    assert tables.split()[:2] == ["trajectory.gsd", "4"]  # rows at 0, 10, 20 and 30 s
    assert "'object'" in tables and "'particle'" in tables

    (work / "swarm.py").write_text(SWARM_SCRIPT, encoding="utf-8")
    printed = run([str(bin_dir / "python"), "swarm.py"], cwd=work, env=env)
    assert "particles 3 stopped 3" in printed

    assert "--firmware" in run([particlebot, "flash", "--help"], cwd=work, env=env)


@pytest.mark.e2e
@pytest.mark.simavr
@pytest.mark.timeout(3600)
def test_emulated_particles_build_their_harness_into_the_cache(
    installed: tuple[Path, Path, dict[str, str]],
) -> None:
    if avr_tools_missing() is not None:
        pytest.skip("simavr is not installed")
    bin_dir, work, env = installed
    script = (
        "from particlebot.sim.particles.emulated.harness import ParticleSim, ensure_harness\n"
        "print(ensure_harness())\n"
        "with ParticleSim() as sim:\n"
        "    sim.run_for(20_000)\n"
        "    print(sim.cycle)\n"
    )
    harness, cycle = run([str(bin_dir / "python"), "-c", script], cwd=work, env=env).split()
    assert Path(harness).parent == Path(env["PARTICLEBOT_CACHE_DIR"])
    assert int(cycle) >= 20_000 * 8
