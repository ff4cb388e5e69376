"""Pictures of a run: the swarm seen from above (particles coloured by where they are in their
cycle, dead ones grey, obstacles, lamp, objects) and the centroid's track toward the lamp."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

# Agg renders to files only (headless machines); Figure + FigureCanvasAgg keep no global state.
from matplotlib import colormaps
from matplotlib.artist import Artist
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.cm import ScalarMappable
from matplotlib.collections import EllipseCollection
from matplotlib.colors import Normalize, to_rgba
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Circle as CirclePatch
from matplotlib.patches import Patch, Rectangle

from particlebot.sim.runs.simcsv import PublishedRun
from particlebot.sim.world.arena import Arena
from particlebot.sim.world.world import World

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]

PHASE_MAP = colormaps["viridis"]
"""Phase 0 (the expansion begins) dark blue to 1 (the cycle ends) yellow; the greys and the
orange below are not in it."""
RESTING = "#d2d2d2"
DEAD = "#5f5f5f"
LOOSE = "#f4a582"
OBJECT = "#8b5a2b"
OBSTACLE = "#3a3a3a"
LAMP = "#ffd21f"
LAMP_IN_VIEW = 1.5
"""A picture takes in the lamp when it lies within this many swarm spans of the swarm."""
SMALLEST_STAMP_PX = 2.0
"""A picture stamps particles of this radius in pixels or more; smaller ones become coverage."""
DISC_LIMIT = 20_000
"""Up to this many particles each is drawn as a disc of its radius; beyond, every particle
colours the pixel it lies in (a disc would be smaller than a pixel anyway)."""


@dataclass(frozen=True)
class Frame:
    """The bodies at one moment, in the caller's order, with what the picture colours by."""

    t: float
    x: FloatArray
    y: FloatArray
    radius: FloatArray
    phase: FloatArray
    """0..1 while cycling, NaN otherwise."""
    alive: BoolArray
    loose: BoolArray
    """Free particles not annexed yet."""
    objects: FloatArray
    """(M, 5): x, y, vx, vy, radius."""

    @classmethod
    def of(cls, world: World) -> Frame:
        state = world.state()
        return cls(
            t=state.t,
            x=state.x,
            y=state.y,
            radius=state.radius,
            phase=np.asarray(world.phase(), dtype=np.float64),
            alive=state.alive,
            loose=state.free,
            objects=state.objects,
        )

    def colours(self) -> npt.NDArray[np.float64]:
        """RGBA per particle: phase colour while cycling, resting, dead or loose."""
        rgba = np.empty((len(self.x), 4))
        cycling = np.isfinite(self.phase)
        rgba[:] = to_rgba(RESTING)
        rgba[cycling] = PHASE_MAP(np.clip(self.phase[cycling], 0.0, 1.0))
        rgba[~self.alive] = to_rgba(DEAD)
        rgba[self.loose] = to_rgba(LOOSE)
        return rgba


@dataclass(frozen=True)
class View:
    """What a picture shows around the swarm: its bounds (m) and the fixed world in them."""

    bounds: tuple[float, float, float, float]
    """x_min, x_max, y_min, y_max"""
    lamp: tuple[float, float]
    arena: Arena
    title: str

    @classmethod
    def around(cls, frame: Frame, lamp: tuple[float, float], arena: Arena, title: str) -> View:
        """The swarm and its objects with a margin, at least 2 m across, and the lamp when it
        is near enough not to shrink the swarm to a speck (else an arrow points to it)."""
        xs: list[FloatArray] = [frame.x - frame.radius, frame.x + frame.radius]
        ys: list[FloatArray] = [frame.y - frame.radius, frame.y + frame.radius]
        if len(frame.objects):
            o = frame.objects
            xs += [o[:, 0] - o[:, 4], o[:, 0] + o[:, 4]]
            ys += [o[:, 1] - o[:, 4], o[:, 1] + o[:, 4]]
        x0, x1 = float(np.min(np.concatenate(xs))), float(np.max(np.concatenate(xs)))
        y0, y1 = float(np.min(np.concatenate(ys))), float(np.max(np.concatenate(ys)))
        span = max(x1 - x0, y1 - y0, 1.0)
        outside = max(x0 - lamp[0], lamp[0] - x1, y0 - lamp[1], lamp[1] - y1, 0.0)
        if outside <= LAMP_IN_VIEW * span:
            x0, x1 = min(x0, lamp[0]), max(x1, lamp[0])
            y0, y1 = min(y0, lamp[1]), max(y1, lamp[1])
        margin = max(0.08 * max(x1 - x0, y1 - y0), 0.3)
        cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
        half_x = max((x1 - x0) / 2 + margin, 1.0)
        half_y = max((y1 - y0) / 2 + margin, 1.0)
        return cls((cx - half_x, cx + half_x, cy - half_y, cy + half_y), lamp, arena, title)

    def shows(self, x: float, y: float) -> bool:
        x0, x1, y0, y1 = self.bounds
        return x0 <= x <= x1 and y0 <= y <= y1

    def to_json(self) -> dict[str, Any]:
        return {"bounds": list(self.bounds), "lamp": list(self.lamp), "title": self.title}

    @classmethod
    def from_json(cls, data: dict[str, Any], arena: Arena) -> View:
        b = data["bounds"]
        return cls(
            (b[0], b[1], b[2], b[3]), (data["lamp"][0], data["lamp"][1]), arena, data["title"]
        )


def picture_size(view: View, width_in: float = 11.0) -> tuple[float, float]:
    """Inches: `width_in` wide and as high as the view needs (with room for the labels)."""
    x0, x1, y0, y1 = view.bounds
    height = (width_in - 1.8) * (y1 - y0) / (x1 - x0) + 1.2
    return width_in, min(max(height, 0.45 * width_in), width_in)


def draw_swarm(frame: Frame, view: View, size_in: tuple[float, float] | None = None) -> Figure:
    """The top view: particles, objects, obstacles, lamp, a legend and the phase colour bar."""
    figure = Figure(figsize=size_in or picture_size(view), dpi=100, layout="constrained")
    FigureCanvasAgg(figure)
    ax = figure.add_subplot()
    x0, x1, y0, y1 = view.bounds
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_aspect("equal")
    ax.set_facecolor("#f7f5f0")
    ax.grid(True, color="#e2ded5", linewidth=0.6, zorder=0)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    _draw_obstacles(ax, view.arena)
    colours = frame.colours()
    if len(frame.x) <= DISC_LIMIT:
        ax.add_collection(
            EllipseCollection(
                widths=2 * frame.radius,
                heights=2 * frame.radius,
                angles=0.0,
                units="xy",
                offsets=np.column_stack((frame.x, frame.y)),
                offset_transform=ax.transData,
                facecolors=colours,
                edgecolors="#404040",
                linewidths=0.3 if len(frame.x) <= 2000 else 0.0,
                zorder=3,
            )
        )
    else:
        ax.imshow(
            _raster(frame, view, colours, figure),
            extent=(x0, x1, y0, y1),
            origin="lower",
            interpolation="nearest",
            zorder=3,
        )
    for o in frame.objects:
        ax.add_patch(CirclePatch((o[0], o[1]), o[4], facecolor=OBJECT, edgecolor="black", zorder=4))
    lx, ly = view.lamp
    if view.shows(lx, ly):
        ax.plot(
            [lx], [ly], marker="*", markersize=22, color=LAMP, markeredgecolor="black", zorder=5
        )
        ax.annotate(
            "lamp", (lx, ly), xytext=(0, -20), textcoords="offset points", ha="center", zorder=5
        )
    else:
        _arrow_to_lamp(ax, view)
    handles: list[Artist] = [
        Patch(facecolor=PHASE_MAP(0.1), edgecolor="#404040", label="cycling (colour: phase)"),
        Patch(facecolor=RESTING, edgecolor="#404040", label="resting"),
    ]
    if not frame.alive.all():
        handles.append(Patch(facecolor=DEAD, edgecolor="#404040", label="dead"))
    if frame.loose.any():
        handles.append(Patch(facecolor=LOOSE, edgecolor="#404040", label="loose (not annexed)"))
    if len(frame.objects):
        handles.append(Patch(facecolor=OBJECT, edgecolor="black", label="passive object"))
    if view.arena.rects or view.arena.circles:
        handles.append(Patch(facecolor=OBSTACLE, label="obstacle"))
    handles.append(
        Line2D(
            [], [], marker="*", linestyle="", markersize=14, color=LAMP,
            markeredgecolor="black", label="lamp",
        )
    )  # fmt: skip
    ax.legend(handles=handles, loc="upper right", fontsize=8, framealpha=0.9)
    bar = figure.colorbar(
        ScalarMappable(Normalize(0.0, 1.0), PHASE_MAP), ax=ax, shrink=0.6, pad=0.01
    )
    bar.set_label("phase: fraction of the cycle (expansion starts at 0)")
    ax.set_title(f"{view.title}  t = {_clock(frame.t)}")
    return figure


def _draw_obstacles(ax: Any, arena: Arena) -> None:
    for rect in arena.rects:
        width, height = rect.x_max - rect.x_min, rect.y_max - rect.y_min
        ax.add_patch(
            Rectangle((rect.x_min, rect.y_min), width, height, facecolor=OBSTACLE, zorder=2)
        )
    for circle in arena.circles:
        ax.add_patch(CirclePatch((circle.x, circle.y), circle.radius, facecolor=OBSTACLE, zorder=2))


def _arrow_to_lamp(ax: Any, view: View) -> None:
    """An arrow at the picture's edge toward a lamp outside it, with its distance."""
    x0, x1, y0, y1 = view.bounds
    cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
    lx, ly = view.lamp
    distance = math.hypot(lx - cx, ly - cy)
    ux, uy = (lx - cx) / distance, (ly - cy) / distance
    # Where the ray from the centre leaves the picture.
    reach = min(
        (x1 - x0) / 2 / abs(ux) if ux else math.inf, (y1 - y0) / 2 / abs(uy) if uy else math.inf
    )
    ax.annotate(
        f"lamp, {distance:.1f} m",
        xy=(cx + 0.97 * reach * ux, cy + 0.97 * reach * uy),
        xytext=(cx + 0.8 * reach * ux, cy + 0.8 * reach * uy),
        arrowprops={"arrowstyle": "-|>", "color": "#b8860b", "lw": 2},
        color="#8a6500",
        ha="center",
        va="center",
        bbox={"boxstyle": "round", "facecolor": "white", "edgecolor": "#b8860b", "alpha": 0.9},
        zorder=6,
    )


def _raster(
    frame: Frame, view: View, colours: npt.NDArray[np.float64], figure: Figure
) -> npt.NDArray[np.float64]:
    """An RGBA image about as fine as the picture, each particle a disc of pixels of its radius
    (at least its centre's pixel)."""
    width_px = int(figure.get_figwidth() * figure.dpi)
    x0, x1, y0, y1 = view.bounds
    metre_px = width_px / (x1 - x0)
    height_px = max(1, round((y1 - y0) * metre_px))
    image = np.zeros((height_px, width_px, 4))
    ix = np.floor((frame.x - x0) * metre_px).astype(np.int64)
    iy = np.floor((frame.y - y0) * metre_px).astype(np.int64)
    radius_px = frame.radius * metre_px
    reach = max(0, math.floor(float(radius_px.max())))
    if float(np.median(radius_px)) < SMALLEST_STAMP_PX:
        # A few pixels or less: cells about one (largest) diameter wide, each coloured by its
        # particles and as opaque as they cover it (stamps that small would look sparse).
        cells_x = max(1, round((x1 - x0) / (2 * float(frame.radius.max()))))
        cell_m = (x1 - x0) / cells_x
        cells_y = max(1, round((y1 - y0) / cell_m))
        coarse = np.zeros((cells_y, cells_x, 4))
        fx, fy = (frame.x - x0) / cell_m, (frame.y - y0) / cell_m
        return _coverage(fx, fy, frame.radius / cell_m, colours, coarse)
    for dy in range(-reach, reach + 1):
        for dx in range(-reach, reach + 1):
            px, py = ix + dx, iy + dy
            keep = (px >= 0) & (px < width_px) & (py >= 0) & (py < height_px)
            if dx or dy:
                keep &= dx * dx + dy * dy <= radius_px**2
            image[py[keep], px[keep]] = colours[keep]
    return image


def _coverage(
    fx: FloatArray,
    fy: FloatArray,
    radius: FloatArray,
    colours: npt.NDArray[np.float64],
    image: npt.NDArray[np.float64],
) -> npt.NDArray[np.float64]:
    """Each cell of `image` takes the area-weighted mean colour of the particles over it and is
    as opaque as they cover it, so a swarm reads as its density. fx, fy, radius: particles in
    cells; each particle's area is shared among the four cells nearest its centre (bilinear),
    which keeps a packed swarm free of the holes that whole particles per cell would leave."""
    height, width = image.shape[:2]
    area = np.pi * radius**2
    gx, gy = fx - 0.5, fy - 0.5
    ix, iy = np.floor(gx).astype(np.int64), np.floor(gy).astype(np.int64)
    wx, wy = gx - ix, gy - iy
    covered = np.zeros(height * width)
    rgb = np.zeros((height * width, 3))
    for dx, dy, weight in (
        (0, 0, (1 - wx) * (1 - wy)), (1, 0, wx * (1 - wy)),
        (0, 1, (1 - wx) * wy), (1, 1, wx * wy),
    ):  # fmt: skip
        px, py = ix + dx, iy + dy
        keep = (px >= 0) & (px < width) & (py >= 0) & (py < height)
        cell = py[keep] * width + px[keep]
        share = area[keep] * weight[keep]
        covered += np.bincount(cell, weights=share, minlength=height * width)
        for c in range(3):
            rgb[:, c] += np.bincount(
                cell, weights=share * colours[keep, c], minlength=height * width
            )
    painted = covered > 0
    flat = image.reshape(-1, 4)
    flat[painted, :3] = rgb[painted] / covered[painted, None]
    flat[painted, 3] = np.minimum(covered[painted], 1.0)
    return image


def save_swarm_picture(path: Path, frame: Frame, view: View) -> Path:
    figure = draw_swarm(frame, view)
    figure.savefig(path)
    return path


def save_track_plot(path: Path, run: PublishedRun, view: View) -> Path:
    """The centroid's path over the world (left) and its distance to the lamp against time
    (right), with the mean speed toward the lamp over the run."""
    figure = Figure(figsize=(12.0, 5.0), dpi=100, layout="constrained")
    FigureCanvasAgg(figure)
    path_ax, distance_ax = figure.subplots(1, 2, width_ratios=(1.0, 1.2))
    cx, cy = run.centroid_m[:, 0], run.centroid_m[:, 1]
    lx, ly = view.lamp
    _draw_obstacles(path_ax, view.arena)
    path_ax.plot(cx, cy, color="#1f77b4", linewidth=1.5, label="centroid")
    path_ax.plot(cx[:1], cy[:1], "o", color="#2ca02c", label="start")
    path_ax.plot(cx[-1:], cy[-1:], "s", color="#d62728", label="end")
    # Zoomed on the path (a swarm creeps millimetres a second); the lamp is shown where it
    # fits, else an arrow points to it.
    reach = max(float(np.ptp(cx)), float(np.ptp(cy)), 0.05)
    pad = 0.25 * reach
    centre = ((cx.min() + cx.max()) / 2, (cy.min() + cy.max()) / 2)
    half = reach / 2 + pad
    if max(abs(lx - centre[0]), abs(ly - centre[1])) < 2 * half:
        half = max(abs(lx - centre[0]), abs(ly - centre[1])) + pad
        path_ax.plot(
            [lx], [ly], marker="*", markersize=18, color=LAMP, markeredgecolor="black",
            linestyle="", label="lamp",
        )  # fmt: skip
    else:
        away = math.hypot(lx - cx[-1], ly - cy[-1])
        ux, uy = (lx - cx[-1]) / away, (ly - cy[-1]) / away
        # Beside the path, across the panel toward the lamp.
        bx, by = centre[0] + 0.6 * half * uy, centre[1] - 0.6 * half * ux
        path_ax.annotate(
            f"to the lamp ({away:.2f} m)",
            xy=(bx + 0.8 * half * ux, by + 0.8 * half * uy),
            xytext=(bx - 0.3 * half * ux, by - 0.3 * half * uy),
            arrowprops={"arrowstyle": "->", "color": "#b8860b", "lw": 1.5},
            color="#8a6500",
            ha="center",
            va="center",
            annotation_clip=False,
        )
    path_ax.set_xlim(centre[0] - half, centre[0] + half)
    path_ax.set_ylim(centre[1] - half, centre[1] + half)
    path_ax.set_aspect("equal")
    path_ax.set_xlabel("x (m)")
    path_ax.set_ylabel("y (m)")
    path_ax.grid(True, color="#dddddd")
    path_ax.legend(loc="best", fontsize=8)
    path_ax.set_title("centroid path")

    distance = run.distance_m if run.distance_m is not None else np.hypot(cx - lx, cy - ly)
    minutes = run.time_s / 60.0
    distance_ax.plot(minutes, distance, color="#1f77b4", marker="." if len(minutes) < 60 else "")
    distance_ax.set_xlabel("time (min)")
    distance_ax.set_ylabel("centroid to lamp (m)")
    distance_ax.grid(True, color="#dddddd")
    span = float(run.time_s[-1] - run.time_s[0]) if len(run.time_s) > 1 else 0.0
    if span > 0:
        speed = (distance[0] - distance[-1]) / span * 1000.0
        distance_ax.set_title(f"{view.title}: {speed:.2f} mm/s toward the lamp on average")
    else:
        distance_ax.set_title(view.title)
    figure.savefig(path)
    return path


def _clock(seconds: float) -> str:
    hours, rest = divmod(math.floor(seconds + 1e-6), 3600)
    minutes, secs = divmod(rest, 60)
    return f"{hours}:{minutes:02d}:{secs:02d}" if hours else f"{minutes}:{secs:02d}"
