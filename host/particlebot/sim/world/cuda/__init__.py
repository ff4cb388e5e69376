"""The world on a GPU (numba-cuda): the CPU model's passes as CUDA kernels, and ensembles.

`World(..., device="cuda")` (or "auto": CUDA when a real GPU is present) keeps the swarm's state
on the GPU between dumps; `Ensemble(worlds)` steps many independent worlds in one launch per
pass. Nothing requires a GPU: with NUMBA_ENABLE_CUDASIM=1 numba-cuda's simulator runs the same
kernels on the CPU (slowly), which is how the tests check them.

    device.py    which backend: "cpu", "cuda", "auto"; DeviceError
    laws.py      the laws as device functions (magnets, contact, servo, obstacles, friction,
                 the published cycle), operation for operation as the CPU kernels'
    kernels.py   the passes of a step, one thread per particle (or cell, swarm)
    swarms.py    the swarms' concatenated state on the device, the step loop, the copies
    ensemble.py  many Worlds stepped side by side
    ptx.py       compiles every kernel to PTX without a GPU (a check of the real target)

What runs on the GPU, every step: the published controller's commands (its cycle, from the
phase offsets the host sets at each phase update), the servo with its stall limit, motion and
the walls, free particles joining, the binning (a counting sort: count with atomics, a prefix
sum level by level, scatter, each cell's few members put in index order), the pairs (contact
spring, dashpot and shear; the magnets with clamp and blend), obstacles (rectangles, circles),
the particles' side of passive objects, static and sliding friction; the passive objects' own
motion and the sum of what the particles do to them (one thread per swarm, in index order).

What runs on the host, and when:
  * the controllers' decisions: the published controller's phase update (once a cycle: light
    distances, noise, who leads) and the firmware controller entirely (its rounds, and its
    commands every step, uploaded as one row of N floats a step: a firmware swarm steps as
    fast as the host commands it);
  * light readings and shadows (the arena's shadow test), when a controller senses; the host
    then copies the swarm back, marks the shadowed, and copies it up again;
  * choosing the dead particles (once, from the run's seed), placement (Algorithm 5, once, at
    build: the same positions on either backend by construction), snapshots and every output
    (the state comes back from the GPU only when something reads it: a dump, a snapshot).
  * Not on the GPU at all: the published stale grid (NeighbourSearch.PUBLISHED_STALE_GRID),
    refused with DeviceError.

Where the GPU's result may differ from the CPU's:
  * Summation order. The CPU evaluates each pair once (i gets f, j gets -f) and adds a
    particle's forces in its neighbour lists' order; the GPU evaluates each pair from both sides
    (exactly opposite forces: the arithmetic negates bit for bit) and adds them in cell order.
    A particle with at most one partner gets the same bits; with more, the sums may differ in
    the last bit. Passive objects: the CPU sums the particles' pushes chunk by chunk (16 chunks
    from 2,048 particles up), the GPU in index order (the CPU's order below 2,048 particles).
  * Fused multiply-add. NVVM contracts a * b + c into one rounding by default (the pair
    kernel's PTX for sm_90 has 8 fma.rn.f64), so on a real GPU even a lone pair may differ from
    the CPU in the last bits (numba-cuda's simulator, plain Python floats, does not contract:
    there the tests find the same bits).
  * float32: `precision="float32"` keeps velocities and force sums in float32 on both backends
    alike (positions stay float64); the compiled GPU kernels type the mixed arithmetic as
    numba's CPU kernels do. The simulator does not: it runs the kernels as Python on NumPy
    scalars, where float32 times a Python float stays float32 (NumPy 2's scalar rules), so in
    float32 its results part from the CPU's in the last bits at once (a lone pair: 9e-9 m after
    15 steps); its bit-for-bit checks are of float64.
  * Atomics only place particles in cells; the per-cell sort erases the order they came in, so
    a GPU run is deterministic: the same seed gives the same bits run after run.
  Measured in the simulator (a 30-particle actuating blob, 4 seeds): positions part from the
  CPU's by 1e-14 to 1e-12 m after 50 steps, up to 2e-8 m after 100, and 1 to 3.5 cm after 200
  to 300 steps, as far as float32 parts from float64 on the CPU over the same run (0.8 to 3.5
  cm): a packed, actuating swarm is chaotic, so any change of rounding parts single paths within
  seconds; the statistics do not move (tests/sim/world/cuda: a 12-particle swarm's drift over
  seeds within the CPU's spread).

Studies: `particlebot study NAME --device cuda` runs the pending runs as ensembles on the local
GPU (studies/batched.py: Table S3's 10,000-particle row, 99 runs, is one ensemble). With
--scheduler, each Dask worker runs its runs one at a time on the GPU it sees: start one worker
process per GPU with only that GPU visible, e.g. `CUDA_VISIBLE_DEVICES=1 dask worker ADDRESS
--nworkers 1 --nthreads 1`.
"""
