"""The published simulator's files, which ours writes too: its CSV output and its config file.

CSV: a `Seed, <seed>` line, then a header `Time,` [per particle `Particlebot_<i>_xpos, _ypos`,
then every `_xvel, _yvel`, then every `_rad`] `Centroid X, Centroid Y, Distance`, then one row per
dump. Units are metres and seconds, y up (a right-handed world). Config: lines alternate between a
key and its values; `#` starts a comment line.
"""

from __future__ import annotations

import csv
import math
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import numpy.typing as npt

from particlebot.errors import ParticlebotError

FloatArray = npt.NDArray[np.float64]

CENTROID_COLUMNS = ("Centroid X", "Centroid Y")
DISTANCE_COLUMN = "Distance"
_PARTICLE_COLUMN = re.compile(r"^Particlebot_(\d+)_(xpos|ypos|xvel|yvel|rad)$")


class SimFormatError(ParticlebotError, ValueError):
    """Not a file in the published simulator's format, or a damaged one."""


@dataclass
class PublishedRun:
    """One CSV of the published format, as arrays (metres, seconds)."""

    path: Path
    seed: int | None
    time_s: FloatArray
    centroid_m: FloatArray
    """(rows, 2)"""
    distance_m: FloatArray | None
    """Centroid-to-light distance per row, when the column is there."""
    x_m: FloatArray | None = None
    """(rows, particles) centre x, when per-particle output was on; NaN where a row lacks it."""
    y_m: FloatArray | None = None
    r_m: FloatArray | None = None
    warnings: list[str] = field(default_factory=list)

    @property
    def particles(self) -> int:
        return 0 if self.x_m is None else int(self.x_m.shape[1])


def looks_published(path: Path) -> bool:
    """True when the file starts with the published format's `Seed,` line."""
    try:
        with path.open("r", encoding="utf-8", errors="replace") as stream:
            first = stream.readline()
    except OSError:
        return False
    return first.replace(" ", "").lower().startswith("seed,")


def _number(text: str) -> float:
    text = text.strip()
    return math.nan if text == "" else float(text)


def read_published_csv(path: Path) -> PublishedRun:
    """Reads one published-format CSV; SimFormatError with the line number when damaged."""
    try:
        with path.open("r", encoding="utf-8", newline="") as stream:
            rows = list(csv.reader(stream))
    except (OSError, UnicodeDecodeError) as exc:
        raise SimFormatError(f"cannot read {path}: {exc}") from None
    if len(rows) < 2 or not rows[0] or rows[0][0].strip().lower() != "seed":
        raise SimFormatError(f"{path}: not a simulator CSV (no 'Seed, N' first line)")
    seed_text = rows[0][1].strip() if len(rows[0]) > 1 else ""
    seed = int(seed_text) if seed_text.lstrip("-").isdigit() else None
    header = [cell.strip() for cell in rows[1]]
    while header and header[-1] == "":
        header.pop()
    index = {name: i for i, name in enumerate(header)}
    if not header or header[0] != "Time" or any(c not in index for c in CENTROID_COLUMNS):
        raise SimFormatError(
            f"{path}: header must start with 'Time' and have 'Centroid X, Centroid Y'"
        )
    values: list[list[float]] = []
    warnings: list[str] = []
    body = rows[2:]
    for line_no, row in enumerate(body, start=3):
        cells = row[: len(header)]
        if not any(c.strip() for c in cells):
            continue
        try:
            if len(cells) < len(header):
                raise ValueError
            values.append([_number(c) for c in cells])
        except ValueError:
            if line_no == len(body) + 2:
                # A run killed mid-write leaves a partial last line; the rows before it stand.
                warnings.append(f"{path.name}: ignored the incomplete last line {line_no}")
                continue
            raise SimFormatError(f"{path}:{line_no}: not a row of numbers") from None
    if not values:
        raise SimFormatError(f"{path}: no rows after the header")
    table = np.array(values, dtype=np.float64)
    run = PublishedRun(
        path=path,
        seed=seed,
        time_s=table[:, 0],
        centroid_m=table[:, [index["Centroid X"], index["Centroid Y"]]],
        distance_m=table[:, index[DISTANCE_COLUMN]] if DISTANCE_COLUMN in index else None,
        warnings=warnings,
    )
    per_particle: dict[str, dict[int, int]] = {}
    for name, column in index.items():
        match = _PARTICLE_COLUMN.match(name)
        if match:
            per_particle.setdefault(match.group(2), {})[int(match.group(1))] = column
    if {"xpos", "ypos"} <= per_particle.keys():
        ids = sorted(per_particle["xpos"])
        run.x_m = table[:, [per_particle["xpos"][i] for i in ids]]
        run.y_m = table[:, [per_particle["ypos"].get(i, 0) for i in ids]]
        if "rad" in per_particle:
            run.r_m = table[:, [per_particle["rad"].get(i, 0) for i in ids]]
    return run


def write_published_csv(
    path: Path,
    seed: int,
    time_s: npt.ArrayLike,
    x_m: npt.ArrayLike,
    y_m: npt.ArrayLike,
    r_m: npt.ArrayLike | None = None,
    light_m: tuple[float, float] | None = None,
) -> None:
    """Writes rows in the published format (per-particle positions, velocities 0, radii when
    given; centroid = mean of centres; distance to light_m when given, else 0)."""
    xs, ys = np.atleast_2d(np.asarray(x_m, float)), np.atleast_2d(np.asarray(y_m, float))
    count = xs.shape[1]
    header = ["Time"]
    header += [f"Particlebot_{i}_{axis}" for i in range(count) for axis in ("xpos", "ypos")]
    header += [f"Particlebot_{i}_{axis}" for i in range(count) for axis in ("xvel", "yvel")]
    if r_m is not None:
        header += [f"Particlebot_{i}_rad" for i in range(count)]
    header += ["Centroid X", "Centroid Y", DISTANCE_COLUMN]
    radii = None if r_m is None else np.atleast_2d(np.asarray(r_m, float))
    with path.open("w", encoding="utf-8", newline="") as stream:
        stream.write(f"Seed, {seed}\n")
        stream.write(", ".join(header) + "\n")
        for row, t in enumerate(np.asarray(time_s, float).ravel()):
            cells = [float(t)]
            for i in range(count):
                cells += [float(xs[row, i]), float(ys[row, i])]
            cells += [0.0] * (2 * count)
            if radii is not None:
                cells += [float(r) for r in radii[row]]
            cx, cy = float(xs[row].mean()), float(ys[row].mean())
            distance = 0.0 if light_m is None else math.hypot(cx - light_m[0], cy - light_m[1])
            cells += [cx, cy, distance]
            stream.write(", ".join(f"{v:.6f}" for v in cells) + "\n")


def read_published_config(path: Path) -> dict[str, list[str]]:
    """Key -> values of a published-format config file (SimFormatError when it is not one)."""
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except (OSError, UnicodeDecodeError) as exc:
        raise SimFormatError(f"cannot read {path}: {exc}") from None
    meaningful = [ln.strip() for ln in lines if ln.strip() and not ln.lstrip().startswith("#")]
    if len(meaningful) % 2:
        raise SimFormatError(f"{path}: a key without a value")
    config: dict[str, list[str]] = {}
    for key, value in zip(meaningful[0::2], meaningful[1::2], strict=True):
        if " " in key or not key.replace("_", "").isalnum():
            raise SimFormatError(f"{path}: {key!r} is not a key")
        config[key] = value.split()
    return config


def light_from_config(path: Path) -> tuple[float, float] | None:
    """(light_x, light_y) in metres from a published-format config, None when it has none."""
    try:
        config = read_published_config(path)
        return float(config["light_x"][0]), float(config["light_y"][0])
    except (SimFormatError, KeyError, IndexError, ValueError):
        return None
