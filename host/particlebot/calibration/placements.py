"""Where the particles go for each reading of a calibration, and who puts them there: the person
at the bench (told what to do, Enter when done), or the tool itself on a simulated swarm."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Protocol, TextIO

import numpy as np

from particlebot.calibration.prompts import Prompter
from particlebot.experiments.measure import place
from particlebot.radio import Radio
from particlebot.swarm.campaigns import ids_text

PLACEMENT_JITTER_M = 0.004
"""A person puts a particle on its mark within a few millimetres; simulated placements do too
(seeded), so repeated trials differ as real ones do."""


@dataclass(frozen=True)
class Placement:
    """Step `step` of `steps`: particle id -> floor distance (cm) from the point under the lamp
    (its centre's), or every particle at `lux` at its photocells (distances then empty)."""

    step: int
    steps: int
    ids: tuple[int, ...]
    distances_cm: dict[int, float]
    instruction: str
    lux: float | None = None
    title: str = "Step"

    @property
    def heading(self) -> str:
        return f"{self.title} {self.step} of {self.steps}"


def _cm(value: float) -> str:
    return f"{value:g} cm"


def ring(ids: Sequence[int], distances_cm: Sequence[float]) -> list[Placement]:
    """Every particle at each distance in turn, on a circle around the point under the lamp."""
    who = f"particle{'s' if len(ids) > 1 else ''} {ids_text(list(ids))}"
    return [
        Placement(
            step,
            len(distances_cm),
            tuple(ids),
            dict.fromkeys(ids, distance),
            f"put {who} on a circle {_cm(distance)} from the point under the lamp (their "
            "centres, along the floor), each the same way round (A0 facing away from the lamp)",
        )
        for step, distance in enumerate(distances_cm, start=1)
    ]


def lux_levels(ids: Sequence[int], levels: Sequence[float]) -> list[Placement]:
    """Every particle where a lux meter reads each level in turn (distances unknown)."""
    who = f"particle{'s' if len(ids) > 1 else ''} {ids_text(list(ids))}"
    return [
        Placement(
            step,
            len(levels),
            tuple(ids),
            {},
            f"put {who} where a lux meter at the photocells' height reads {lux:g} lx",
            lux=lux,
        )
        for step, lux in enumerate(levels, start=1)
    ]


def line(ids: Sequence[int], slots_cm: Sequence[float], steps: int) -> list[Placement]:
    """The particles in a line at the given slots (one each, in id order first), moved on by
    one slot each step: the far one comes to the front, so each particle sees `steps` slots."""
    if len(slots_cm) != len(ids):
        raise ValueError(
            f"a line needs one distance per particle: {len(slots_cm)} distances for "
            f"{len(ids)} particles ({ids_text(list(ids))})"
        )
    placements = []
    count = len(ids)
    for step in range(steps):
        order = [ids[(slot - step) % count] for slot in range(count)]
        where = dict(zip(order, slots_cm, strict=True))
        spots = ", ".join(f"{pid} at {_cm(where[pid])}" for pid in order)
        how = "" if step == 0 else " (the far one to the front, the others out one place)"
        placements.append(
            Placement(
                step + 1,
                steps,
                tuple(ids),
                where,
                f"the line from the point under the lamp{how}: {spots}",
            )
        )
    return placements


def trials(ids: Sequence[int], positions_cm: Sequence[float], count: int) -> list[Placement]:
    """Fig. S5's experiment: the same line `count` times, put down afresh for each trial."""
    if len(positions_cm) != len(ids):
        raise ValueError(
            f"one position per particle: {len(positions_cm)} positions for {len(ids)} "
            f"particles ({ids_text(list(ids))})"
        )
    where = dict(zip(ids, positions_cm, strict=True))
    spots = ", ".join(f"{pid} at {_cm(where[pid])}" for pid in ids)
    return [
        Placement(
            trial,
            count,
            tuple(ids),
            where,
            ("lay out" if trial == 1 else "lift the line and lay it out again")
            + f" from the point under the lamp: {spots}",
            title="Trial",
        )
        for trial in range(1, count + 1)
    ]


def reference(particle_id: int, lamp_height_cm: float) -> Placement:
    """Method A's reference point: one particle right under the lamp."""
    return Placement(
        1,
        1,
        (particle_id,),
        {particle_id: 0.0},
        f"put particle {particle_id} at the reference point, right under the lamp (its "
        f"photocells {_cm(lamp_height_cm)} below the lamp's centre)",
        title="Reference",
    )


class Placer(Protocol):
    def place(self, placement: Placement) -> None:
        """Returns once the particles are where placement says (Quit when the person quits)."""


class PersonPlacer:
    """Tells the person what to do and waits for Enter."""

    def __init__(
        self, prompter: Prompter, out: TextIO, keep_alive: Callable[[], None] | None = None
    ) -> None:
        self.prompter = prompter
        self.out = out
        self.keep_alive = keep_alive

    def place(self, placement: Placement) -> None:
        print(f"{placement.heading}: {placement.instruction}.", file=self.out, flush=True)
        self.prompter.confirm("  then press Enter (q quits) ", self.keep_alive)


class SimulatedPlacer:
    """Puts simulated particles where a placement says, as a person would (a few mm off). A
    ring's particles all go to one spot on the line away from the lamp: the light model casts no
    shadows, so each reads what it would on its own spot of the circle, A0 facing away."""

    def __init__(self, radio: Radio, out: TextIO, seed: int = 1) -> None:
        self.radio = radio
        self.out = out
        self._rng = np.random.default_rng([seed, 0xCA11B])

    def place(self, placement: Placement) -> None:
        if placement.lux is not None:
            raise ValueError("simulated particles are placed by distance, not by lux")
        offsets = {}
        for particle_id in placement.ids:
            dx, dy = self._rng.normal(0.0, PLACEMENT_JITTER_M, 2)
            offsets[particle_id] = (placement.distances_cm[particle_id] / 100 + dx, dy)
        place(self.radio, offsets)
        print(f"{placement.heading}: (simulated) {placement.instruction}.", file=self.out)
