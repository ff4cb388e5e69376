"""Whether numba's cache holds the simulator's compiled kernels for this machine, and a warm-up
that compiles them (what `particlebot setup` runs, and commands run first when the cache is cold,
so that compiling is announced and never counted in a run's speed or ETA)."""

from __future__ import annotations

import importlib
import os
import sys
from collections.abc import Callable, Iterator
from dataclasses import replace
from typing import Any

COMPILE_USUAL_S = 150.0
"""Seconds a cold cache takes to fill on a 2-core machine (2 min 20 s to 2 min 37 s measured:
`make demo` from a fresh clone, the compile-afresh test). Said, not relied on."""

KERNEL_MODULES = (
    "particlebot.sim.world",
    "particlebot.sim.particles.model",
    "particlebot.sim.scenarios.placement",
)
"""The packages and modules whose numba kernels a simulation compiles."""

WARM_UP_SEED = 1
PARALLEL_EXTRA = 100
"""Particles beyond the world's PARALLEL_FROM for the warm-up's parallel swarm."""


def _kernel_modules() -> Iterator[Any]:
    """Every loaded module of the simulator that may hold kernels (importing the packages loads
    them: the world imports its kernels, the models theirs)."""
    for name in KERNEL_MODULES:
        importlib.import_module(name)
    importlib.import_module("particlebot.sim.scenarios.build")
    for name, module in list(sys.modules.items()):
        if module is not None and any(
            name == root or name.startswith(root + ".") for root in KERNEL_MODULES
        ):
            yield module


def simulator_kernels() -> dict[str, Any]:
    """name -> numba dispatcher of every cached, separately compiled kernel (not those inlined
    into their callers: numba never compiles those on their own, so the cache never holds them)."""
    from numba.core.registry import CPUDispatcher

    found: dict[str, Any] = {}
    for module in _kernel_modules():
        for attribute, value in vars(module).items():
            if not isinstance(value, CPUDispatcher) or value.__module__ != module.__name__:
                continue
            if value.targetoptions.get("inline", "never") == "always":
                continue
            if not hasattr(getattr(value, "_cache", None), "_cache_file"):
                continue  # not cache=True
            found[f"{module.__name__}.{attribute}"] = value
    return found


def _cached_here(dispatcher: Any, magic: tuple[Any, ...]) -> bool:
    """Whether the dispatcher's cache index holds a version compiled for this CPU and numba from
    this source. numba keys its index by (signature, the target machine's magic tuple, code
    hashes) and drops an index whose source stamp or numba version differs."""
    try:
        index = dispatcher._cache._cache_file._load_index()
    except Exception:  # a damaged index: numba recompiles, so count it as not cached
        return False
    return any(isinstance(key, tuple) and len(key) > 1 and key[1] == magic for key in index)


def uncached_kernels() -> list[str]:
    """Names of the simulator's kernels that the next run would have to compile."""
    from numba.core.registry import cpu_target

    magic = cpu_target.target_context.codegen().magic_tuple()
    return [
        name
        for name, dispatcher in simulator_kernels().items()
        if name not in NOT_WARMED and not _cached_here(dispatcher, magic)
    ]


def kernels_cached() -> bool:
    return not uncached_kernels()


NOT_WARMED: frozenset[str] = frozenset()
"""Kernels the warm-up does not reach (tests' helpers, float32-only paths): not looked at."""


def _stages() -> list[tuple[str, Callable[[], None]]]:
    from particlebot.sim.scenarios.build import build_world
    from particlebot.sim.scenarios.scenario import (
        ControllerKind,
        LampSpec,
        PlacementKind,
        Scenario,
        SwarmSpec,
    )
    from particlebot.sim.world.params import NeighbourSearch, PhysicsParams
    from particlebot.sim.world.world import PARALLEL_FROM, World

    def run(
        particles: int,
        controller: ControllerKind,
        placement: PlacementKind = PlacementKind.ALGORITHM5,
        search: NeighbourSearch = NeighbourSearch.EXACT,
    ) -> None:
        scenario = Scenario(
            name="warm-up",
            seed=WARM_UP_SEED,
            swarm=SwarmSpec(particles=particles, placement=placement),
            lamp=LampSpec(x=-3.0),
            physics=PhysicsParams(neighbour_search=search),
        )
        scenario = replace(scenario, controller=replace(scenario.controller, kind=controller))
        world = build_world(scenario).world
        world.step(3)
        world.state()
        world.centroid()
        # What `simulate --resume` does first in a fresh process.
        resumed = World.from_snapshot(world.snapshot())
        resumed.step(2)

    big = PARALLEL_FROM + PARALLEL_EXTRA
    return [
        ("published controller, 10 particles", lambda: run(10, ControllerKind.PUBLISHED)),
        ("firmware controller, 10 particles", lambda: run(10, ControllerKind.FIRMWARE)),
        (f"parallel path, {big:,} particles", lambda: run(big, ControllerKind.PUBLISHED)),
        (f"firmware controller, {big:,} particles", lambda: run(big, ControllerKind.FIRMWARE)),
        (
            "the published placement and neighbour search",
            lambda: run(
                10,
                ControllerKind.PUBLISHED,
                PlacementKind.ALGORITHM5_PUBLISHED,
                NeighbourSearch.PUBLISHED_STALE_GRID,
            ),
        ),
    ]


def warm_up(report: Callable[[int, int, str], None] | None = None) -> None:
    """Compiles (or loads) every kernel a simulation uses by running tiny worlds of each kind;
    report(done, total, stage) before each stage and at the end."""
    stages = _stages()
    for done, (label, stage) in enumerate(stages):
        if report is not None:
            report(done, len(stages), label)
        stage()
    if report is not None:
        report(len(stages), len(stages), "done")


def cache_folder() -> str:
    """Where numba keeps the compiled kernels: NUMBA_CACHE_DIR when set, else the __pycache__
    folders beside the simulator's sources (or, where those are read-only, the user's cache)."""
    import numba

    configured = numba.config.CACHE_DIR  # type: ignore[attr-defined]  # set at import
    if configured:
        return str(configured)
    folders = {str(d._cache.cache_path) for d in simulator_kernels().values()}
    if not folders:
        return "(no kernels found)"
    common = os.path.commonpath(sorted(folders))
    return common if len(folders) == 1 else f"__pycache__ folders under {common}"
