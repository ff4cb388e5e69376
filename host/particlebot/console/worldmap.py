"""A small top view of a simulated swarm for the console: the particles, the lamp and the track of
the centroid, drawn in text (a terminal cell is about twice as tall as it is wide)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from rich.text import Text

from particlebot.protocol import State

CELL_ASPECT = 2.0
"""A character cell's height over its width."""
STATE_STYLES = {
    State.CYCLING: "bold green",
    State.PAUSED: "green",
    State.WAITING: "cyan",
    State.ESTIMATING: "yellow",
    State.DONE: "magenta",
    State.STOPPING: "red",
}


@dataclass(frozen=True)
class MapParticle:
    id: int
    x: float
    y: float
    expanded: bool
    """Its body is bigger than contracted (drawn as a filled disc)."""
    state: State | None


def render_map(
    particles: Sequence[MapParticle],
    lamp: tuple[float, float],
    track: Sequence[tuple[float, float]],
    width: int,
    height: int,
) -> Text:
    """width x height characters: the lamp (*), the particles (O contracted, @ expanded,
    coloured by state), the centroid's track (.) and where it is now (+), framed to hold the
    lamp and the swarm; the last line gives the scale and the distance to the lamp."""
    rows = max(3, height - 1)
    xs = [p.x for p in particles] + [lamp[0]]
    ys = [p.y for p in particles] + [lamp[1]]
    cx = sum(p.x for p in particles) / max(1, len(particles))
    cy = sum(p.y for p in particles) / max(1, len(particles))
    span_x = max(max(xs) - min(xs), 0.3) * 1.15
    span_y = max(max(ys) - min(ys), 0.3) * 1.15
    # Metres per column, so that the picture keeps the floor's proportions.
    scale = max(span_x / max(1, width - 1), span_y * CELL_ASPECT / max(1, rows - 1))
    mid_x, mid_y = (max(xs) + min(xs)) / 2, (max(ys) + min(ys)) / 2
    grid = [[(" ", "")] * width for _ in range(rows)]

    def put(x: float, y: float, char: str, style: str) -> None:
        col = round((x - mid_x) / scale + (width - 1) / 2)
        row = round((mid_y - y) / (scale * CELL_ASPECT) + (rows - 1) / 2)
        if 0 <= col < width and 0 <= row < rows:
            grid[row][col] = (char, style)

    for x, y in track:
        put(x, y, ".", "dim")
    for p in particles:
        style = "white" if p.state is None else STATE_STYLES.get(p.state, "white")
        put(p.x, p.y, "@" if p.expanded else "O", style)
    put(cx, cy, "+", "bold white")
    put(lamp[0], lamp[1], "*", "bold yellow")
    text = Text()
    for row in grid:
        for char, style in row:
            text.append(char, style)
        text.append("\n")
    distance = math.hypot(cx - lamp[0], cy - lamp[1])
    text.append(f"1 col = {scale * 100:.1f} cm, lamp {distance:.2f} m", "dim")
    return text
