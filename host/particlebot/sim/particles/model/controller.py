"""The contract between the world and a vectorised controller: what it senses, what it commands."""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Protocol

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]


class WorldView(Protocol):
    """What the world lets a controller sense at the current step; every array has one entry per
    particle (index order is fixed for the whole run) and must be treated as read-only.

    The world computes these lazily and caches them for the step, so a controller that only
    re-estimates every few minutes pays for the light model only then.
    """

    @property
    def count(self) -> int:
        """N, the number of particles (the passive objects of a scenario are not particles)."""

    @property
    def t(self) -> float:
        """Simulated seconds since the run began."""

    @property
    def x(self) -> FloatArray:
        """Centre x (m)."""

    @property
    def y(self) -> FloatArray:
        """Centre y (m)."""

    @property
    def r_min(self) -> float:
        """Contracted radius (m)."""

    @property
    def r_max(self) -> float:
        """Fully expanded radius (m)."""

    def light_distance(self) -> FloatArray:
        """Ground distance (m) from each centre to the lamp's foot, as the published simulator's
        phase rule uses it; under shadow mode 1 a shadowed particle is reported beyond every lit
        one (it goes last)."""

    def light_readings(self) -> FloatArray:
        """Each particle's intensity V_n (0..1023, unrounded): eq. 11 of the SI for the lamp's
        straight-line distance, 0 where an obstacle shadows the particle (modes 1 and 2)."""

    def acting(self) -> BoolArray:
        """True where a particle may actuate now: alive, attached, and not held still by shadow
        mode 2. The world ignores what a controller commands the others: their radius stays
        where it is (the published model: a dead particle keeps the radius it died with; a free
        particle waits contracted)."""


@dataclass(frozen=True)
class CycleCommands:
    """Commands a GPU computes itself, for `rows` steps from step number `first`: particle i's
    radius at step s is the published cycle's at clock ((first + s) dt) mod cycle_s shifted by
    offset[i] (see published._radius_at): rising from r_min over rise_s, falling, then NaN."""

    rows: int
    first: int
    offset: FloatArray
    cycle_s: float
    rise_s: float


class Controller(ABC):
    """Decides every particle's commanded radius each step, vectorised over the swarm.

    The world calls bind() once before the first step, then command() every step with the view
    of that step. command() writes radii in metres into `out` (shape (N,), float64); the world
    clamps them to [r_min, r_max] and then applies the servo's stall limit, so a controller says
    what the servo is told, not where the body ends up. NaN tells a servo to hold where it is
    (the published controller's rest). Controllers draw randomness only from the generator
    bind() gives, so a run is reproduced by its seed; a snapshot stores a controller as data, so
    its state must be plain attributes, numpy arrays and types listed in sim.world.snapshot.TYPES.
    """

    @abstractmethod
    def bind(self, count: int, rng: np.random.Generator) -> None:
        """Sizes the controller's state for `count` particles; called once before the first step."""

    @abstractmethod
    def command(self, view: WorldView, out: FloatArray) -> None:
        """Writes every particle's commanded radius (m) for the step at view.t into out."""

    def command_ahead(self, view: WorldView, dt: float, out: FloatArray) -> int:
        """Optional fast path: fills out[j] (out has shape (k, N)) with the commands of the steps
        at view.t + j dt for as many rows as it can without sensing the world again, and returns
        how many (row 0 is this step, sensed through `view` as command() would). The world then
        runs those steps in one compiled call, which is what makes small swarms fast. Results must
        not depend on how the world cuts a run into blocks: compute step j's time as
        (round(view.t / dt) + j) x dt. The default, 0, means "not supported": command() is called
        every step."""
        return 0

    def cycle_ahead(self, view: WorldView, dt: float, rows: int) -> CycleCommands | None:
        """Optional GPU path: command_ahead's steps as a formula the GPU evaluates (no commands
        uploaded), for up to `rows` steps; None (the default) means "not supported", and the
        world uploads command_ahead's or command()'s rows."""
        return None

    def phase(self, view: WorldView) -> FloatArray:
        """Where each particle is in its cycle, 0..1 (NaN where it is not cycling); pictures colour
        particles by it. The default says nothing is known."""
        return np.full(view.count, np.nan)
