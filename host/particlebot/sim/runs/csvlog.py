"""The published simulator's CSV, written as it writes it: a `Seed, N` line, a header, then one
row every dump interval; each row flushed, so a stopped run keeps every row it wrote."""

from __future__ import annotations

import contextlib
import io
import math
from pathlib import Path
from typing import BinaryIO

import numpy as np

from particlebot.errors import ParticlebotError
from particlebot.fileio import cannot_write, write_text
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
    """Appends rows to a run's CSV; opened fresh (writing the two header lines) or to continue.
    Each row goes to the file in one unbuffered write; a write that fails (a full disk) is cut
    back to the last whole row and raised as OutputError, so the CSV never ends in a torn line."""

    def __init__(self, path: Path, stream: BinaryIO, per_particle: bool) -> None:
        self.path = path
        self._stream = stream
        self.per_particle = per_particle

    @classmethod
    def create(cls, path: Path, seed: int, bodies: int, per_particle: bool) -> CsvLog:
        write_text(path, f"Seed, {seed}\n" + header(bodies, per_particle))
        return cls(path, _append(path), per_particle)

    @classmethod
    def resume(
        cls, path: Path, up_to_s: float, per_particle: bool, seed: int, bodies: int
    ) -> tuple[CsvLog, str | None]:
        """Continues a CSV from a snapshot at up_to_s: rows written after it (the run went on
        past its last snapshot before it stopped) are dropped, since the resumed run writes
        them again, and a half-written last line goes too; header lines that are missing are
        written again. Returns the log and a note when rows before the snapshot are missing
        (they cannot be written again); CsvDamagedError for a file that is not text."""
        note = keep_rows_through(path, up_to_s, f"Seed, {seed}\n" + header(bodies, per_particle))
        return cls(path, _append(path), per_particle), note

    def write(self, state: BodyState, centroid: tuple[float, float], distance: float) -> None:
        data = row(state, centroid, distance, self.per_particle).encode("utf-8")
        whole = self._stream.tell()
        try:
            done = 0
            while done < len(data):
                done += self._stream.write(data[done:]) or 0
        except OSError as exc:
            with contextlib.suppress(OSError):  # if even this fails, the error says why
                self._stream.truncate(whole)
            raise cannot_write(self.path, exc) from None

    def close(self) -> None:
        self._stream.close()


def _append(path: Path) -> BinaryIO:
    try:
        return open(path, "ab", buffering=0)  # CsvLog closes it
    except OSError as exc:
        raise cannot_write(path, exc) from None


class CsvDamagedError(ParticlebotError, ValueError):
    """A run's CSV that is not the text it writes (binary, another encoding)."""


def keep_rows_through(path: Path, t_s: float, head: str | None = None) -> str | None:
    """Rewrites the CSV with its two header lines and the complete rows at times <= t_s, whole
    or not at all. `head` (the two header lines) replaces header lines that are missing or
    damaged; without it they are kept as they are. Returns a note when no row from the run's
    start survives (an empty or cut file), else None."""
    try:
        with path.open("r", encoding="utf-8", newline="") as stream:
            lines = stream.read().split("\n")
    except UnicodeDecodeError:
        raise CsvDamagedError(
            f"{path} is damaged (not text): move it away to resume without its rows"
        ) from None
    has_head = len(lines) > 2 and lines[0].startswith("Seed,") and lines[1].startswith("Time,")
    if has_head or head is None:
        kept, body = lines[:2], lines[2:-1]
    else:
        # split() leaves "" after a final newline: here the rows that follow whatever is left.
        kept = head.rstrip("\n").split("\n")
        body = [line for line in lines[:-1] if not line.startswith(("Seed,", "Time,"))]
    # split() leaves "" after a final newline; anything else there is a line cut short.
    first: float | None = None
    for line in body:
        text = line.split(",", 1)[0]
        try:
            t = float(text)
        except ValueError:
            break
        if not math.isfinite(t) or t > t_s + 1e-6:
            break
        first = t if first is None else first
        kept.append(line)
    write_text(path, "\n".join(kept) + "\n", newline="")
    lost = first is None or first > 1e-6
    if not lost and has_head:
        return None
    missing = "its header lines were written again" if not has_head else ""
    if lost and t_s > 0:
        gone = f"it holds no rows from the run's start to {t_s:g} s, which cannot be written again"
        missing = f"{missing}; {gone}" if missing else gone
    return f"{path}: {missing}" if missing else None
