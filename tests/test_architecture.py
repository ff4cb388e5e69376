"""The import rules of the architecture page hold: every import in the package is one its table
allows, so the page and the code cannot drift apart."""

from __future__ import annotations

import ast
import re
from pathlib import Path

from tests.support.repo import REPO_ROOT

ROOT = REPO_ROOT
PACKAGE = ROOT / "host" / "particlebot"
PAGE = ROOT / "docs" / "architecture.md"


def rules() -> tuple[set[str], dict[str, set[str] | None]]:
    """The foundations and, per package, what it may import (None: everything), from the page."""
    text = PAGE.read_text(encoding="utf-8")
    section = text[text.index("## What each package may import") :]
    section = section[: section.index("\n## ", 1)]
    foundations_line = re.search(r"The foundations \(([^)]*)\)", section)
    assert foundations_line is not None, "the page no longer names the foundations"
    foundations = set(re.findall(r"`([a-z_.]+)`", foundations_line.group(1)))
    allowed: dict[str, set[str] | None] = {}
    for row in re.findall(r"^\| `([a-z_.]+)` \| (.*) \|$", section, re.M):
        package, may = row
        if may.startswith("everything"):
            allowed[package] = None
        else:
            # Only the names before a parenthesis are rules; what follows explains them.
            allowed[package] = set(re.findall(r"`([a-z_.]+)`", re.sub(r"\(.*?\)", "", may)))
    assert len(allowed) > 10, "the page's table of imports was not found"
    return foundations, allowed


def package_of(module: str) -> str:
    """particlebot.sim.world.kernels -> sim.world; particlebot.swarm.api -> swarm."""
    parts = module.split(".")[1:]
    if not parts:
        return "particlebot"
    if parts[0] == "sim" and len(parts) > 1:
        return f"sim.{parts[1]}"
    return parts[0]


def module_name(path: Path) -> str:
    relative = path.relative_to(PACKAGE.parent).with_suffix("")
    parts = list(relative.parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def imports() -> set[tuple[str, str, str]]:
    """(importing package, imported package, file) for every import of particlebot in it."""
    found = set()
    for path in sorted(PACKAGE.rglob("*.py")):
        source = package_of(module_name(path))
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Import):
                names = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom) and node.module == "particlebot":
                # `from particlebot import resources` imports the module particlebot.resources.
                names = [
                    f"particlebot.{alias.name}"
                    if (PACKAGE / f"{alias.name}.py").is_file() or (PACKAGE / alias.name).is_dir()
                    else "particlebot"
                    for alias in node.names
                ]
            elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                names = [node.module]
            else:
                continue
            for name in names:
                if name == "particlebot" or name.startswith("particlebot."):
                    target = package_of(name)
                    if target != source:
                        found.add((source, target, str(path.relative_to(ROOT))))
    return found


def violations() -> dict[tuple[str, str], list[str]]:
    foundations, allowed = rules()
    wrong: dict[tuple[str, str], list[str]] = {}
    for source, target, where in imports():
        if source in foundations:
            ok = target in foundations
        elif source not in allowed:
            ok = False
        else:
            may = allowed[source]
            ok = may is None or target in foundations or target in may
        if not ok:
            wrong.setdefault((source, target), []).append(where)
    return wrong


def test_every_package_has_a_row() -> None:
    foundations, allowed = rules()
    packages = {package_of(module_name(path)) for path in PACKAGE.rglob("*.py")}
    missing = sorted(packages - foundations - set(allowed))
    assert not missing, f"docs/architecture.md has no import rule for {missing}"


def test_every_import_is_one_the_architecture_page_allows() -> None:
    wrong = violations()
    assert not wrong, "imports docs/architecture.md does not allow:\n" + "\n".join(
        f"  {source} -> {target}: {', '.join(sorted(files))}"
        for (source, target), files in sorted(wrong.items())
    )
