"""The command starts at once: `--help` of particlebot and of every subcommand loads neither the
simulator nor its heavy libraries, and the package declares every library it imports."""

from __future__ import annotations

import ast
import os
import subprocess
import sys
import tomllib
from importlib.metadata import packages_distributions, requires
from pathlib import Path

import pytest
from packaging.requirements import Requirement

from particlebot.cli import COMMANDS

REPO = Path(__file__).resolve().parents[1]
HEAVY = ("numba", "scipy", "pandas", "matplotlib", "cv2", "dask", "distributed", "gsd")


def imported_modules(argv: list[str]) -> set[str]:
    """Every module `python -X importtime -m particlebot.cli ARGV` imports."""
    env = {**os.environ, "PYTHONPATH": str(REPO / "host")}
    result = subprocess.run(
        [sys.executable, "-X", "importtime", "-m", "particlebot.cli", *argv],
        capture_output=True,
        text=True,
        env=env,
        check=False,
    )
    assert result.returncode == 0, result.stderr[-2000:]
    assert "usage: particlebot" in result.stdout
    lines = [line for line in result.stderr.splitlines() if line.startswith("import time:")]
    assert lines, "python printed no import times"
    return {line.rsplit("|", 1)[1].strip() for line in lines[1:]}


@pytest.mark.parametrize("command", [None, *COMMANDS])
def test_help_imports_no_simulator(command: str | None) -> None:
    modules = imported_modules([command, "--help"] if command else ["--help"])
    assert "particlebot.cli" in modules or "particlebot" in modules
    heavy = sorted(m for m in modules if m.split(".")[0] in HEAVY)
    assert not heavy, f"--help imports {heavy[:5]}"
    assert not [m for m in modules if m.startswith("particlebot.sim")]


def test_every_imported_library_is_declared() -> None:
    project = tomllib.loads((REPO / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    declared: set[str] = set()
    for line in project["dependencies"]:
        requirement = Requirement(line)
        declared.add(requirement.name.lower())
        for extra in requirement.extras:  # dask[distributed] brings distributed
            for dependency in map(Requirement, requires(requirement.name) or []):
                marker = dependency.marker
                if marker is not None and marker.evaluate({"extra": extra}):
                    declared.add(dependency.name.lower())
    roots: set[str] = set()
    for path in (REPO / "host" / "particlebot").rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Import):
                roots.update(alias.name.split(".")[0] for alias in node.names)
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                roots.add(node.module.split(".")[0])
    distributions = packages_distributions()
    third_party = roots - set(sys.stdlib_module_names) - {"particlebot"}
    undeclared = {
        module: distributions.get(module)
        for module in third_party
        if not {name.lower() for name in distributions.get(module, [module])} & declared
    }
    assert not undeclared
