"""The published simulator's CSV, written as it writes it: a `Seed, N` line, a header, then one
row every dump interval; each row flushed, so a stopped run keeps every row it wrote."""

from __future__ import annotations

import io
import math
from pathlib import Path
from typing import TextIO

import numpy as np

from particlebot.fileio import write_text
from particlebot.sim.world.bodies import BodyState


def header(bodies: int, per_particle: bool) -> str:
    """The header line (with its newline): the published spacing, trailing commas included."""
    parts = ["Time,"]
    if per_particle:
        parts += [f"Particlebot_{i}_xpos, Particlebot_{i}_ypos," for i in range(bodies)]
        parts += [f"Particlebot_{i}_xvel, Particlebot_{i}_yvel," for i in range(bodies)]
        parts += [f"Particlebot_{i}_rad," for i in range(bodies)]
    parts.append("Centroid X, Centroid Y, Distance\n")
    return "".join(parts)


def row(
    state: BodyState,
    centroid: tuple[float, float],
    distance: float,
    per_particle: bool,
) -> str:
    """One row as the published code prints it (%f, i.e. 6 decimals: micrometres)."""
    out = io.StringIO()
    out.write(f"{state.t:f},")
    if per_particle:
        # Passive objects follow the particles, as the published object is its last "cell".
        objects = state.objects
        x = np.concatenate([state.x, objects[:, 0]])
        y = np.concatenate([state.y, objects[:, 1]])
        vx = np.concatenate([state.vx, objects[:, 2]])
        vy = np.concatenate([state.vy, objects[:, 3]])
        r = np.concatenate([state.radius, objects[:, 4]])
        out.write("".join(f"{a:f}, {b:f}," for a, b in zip(x, y, strict=True)))
        out.write("".join(f"{a:f}, {b:f}," for a, b in zip(vx, vy, strict=True)))
        out.write("".join(f"{a:f}," for a in r))
    out.write(f"{centroid[0]:f}, {centroid[1]:f}, {distance:f},\n")
    return out.getvalue()


class CsvLog:
    """Appends rows to a run's CSV; opened fresh (writing the two header lines) or to continue."""

    def __init__(self, path: Path, stream: TextIO, per_particle: bool) -> None:
        self.path = path
        self._stream = stream
        self.per_particle = per_particle

    @classmethod
    def create(cls, path: Path, seed: int, bodies: int, per_particle: bool) -> CsvLog:
        stream = path.open("x", encoding="utf-8", newline="")
        stream.write(f"Seed, {seed}\n")
        stream.write(header(bodies, per_particle))
        stream.flush()
        return cls(path, stream, per_particle)

    @classmethod
    def resume(cls, path: Path, up_to_s: float, per_particle: bool) -> CsvLog:
        """Continues a CSV from a snapshot at up_to_s: rows written after it (the run went on
        past its last snapshot before it stopped) are dropped, since the resumed run writes
        them again, and a half-written last line goes too."""
        keep_rows_through(path, up_to_s)
        return cls(path, path.open("a", encoding="utf-8", newline=""), per_particle)

    def write(self, state: BodyState, centroid: tuple[float, float], distance: float) -> None:
        self._stream.write(row(state, centroid, distance, self.per_particle))
        self._stream.flush()

    def close(self) -> None:
        self._stream.close()


def keep_rows_through(path: Path, t_s: float) -> None:
    """Rewrites the CSV with its two header lines and the complete rows at times <= t_s."""
    with path.open("r", encoding="utf-8", newline="") as stream:
        lines = stream.read().split("\n")
    # split() leaves "" after a final newline; anything else there is a line cut short.
    body = lines[2:-1]
    kept = lines[:2]
    for line in body:
        first = line.split(",", 1)[0]
        try:
            t = float(first)
        except ValueError:
            break
        if not math.isfinite(t) or t > t_s + 1e-6:
            break
        kept.append(line)
    write_text(path, "\n".join(kept) + "\n", newline="")
