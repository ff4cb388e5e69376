"""The world's compiled inner loops (numba): servo, motion, contacts, magnets, friction, lists.

One concern per module, each importing only those above it in this list:

    layout    indices into the parameter vector and the per-particle rows, array types, the
              memory layout (its docstring), numba's thread pool started at import
    laws      force laws of one body or one pair: magnets, contacts, obstacles, friction
    motion    a step's first pass (servo, positions) and last (obstacles, objects, friction)
    objects   passive objects' own motion
    binning   grid cells, the re-ordering into cell order, the chunks' bounds
    lists     the half neighbour lists: build, rebuild rule, restore
    pairs     the pair pass: one at a time, or in vectorised blocks from lists or a grid
    stale     the published code's stale grid and its serial step loop
    step      the step loop (`advance`) and each pass over the chunks in parallel

Each pair is evaluated once (Newton's third law: i gets f, j gets -f), as the published code's
two one-sided evaluations give bit-identical opposite forces. The work is cut into chunks along
grid rows: a particle's listed neighbours lie in its own chunk or the next one, so the pair pass
runs the even chunks in parallel, then the odd ones, without atomics; every other pass writes
only its own chunk. Results do not depend on the number of threads.

numba's on-disk cache keys each compiled function on its own module's file: a kernel that
inlines or calls one from another module here is not recompiled when only that other module
changes. After editing a kernel module, clear the cache (the __pycache__ folders' *.nbi and
*.nbc files beside these modules, or NUMBA_CACHE_DIR) before measuring or trusting results.

This package's names are the World's interface to the kernels; the rest stay in their modules.
"""

from __future__ import annotations

from particlebot.sim.world.kernels.layout import (
    ACC_COLS,
    B_FA,
    B_FR,
    B_FX,
    B_FY,
    B_MAG,
    B_R,
    BODY_ROWS,
    DETACHED,
    F_ACTING,
    F_ALIVE,
    F_HELD,
    F_JOINED,
    F_KIND,
    FLAG_ROWS,
    FREE,
    MEMBER,
    O_FRICTION,
    O_INV_MASS,
    O_MAG,
    O_R,
    O_STATIC,
    O_VX,
    O_VY,
    O_X,
    O_Y,
    OBJECT_COLS,
    P_ATTRACTION,
    P_BLEND_GAP,
    P_CLAMP_FORCE,
    P_CLAMP_GAP,
    P_CONSTRAINED,
    P_CONTRACTION,
    P_CUTOFF,
    P_DAMPING,
    P_DT,
    P_FRICTION,
    P_HALF_WIDTH,
    P_LIST_RADIUS,
    P_MAX_SPEED,
    P_OBSTACLE_SPRING,
    P_REST_SPEED,
    P_RMAX,
    P_RMIN,
    P_SHEAR,
    P_SKIN,
    P_SPRING,
    P_STATIC,
    P_TORQUE,
    P_TOUCH_GAP,
    PARAM_COUNT,
    ByteArray,
    FloatArray,
    IntArray,
    ListArray,
)
from particlebot.sim.world.kernels.lists import SORT_EVERY, build_lists, restore_lists
from particlebot.sim.world.kernels.pairs import PAIR_BLOCK, PAIR_INDEX_ROWS, PAIR_VALUE_ROWS
from particlebot.sim.world.kernels.stale import (
    STALE_GRID,
    STALE_REACH,
    advance_stale,
    stale_index,
    stale_list,
)
from particlebot.sim.world.kernels.step import advance

__all__ = [
    "ACC_COLS",
    "BODY_ROWS",
    "B_FA",
    "B_FR",
    "B_FX",
    "B_FY",
    "B_MAG",
    "B_R",
    "DETACHED",
    "FLAG_ROWS",
    "FREE",
    "F_ACTING",
    "F_ALIVE",
    "F_HELD",
    "F_JOINED",
    "F_KIND",
    "MEMBER",
    "OBJECT_COLS",
    "O_FRICTION",
    "O_INV_MASS",
    "O_MAG",
    "O_R",
    "O_STATIC",
    "O_VX",
    "O_VY",
    "O_X",
    "O_Y",
    "PAIR_BLOCK",
    "PAIR_INDEX_ROWS",
    "PAIR_VALUE_ROWS",
    "PARAM_COUNT",
    "P_ATTRACTION",
    "P_BLEND_GAP",
    "P_CLAMP_FORCE",
    "P_CLAMP_GAP",
    "P_CONSTRAINED",
    "P_CONTRACTION",
    "P_CUTOFF",
    "P_DAMPING",
    "P_DT",
    "P_FRICTION",
    "P_HALF_WIDTH",
    "P_LIST_RADIUS",
    "P_MAX_SPEED",
    "P_OBSTACLE_SPRING",
    "P_REST_SPEED",
    "P_RMAX",
    "P_RMIN",
    "P_SHEAR",
    "P_SKIN",
    "P_SPRING",
    "P_STATIC",
    "P_TORQUE",
    "P_TOUCH_GAP",
    "SORT_EVERY",
    "STALE_GRID",
    "STALE_REACH",
    "ByteArray",
    "FloatArray",
    "IntArray",
    "ListArray",
    "advance",
    "advance_stale",
    "build_lists",
    "restore_lists",
    "stale_index",
    "stale_list",
]
