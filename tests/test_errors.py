"""Every exception class the package defines derives from ParticlebotError, and errors.py's tree
names it with its module. The classes are found by reading the source, so that none is missed."""

from __future__ import annotations

import ast
import builtins
import re
from pathlib import Path

import particlebot
from particlebot import ParticlebotError, errors

PACKAGE = Path(particlebot.__file__).parent


def _base_name(node: ast.expr) -> str | None:
    if isinstance(node, ast.Name):
        return node.id
    if isinstance(node, ast.Attribute):
        return node.attr
    return None


def class_bases() -> dict[str, list[str]]:
    """Every class the package defines ("module:Class") with its bases' names."""
    classes: dict[str, list[str]] = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        module = ".".join(path.relative_to(PACKAGE.parent).with_suffix("").parts)
        module = module.removesuffix(".__init__")
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ClassDef):
                names = [name for base in node.bases if (name := _base_name(base))]
                classes[f"{module}:{node.name}"] = names
    return classes


def ancestors(key: str, classes: dict[str, list[str]]) -> set[str]:
    """The names of a class's bases, theirs, and so on (a base defined here is followed)."""
    by_name: dict[str, list[str]] = {}
    for other in classes:
        by_name.setdefault(other.split(":")[1], []).append(other)
    found: set[str] = set()
    todo = [key]
    while todo:
        for base in classes[todo.pop()]:
            if base not in found:
                found.add(base)
                todo.extend(by_name.get(base, []))
    return found


def exception_classes() -> dict[str, set[str]]:
    """Each exception class the package defines, with its ancestors' names: a class is one if
    they include a built-in exception."""
    classes = class_bases()
    result: dict[str, set[str]] = {}
    for key in classes:
        names = ancestors(key, classes)
        for name in names:
            builtin = getattr(builtins, name, None)
            if isinstance(builtin, type) and issubclass(builtin, BaseException):
                result[key] = names
                break
    return result


def test_every_exception_class_derives_from_the_root() -> None:
    found = exception_classes()
    assert len(found) > 40  # the reading works
    assert "particlebot.radio.base:PortBusyError" in found  # through a base of its own
    for key, names in found.items():
        if key != "particlebot.errors:ParticlebotError":
            assert "ParticlebotError" in names, f"{key} does not derive from ParticlebotError"
    assert issubclass(particlebot.IdInUse, ParticlebotError)  # the reading agrees with Python


def test_the_tree_in_the_docstring_names_every_exception_class() -> None:
    lines = (errors.__doc__ or "").splitlines()
    for key in exception_classes():
        module, name = key.split(":")
        if name == "ParticlebotError":
            continue
        where = re.escape(module.removeprefix("particlebot."))
        line = re.compile(rf"\+-- {name}\b.* {where}$")
        assert any(line.search(text) for text in lines), f"{key} is not in errors.py's tree"
