"""The `published` controller: the published simulator's light wave, vectorised over the swarm.

Every particle runs the same cycle of (nx + 1) rise periods: expand linearly from R_min to R_max
over one rise period, contract over the next, then rest (the servo is not told anything, so it
holds). Its phase is set from its 2-D distance to the lamp, 2 s of lag per contracted diameter
further than the nearest particle, so a wave of expansions runs from the lit side to the far side.
Phases are recomputed every `update_cycles` cycles (Algorithm 6's N; the published main: every
cycle) and then get Gaussian noise (sd 0.3 rise periods). Under shadow mode LAST a shadowed
particle gets phase -(nx - 1) rise periods (it goes last); under STILL the world holds it.

Sensor noise as Fig. S20 states it: at each phase update every particle's distance to the lamp
is off by a Gaussian error of `noise_diameters` contracted diameters.

One deviation, documented in README: the nearest distance d_min is taken over the particles that
may actuate (the published code takes every particle, dead ones included); it shifts all phases
by the same amount, so only where a wave starts inside the cycle changes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np

from particlebot.options import Bounds, check_fields
from particlebot.sim.particles.model.controller import (
    Controller,
    CycleCommands,
    FloatArray,
    WorldView,
)

_PARALLEL_FROM = 4096
"""Below this many particles the profile is filled inline (a parallel region costs more)."""
_TIME_TOLERANCE = 1e-6
"""Seconds: an update due at t is done at the step whose time is within this of t."""


_RANGES = {
    "rise_s": Bounds(minimum=1e-3, maximum=1e4),
    "nx": Bounds(minimum=1, maximum=1e6),
    "update_cycles": Bounds(minimum=1, maximum=1e6),
    "phase_noise": Bounds(minimum=0, maximum=1e3),
    "noise_diameters": Bounds(minimum=0, maximum=1e6),
}
"""A servo's rise takes a millisecond to hours; noise is a share of rise periods or diameters."""


@dataclass(frozen=True)
class PublishedSettings:
    """The published main's actuation numbers."""

    rise_s: float = 2.0
    """Expansion time (s); contraction takes as long."""
    nx: int = 5
    """The cycle is (nx + 1) rise periods: 12 s, an 8 s rest."""
    update_cycles: int = 1
    """Cycles between phase updates (Algorithm 6's N)."""
    phase_noise: float = 0.3
    """Sd of the Gaussian noise added to every phase at each update, in rise periods."""
    noise_diameters: float = 0.0
    """Sd of each particle's distance-estimation error, in contracted diameters (Fig. S20)."""

    def __post_init__(self) -> None:
        for name in ("nx", "update_cycles"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ValueError(f"{name} must be a whole number >= 1, not {value!r}")
        check_fields(self, _RANGES)

    @property
    def cycle_s(self) -> float:
        """One expansion-contraction cycle with its rest (s)."""
        return (self.nx + 1) * self.rise_s

    @property
    def update_s(self) -> float:
        """Time between phase updates (s)."""
        return self.update_cycles * self.cycle_s


@numba.njit(cache=True, inline="always")
def _radius_at(
    clock: float, offset: float, cycle: float, rise: float, r_min: float, stroke: float
) -> float:
    """The commanded radius at a point of the cycle (clock, in [0, cycle)) for a phase offset
    (in [0, cycle)): rising, falling, or NaN (rest: hold)."""
    tau = clock + offset
    if tau >= cycle:
        tau -= cycle
    if tau < rise:
        return r_min + stroke * tau / rise
    if tau < 2.0 * rise:
        return r_min + stroke * (2.0 - tau / rise)
    return math.nan


@numba.njit(parallel=True, cache=True)
def _fill(
    times: FloatArray,
    offset: FloatArray,
    cycle: float,
    rise: float,
    r_min: float,
    stroke: float,
    out: FloatArray,
) -> None:
    """out[j, i] = the commanded radius of particle i at times[j]; offset = phase mod cycle."""
    n = offset.shape[0]
    for j in range(times.shape[0]):
        clock = times[j] % cycle
        if n < _PARALLEL_FROM:
            for i in range(n):
                out[j, i] = _radius_at(clock, offset[i], cycle, rise, r_min, stroke)
        else:
            for i in numba.prange(n):
                out[j, i] = _radius_at(clock, offset[i], cycle, rise, r_min, stroke)


class PublishedController(Controller):
    """The published light-wave actuation (see the module's description)."""

    def __init__(self, settings: PublishedSettings | None = None) -> None:
        self.settings = settings if settings is not None else PublishedSettings()
        self._phase = np.zeros(0)
        self._offset = np.zeros(0)
        self._rng = np.random.default_rng()
        self._updates = 0

    @property
    def phases(self) -> FloatArray:
        """Each particle's phase offset (s) from the last update (a copy)."""
        return self._phase.copy()

    def bind(self, count: int, rng: np.random.Generator) -> None:
        self._phase = np.zeros(count)
        self._offset = np.zeros(count)
        self._rng = rng
        self._updates = 0

    def command(self, view: WorldView, out: FloatArray) -> None:
        self._update_if_due(view, view.t)
        self._fill(np.array([view.t]), view, out.reshape(1, -1))

    def command_ahead(self, view: WorldView, dt: float, out: FloatArray) -> int:
        first = round(view.t / dt)
        self._update_if_due(view, view.t)
        times = (first + np.arange(out.shape[0], dtype=np.float64)) * dt
        # Stop before the next update: it needs the world as it will be then.
        due = self._updates * self.settings.update_s - _TIME_TOLERANCE
        rows = max(1, int(np.searchsorted(times, due, side="left")))
        self._fill(times[:rows], view, out[:rows])
        return rows

    def cycle_ahead(self, view: WorldView, dt: float, rows: int) -> CycleCommands | None:
        first = round(view.t / dt)
        self._update_if_due(view, view.t)
        times = (first + np.arange(rows, dtype=np.float64)) * dt
        due = self._updates * self.settings.update_s - _TIME_TOLERANCE
        rows = max(1, int(np.searchsorted(times, due, side="left")))
        s = self.settings
        return CycleCommands(rows, first, self._offset, s.cycle_s, s.rise_s)

    def phase(self, view: WorldView) -> FloatArray:
        s = self.settings
        tau = np.mod(view.t + self._phase, s.cycle_s)
        cycling = (tau < 2 * s.rise_s) & view.acting()
        return np.where(cycling, tau / s.cycle_s, np.nan)

    def _update_if_due(self, view: WorldView, t: float) -> None:
        if t >= self._updates * self.settings.update_s - _TIME_TOLERANCE:
            self._update(view)
            self._updates = math.floor(t / self.settings.update_s + _TIME_TOLERANCE) + 1

    def _update(self, view: WorldView) -> None:
        """New phases from the distances to the lamp, with sensor and phase noise."""
        s = self.settings
        diameter = 2.0 * view.r_min
        distance = view.light_distance().copy()
        distance += self._rng.normal(0.0, s.noise_diameters * diameter, view.count)
        lit = view.light_readings() > 0
        leaders = lit & view.acting()
        nearest = float(distance[leaders].min()) if leaders.any() else 0.0
        phase = (nearest - distance) / diameter * s.rise_s
        phase[~lit] = -(s.nx - 1) * s.rise_s
        phase += self._rng.normal(0.0, s.phase_noise * s.rise_s, view.count)
        self._phase = phase
        self._offset = np.mod(phase, s.cycle_s)

    def _fill(self, times: FloatArray, view: WorldView, out: FloatArray) -> None:
        s = self.settings
        r_min = view.r_min
        _fill(times, self._offset, s.cycle_s, s.rise_s, r_min, view.r_max - r_min, out)
