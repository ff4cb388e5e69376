"""The package's imports point down: each subpackage imports only from the layers below it, and no
module imports itself round a circle. Read from the source with ast, imports inside functions
(lazy ones) included, so that the layering cannot quietly regress."""

from __future__ import annotations

import ast
from collections import defaultdict
from pathlib import Path

import particlebot

PACKAGE = Path(particlebot.__file__).parent

LAYERS: tuple[frozenset[str], ...] = tuple(
    frozenset(layer.split())
    for layer in (
        "errors",  # the root of every error
        # helpers; where artefacts live; the protocol (shared/protocol.toml)
        "closing options toml_lines protocol devices resources fileio progress machine",
        # reset causes; the native firmware library; the fleet file; the MP4 writer
        "resets firmware fleet videowriter",
        "sim",  # the simulator: world, particles, air, runs, scenarios
        "radio",  # radios, real and simulated (a simulated radio drives sim)
        "session",  # frames over a radio
        "logs",  # session logs, replayed as a radio
        "swarm plots provision",  # the base station's model; figures; flashing
        "analysis console",  # tracks, videos and statistics; the console UI
        "studies",  # the paper's studies (filming runs reads them with the tracker)
        "experiments",  # scripted experiments on a swarm
        "calibration",  # the calibration bench
        "__init__",  # the package's public names (and its version)
        "commands cli",  # the command line
    )
)
"""Subpackages (and top-level modules) from the bottom up: one may import from its own and any
layer below, never from its own layer's others or from above."""


def unit(module: str) -> str:
    """The subpackage or top-level module a module belongs to ("__init__" for the package)."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else "__init__"


def modules() -> dict[str, Path]:
    found = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        name = ".".join(path.relative_to(PACKAGE.parent).with_suffix("").parts)
        found[name.removesuffix(".__init__")] = path
    return found


def imports() -> dict[str, set[str]]:
    """Each module's particlebot imports, as the modules they name (a name imported from a
    package that is itself a module counts as that module)."""
    known = modules()

    def resolve(name: str) -> str:
        while name not in known:
            name = name.rpartition(".")[0]
        return name

    graph: dict[str, set[str]] = defaultdict(set)
    for module, path in known.items():
        tree = ast.parse(path.read_text(encoding="utf-8"))
        # Imports under `if TYPE_CHECKING:` name types for annotations only and never run, so a
        # circle through one is no circle at run time.
        typing_only = {
            id(inner)
            for block in ast.walk(tree)
            if isinstance(block, ast.If) and ast.unparse(block.test).endswith("TYPE_CHECKING")
            for statement in block.body
            for inner in ast.walk(statement)
        }
        for node in ast.walk(tree):
            if id(node) in typing_only:
                continue
            names: list[str] = []
            if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                names = [f"{node.module}.{alias.name}" for alias in node.names]
            elif isinstance(node, ast.Import):
                names = [alias.name for alias in node.names]
            for name in names:
                if name.split(".")[0] == "particlebot" and resolve(name) != module:
                    graph[module].add(resolve(name))
    return graph


def layer_of(name: str) -> int:
    for index, layer in enumerate(LAYERS):
        if name in layer:
            return index
    raise AssertionError(f"{name} is in no layer of LAYERS: put it where it belongs")


def test_every_subpackage_imports_only_from_the_layers_below() -> None:
    wrong = []
    for module, targets in imports().items():
        here = unit(module)
        for target in targets:
            there = unit(target)
            if there != here and layer_of(there) >= layer_of(here):
                wrong.append(f"{module} imports {target}")
    assert not wrong, "imports that do not point down:\n" + "\n".join(sorted(wrong))


def test_no_module_imports_itself_round_a_circle() -> None:
    graph = imports()
    circles: list[list[str]] = []
    state: dict[str, int] = {}  # 1: on the current path, 2: done
    path: list[str] = []

    def visit(module: str) -> None:
        state[module] = 1
        path.append(module)
        for target in sorted(graph.get(module, ())):
            if state.get(target) == 1:
                circles.append([*path[path.index(target) :], target])
            elif target not in state:
                visit(target)
        path.pop()
        state[module] = 2

    for module in sorted(modules()):
        if module not in state:
            visit(module)
    assert not circles, "import circles:\n" + "\n".join(" -> ".join(c) for c in circles)


def test_the_check_sees_an_arrow_that_runs_back_up() -> None:
    graph = imports()
    assert "particlebot.sim.world.kernels.layout" in graph["particlebot.sim.world.kernels.step"]
    assert layer_of(unit("particlebot.analysis.tracker")) > layer_of(unit("particlebot.sim"))
    assert not any(unit(target) in ("analysis", "logs") for target in graph["particlebot.sim"])


LONGEST = 800
"""Lines a module may have; a longer one says why it is one piece (or that it is generated)."""


def test_no_module_is_longer_than_800_lines_unless_it_says_why() -> None:
    long = []
    for module, path in modules().items():
        text = path.read_text(encoding="utf-8")
        if text.count("\n") > LONGEST:
            purpose = ast.get_docstring(ast.parse(text)) or ""
            if "Generated" not in purpose and "one piece" not in purpose:
                long.append(f"{module}: {text.count(chr(10))} lines")
    assert not long, "modules too long to read as one concern:\n" + "\n".join(long)
