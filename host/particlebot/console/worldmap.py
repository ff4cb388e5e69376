"""A small top view of a simulated swarm for the console: the particles, the track of their
centroid and the lamp (or the way to it), drawn in text (a terminal cell is about twice as tall as
it is wide)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from rich.text import Text

from particlebot.protocol import State

CELL_ASPECT = 2.0
"""A character cell's height over its width."""
SWARM_MARGIN_M = 0.2
"""Room around the swarm in the picture (more than a particle's diameter)."""
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
    """width x height characters: the particles (O contracted, @ expanded, coloured by state),
    the centroid's track (.) and where it is now (+, or the particle on it reversed), framed
    around the swarm; the lamp (*) where it is, or on the frame's edge in its direction when it
    lies beyond. The last line gives the scale and the distance to the lamp."""
    rows = max(3, height - 1)
    cx = sum(p.x for p in particles) / max(1, len(particles))
    cy = sum(p.y for p in particles) / max(1, len(particles))
    xs = [p.x for p in particles] + [x for x, _ in track] + [cx]
    ys = [p.y for p in particles] + [y for _, y in track] + [cy]
    span_x = max(xs) - min(xs) + 2 * SWARM_MARGIN_M
    span_y = max(ys) - min(ys) + 2 * SWARM_MARGIN_M
    # Metres per column, so that the picture keeps the floor's proportions.
    scale = max(span_x / max(1, width - 1), span_y / (CELL_ASPECT * max(1, rows - 1)))
    mid_x, mid_y = (max(xs) + min(xs)) / 2, (max(ys) + min(ys)) / 2
    grid = [[(" ", "")] * width for _ in range(rows)]

    def cell(x: float, y: float) -> tuple[float, float]:
        return (
            (x - mid_x) / scale + (width - 1) / 2,
            (mid_y - y) / (scale * CELL_ASPECT) + (rows - 1) / 2,
        )

    def square(x: float, y: float) -> tuple[int, int]:
        """The character cell (column, row) a floor point falls in."""
        col, row = cell(x, y)
        return round(col), round(row)

    def put(x: float, y: float, char: str, style: str) -> None:
        col, row = square(x, y)
        if 0 <= col < width and 0 <= row < rows:
            grid[row][col] = (char, style)

    for x, y in track:
        put(x, y, ".", "dim")
    put(cx, cy, "+", "bold white")
    # The particles over the centroid's mark: in a small blob the centroid often lies on the
    # middle particle's cell, which then shows the particle, reversed, rather than hiding it.
    centroid = square(cx, cy)
    for p in particles:
        style = "white" if p.state is None else STATE_STYLES.get(p.state, "white")
        if square(p.x, p.y) == centroid:
            style = f"{style} reverse"
        put(p.x, p.y, "@" if p.expanded else "O", style)
    # The lamp, or where the line toward it leaves the frame.
    col, row = cell(*lamp)
    centre_col, centre_row = cell(cx, cy)
    dc, dr = col - centre_col, row - centre_row
    reach = max(abs(dc) / max(1e-9, (width - 1) / 2), abs(dr) / max(1e-9, (rows - 1) / 2), 1.0)
    lamp_col = round((width - 1) / 2 + (col - (width - 1) / 2) / reach)
    lamp_row = round((rows - 1) / 2 + (row - (rows - 1) / 2) / reach)
    lamp_col = min(max(lamp_col, 0), width - 1)
    lamp_row = min(max(lamp_row, 0), rows - 1)
    grid[lamp_row][lamp_col] = ("*", "bold yellow")
    text = Text()
    for line in grid:
        for char, style in line:
            text.append(char, style)
        text.append("\n")
    distance = math.hypot(cx - lamp[0], cy - lamp[1])
    text.append(f"1 col = {scale * 100:.1f} cm; lamp {distance:.2f} m away", "dim")
    return text
