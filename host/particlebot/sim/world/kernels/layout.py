"""The kernels' shared vocabulary: indices into the parameter vector and the per-particle rows,
the particle kinds, passive objects' columns, the array types, the pair arithmetic's fast-math
flags and the unsigned slot index every pass uses. Every kernel module imports this one first,
which starts numba's thread pool (see below).

Memory layout (structure of arrays, rows of 2-D arrays, particles in *internal* order): at a
list build the particles are put in grid-cell order (row by row), so that a particle's neighbours
sit close to it in memory (a large swarm rebuilding at every step does so at every SORT_EVERY-th
build, and the pair pass reaches them through the grid's order in between); `ext[i]` is the
caller's index of internal slot i. Passive objects (few, possibly huge discs) live in their own
array and meet every particle directly.

    pos     float64 (2, N)  x, y            ref  float64 (2, N)  x, y at the last list build
    vel     F       (2, N)  vx, vy (the first pass reflects it at walls, the last sets it;
                            the force passes between read it as the step's old velocity)
    body    F       (6, N)  r, contact-force sum, attraction sum, magnet factor (1, or 0 once
                            detached), force x, force y (the last two a step's own: zero
                            between steps; the pair passes add into them, the last pass reads
                            and clears them)
    flags   uint8   (5, N)  kind (MEMBER / FREE / DETACHED), acting, joined, alive, held
    nbr     int32   (N, M)  half neighbour lists: j > i within the list radius, counts in ncount

F is float64 or float32 (the World's `precision`; positions are always float64: float32 cannot
resolve a 10 um step 100 m from the origin).
"""

from __future__ import annotations

import os

import numba
import numpy as np
import numpy.typing as npt

# Start numba's thread pool before any kernel is compiled or loaded. Starting it registers the
# parallel scheduler's symbols (allocate_sched, ...) with LLVM; kernels that reach a parallel
# region link against them, and a small swarm never starts the pool itself. `simulate --resume`
# of a small swarm calls restore_lists first: compiled in such a process and loaded from numba's
# cache by the next, it segfaulted; compiled against cached kernels, it failed with "LLVM ERROR:
# Symbol not found: allocate_sched" (the kind of numba issue #2439). test_compiled_afresh.py.
# Every kernel module imports this one, so the pool is up before any of them is first called.
#
# The pool is numba's OpenMP layer on GNU libgomp, which reads its environment once, as it loads.
# Its workers spin 300,000 times at each barrier and after each parallel region before they sleep.
# Where other processes hold the cores, that spinning takes the core from the very thread a
# barrier waits for, and from everyone else between regions: beside two busy loops on two cores,
# a 10,000-particle step on two threads had calls stalled for 1.4 s and ran at 1.9-4.0 ms a
# step, and even one thread slowed to 2.8-5.8 ms (the idle worker still spinning). With 10,000
# spins: 1.6 ms on one thread, 1.9 on two, no stall, and an idle machine's two-thread step is
# unchanged (0.50 against 0.48 ms); OMP_WAIT_POLICY=passive also ends the stalls but doubles the
# idle step (1.15 ms). A user's own GOMP_SPINCOUNT or OMP_WAIT_POLICY is kept.
SPIN_COUNT = "10000"
if "GOMP_SPINCOUNT" not in os.environ and "OMP_WAIT_POLICY" not in os.environ:
    os.environ["GOMP_SPINCOUNT"] = SPIN_COUNT
numba.get_num_threads()


# ---- indices into the parameter vector `prm` (float64) -------------------------------------
P_DT = 0
P_RMIN = 1
P_RMAX = 2
P_SPRING = 3
P_DAMPING = 4
P_SHEAR = 5
P_OBSTACLE_SPRING = 6
P_ATTRACTION = 7
P_CLAMP_FORCE = 8
P_CLAMP_GAP = 9
P_BLEND_GAP = 10
P_CUTOFF = 11
P_FRICTION = 12  # mu x g: sliding deceleration
P_STATIC = 13  # force a particle at rest resists
P_REST_SPEED = 14
P_MAX_SPEED = 15
P_TORQUE = 16
P_CONSTRAINED = 17
P_CONTRACTION = 18
P_HALF_WIDTH = 19
P_SKIN = 20
P_LIST_RADIUS = 21
P_TOUCH_GAP = 22
PARAM_COUNT = 23

# ---- rows ----------------------------------------------------------------------------------
B_R = 0
B_FR = 1
B_FA = 2
B_MAG = 3
B_FX = 4
B_FY = 5
BODY_ROWS = 6

F_KIND = 0
F_ACTING = 1
F_JOINED = 2
F_ALIVE = 3
F_HELD = 4
FLAG_ROWS = 5

MEMBER = 0
FREE = 1
DETACHED = 2

# Passive objects: one row per object.
O_X = 0
O_Y = 1
O_VX = 2
O_VY = 3
O_R = 4
O_INV_MASS = 5
O_FRICTION = 6  # its sliding deceleration (mu x friction factor x g x mass factor)
O_STATIC = 7  # force it resists at rest (static_factor x that x mass)
O_MAG = 8
OBJECT_COLS = 9

# Per-chunk reduction of what particles do to object m: fx, fy.
ACC_COLS = 2

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
ByteArray = npt.NDArray[np.uint8]
ListArray = npt.NDArray[np.int32]

# Pair arithmetic may be reassociated and contracted (FMA); nothing in it tests for NaN. Only
# the one-at-a-time pair pass of small swarms (_pairs_each) and the published stale grid use it.
# The block pair pass of large swarms (_pairs, _pairs_cells and what they call) is plain IEEE
# arithmetic: with fast-math it came out of a fresh compilation differently optimised than out
# of numba's cache, so a seeded 3,000-particle swarm took a different path the first time it
# ran on a machine than every time after (last bits at step 5, metres after 500 steps). Plain
# arithmetic measured as fast (200,000 particles, boiling: 105-115 ns a particle-step on one
# thread either way). Small swarms came out the same both ways (500 and 1,500 particles; tests
# pin their paths). test_compiled_afresh.py guards it.
_FAST = {"contract", "arcp", "nsz", "reassoc"}


@numba.njit(cache=True, inline="always")
def _slot(i: int) -> int:
    """A particle's slot as an unsigned index. Numba checks every signed index for a negative
    value (to count it from the end), on every access: a loop over range(lo, hi) cannot tell it
    never is. An unsigned index it takes as is (a plain copy loop: 0.64 -> 0.33 ns an element).
    Only for indexing: uint64 mixed with int64 arithmetic gives float64 in numba."""
    return numba.uint64(i)  # type: ignore[return-value]
