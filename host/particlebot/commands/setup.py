"""`particlebot setup`: compiles the simulator's kernels into numba's cache ahead of the first
simulation, with progress, so that no later command spends its first minutes compiling."""

from __future__ import annotations

import argparse

DESCRIPTION = """\
Compiles the simulator's numba kernels (every kind of swarm a simulation runs: the published
and the firmware controller, small swarms and the parallel path) into numba's cache, and says
where the cache is. A command that finds the cache cold compiles them itself first; this does it
ahead of time (after an install, an upgrade, or a change of CPU). NUMBA_CACHE_DIR moves the
cache."""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.description = DESCRIPTION
    parser.add_argument(
        "--force", action="store_true", help="compile again even if the cache holds them"
    )
    parser.add_argument(
        "--check",
        action="store_true",
        help="compile nothing: exit 0 when the cache holds every kernel, 1 when not",
    )


def run(args: argparse.Namespace) -> int:
    from particlebot.commands._kernels import prepare_kernels
    from particlebot.sim.warmup import cache_folder, uncached_kernels

    if args.check:
        missing = uncached_kernels()
        if missing:
            print(f"{len(missing)} of the simulator's kernels are not compiled yet: run "
                  "`particlebot setup`")  # fmt: skip
            return 1
        print(f"the simulator's kernels are compiled, in {cache_folder()}")
        return 0
    try:
        compiled = prepare_kernels(force=args.force)
    except KeyboardInterrupt:
        print("particlebot: setup: stopped; what was compiled stays cached")
        return 130
    if not compiled:
        print(f"the simulator's kernels are compiled already, in {cache_folder()}")
    return 0
