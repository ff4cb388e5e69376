"""What one run of a study is (a small picklable spec with a stable id) and what comes back."""

from __future__ import annotations

import hashlib
import json
from collections.abc import Callable
from dataclasses import asdict, dataclass, field, fields, is_dataclass
from typing import Any, ClassVar, Protocol

import numpy as np
import numpy.typing as npt

from particlebot.studies.published import DT_S

FloatArray = npt.NDArray[np.float64]
CellValue = int | float | str
ShareDone = Callable[[float], None]
"""Told how far a run is, as the share of its steps done (0 to 1), as often as the run likes."""


@dataclass(frozen=True)
class Rect:
    """An axis-aligned rectangular obstacle (m)."""

    x_min: float
    x_max: float
    y_min: float
    y_max: float


@dataclass(frozen=True)
class Circle:
    """A circular obstacle (m)."""

    x: float
    y: float
    radius: float


@dataclass(frozen=True)
class PassiveObject:
    """A disc the swarm may push: centre (m) and the published factors (radius x the contracted
    particle radius; mass, friction and magnetic attraction x a particle's)."""

    x: float
    y: float
    radius_factor: float
    mass_factor: float = 1.0
    friction_factor: float = 1.0
    attraction_factor: float = 0.0


@dataclass(frozen=True)
class WorldSetup:
    """Everything the simulator needs to reproduce one run, and nothing bulky.

    It mirrors the simulator's scenario field by field; the seam (studies/seam.py) translates.
    Coordinates are in metres in the study frame: the origin is the swarm's initial centroid
    (after placement), so that the paper's "2.5 DPD from the initial centroid" is a number here.
    """

    particles: int
    seed: int
    duration_s: float
    lamp_x: float
    lamp_y: float = 0.0
    lamp_height: float | None = None
    """None: the simulator's default lamp height."""
    placement: str = "blob"
    """'blob' (Algorithm 5), 'hex' (hexagonal blob) or 'line'."""
    rects: tuple[Rect, ...] = ()
    circles: tuple[Circle, ...] = ()
    passive_object: PassiveObject | None = None
    dead: int = 0
    """Particles chosen at random (from the seed) that stop actuating at dead_at_s."""
    dead_at_s: float = 0.0
    detach_dead: bool = False
    """Dead particles let go of their neighbours (Fig. S21) instead of being dragged along."""
    free_particles: int = 0
    """Loose particles scattered in free_region, which the robot may annex (Fig. S21)."""
    free_region: Rect | None = None
    shadow: str = "ignore"
    """What an obstacle between a particle and the lamp does: 'ignore', 'last' (the particle
    reads no light and goes last in the wave: the gap study, SI S9) or 'still'."""
    controller: str = "published"
    noise_diameters: float = 0.0
    """The controller's distance-estimation error, sd in minimum particle diameters (Fig. S20)."""
    dump_interval_s: float = 60.0
    """Rows of the centroid track (the published CSV's interval) at most this far apart: a run
    whose duration is not a multiple of it gets rows a little closer, so that the last row is
    the run's end (a 20 s run would otherwise leave only its start to measure)."""
    per_particle: bool = False
    """Every particle's position and radius in each CSV row (the published `testing 1`): what
    filming the run needs (studies.camera)."""
    overrides: tuple[tuple[str, float], ...] = ()
    """Published numbers changed for this run, (name, value) pairs: fields of the world's
    PhysicsParams (static_factor, shear, magnet_cutoff, ...) and the published controller's
    phase_noise and update_cycles (`particlebot study --set`)."""


@dataclass(frozen=True)
class Track:
    """The centroid of every particle against time: the published CSV's columns."""

    time_s: FloatArray
    centroid_x: FloatArray
    centroid_y: FloatArray
    distance_m: FloatArray
    """Ground distance from the centroid to the lamp."""

    def to_json(self) -> dict[str, list[float]]:
        return {
            "time_s": self.time_s.tolist(),
            "centroid_x": self.centroid_x.tolist(),
            "centroid_y": self.centroid_y.tolist(),
            "distance_m": self.distance_m.tolist(),
        }

    @staticmethod
    def from_json(data: dict[str, list[float]]) -> Track:
        return Track(
            np.asarray(data["time_s"], dtype=float),
            np.asarray(data["centroid_x"], dtype=float),
            np.asarray(data["centroid_y"], dtype=float),
            np.asarray(data["distance_m"], dtype=float),
        )


@dataclass(frozen=True)
class SimOutcome:
    """What a run leaves for the measures, on the worker: the track, where every particle ended
    (robot, dead and free particles, in the study frame), the passive object's start and end, and
    the simulator's own summary (steps, wall time, ...)."""

    track: Track
    final_xy: FloatArray
    object_start: tuple[float, float] | None = None
    object_end: tuple[float, float] | None = None
    summary: dict[str, float] = field(default_factory=dict)


class Measure(Protocol):
    """How a run's outcome becomes a study's numbers (studies.measures holds the studies'
    measures): a frozen dataclass, whose fields are its parameters (they enter the run's
    fingerprint), with evaluate. Specs depend on this, not on the measures themselves."""

    __dataclass_fields__: ClassVar[dict[str, Any]]

    def evaluate(self, setup: WorldSetup, outcome: SimOutcome) -> dict[str, float]:
        """The numbers, by name; MeasureError when the outcome lacks what they need."""
        ...


@dataclass(frozen=True)
class RunSpec:
    """One run of a study: which cell of the study it belongs to, the world to simulate, and how
    to measure the outcome. Small and picklable: this is what travels to a worker."""

    study: str
    cell: tuple[tuple[str, CellValue], ...]
    """The study's coordinates of this run, e.g. (("particles", 100), ("dead_fraction", 0.2))."""
    seed: int
    setup: WorldSetup
    measure: Measure
    """How the outcome becomes the study's numbers (studies.measures)."""

    @property
    def cell_dict(self) -> dict[str, CellValue]:
        return dict(self.cell)

    @property
    def fingerprint(self) -> str:
        """Hash of everything that determines the result: the setup and the measure. Fields at
        their defaults are left out, so that a field added later (with a default that keeps the
        old behaviour) leaves every stored run id as it was."""
        setup = {
            f.name: value
            for f in fields(self.setup)
            if (value := getattr(self.setup, f.name)) != f.default
        }
        return fingerprint({"setup": _plain(setup), "measure": describe(self.measure)})

    @property
    def run_id(self) -> str:
        """Readable and stable: study, cell, seed, and the fingerprint's first 10 hex digits, so
        that a run whose setup changed (another duration, say) is never mistaken for this one."""
        parts = [self.study]
        for name, value in self.cell:
            parts.append(f"{_ID_NAMES.get(name, name)}{_id_value(value)}")
        parts.append(f"s{self.seed}")
        return "-".join(parts) + "-" + self.fingerprint[:10]

    @property
    def cost(self) -> float:
        """Particle-steps: what the run costs, for ETAs and for starting the longest runs first."""
        bodies = self.setup.particles + self.setup.free_particles
        return bodies * self.setup.duration_s / DT_S


_ID_NAMES = {
    "particles": "n",
    "dead_fraction": "dead",
    "gap_fraction": "gap",
    "radius_fraction": "obj",
    "noise_diameters": "noise",
    "free_ratio": "free",
}


def _id_value(value: CellValue) -> str:
    if isinstance(value, float):
        return f"{value:g}"
    return str(value)


def _plain(value: Any) -> Any:
    """Dataclasses and tuples inside a setup as JSON-ready dicts and lists."""
    if is_dataclass(value) and not isinstance(value, type):
        return asdict(value)
    if isinstance(value, dict):
        return {key: _plain(item) for key, item in value.items()}
    if isinstance(value, tuple | list):
        return [_plain(item) for item in value]
    return value


def describe(measure: Measure) -> dict[str, Any]:
    """A measure as plain data: its kind and parameters."""
    return {"kind": type(measure).__name__, **asdict(measure)}


def fingerprint(data: dict[str, Any]) -> str:
    """SHA-256 of canonical JSON (sorted keys, shortest float repr): the same on every machine."""
    text = json.dumps(data, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()


@dataclass(frozen=True)
class RunRecord:
    """One finished run as the results folder keeps it: one JSON file per run."""

    run_id: str
    study: str
    cell: dict[str, CellValue]
    seed: int
    runner: str
    """Who produced it ('simulator', or 'stand-in' in tests): a resumed study only counts runs its
    own runner made."""
    metrics: dict[str, float]
    summary: dict[str, float]
    track: dict[str, list[float]]
    setup: dict[str, Any]
    measure: dict[str, Any]
    wall_s: float
    worker: str
    pid: int

    def to_json(self) -> dict[str, Any]:
        return asdict(self)

    @staticmethod
    def from_json(data: dict[str, Any]) -> RunRecord:
        return RunRecord(**data)
