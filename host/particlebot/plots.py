"""Session plots: a log's STATUS frames as per-particle radius, state and intensity over time; for a
simulated radio also the world's truth: the commanded radius without aliasing, and a top view of
every particle's path and the centroid's track toward the lamp."""

from __future__ import annotations

import dataclasses
import json
import math
import statistics
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

# Agg renders to files only: the plot must work on a headless lab PC or CI runner, and the
# Figure/FigureCanvasAgg pair (not pyplot) keeps no global state between plots.
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from matplotlib.transforms import blended_transform_factory

from particlebot.errors import ParticlebotError
from particlebot.protocol import Method, State
from particlebot.resets import reset_cause, restarted
from particlebot.sim.swarm.records import WorldRecordError, WorldTrack, read_world

Record = dict[str, Any]

# Commands worth a marker: the ones that change what every particle does.
MARKED_COMMANDS = ("START", "STOP")

# A particle acts on STOP the moment it arrives; a STATUS after it in one of these states shows
# the particle obeyed, so the plot draws it stopped from the STOP on, not from that STATUS.
OBEYED_STOP_STATES = frozenset({State.STOPPING, State.IDLE, State.DONE})
RESET_COLOUR = "#d62728"

# The STATUS_PERIOD_MS default, used to hold a lone sample when a particle's own spacing is unknown.
DEFAULT_STATUS_PERIOD_S = 2.0

# A silence longer than this many STATUS periods is drawn as a gap, not as the last state held on:
# the particle may have been switched off or out of range, and the plot must not pretend otherwise.
GAP_PERIODS = 3.0

STATE_COLOURS: dict[int, str] = {
    State.IDLE: "#c8c8c8",
    State.ESTIMATING: "#f2c14e",
    State.WAITING: "#9ecae1",
    State.CYCLING: "#2e8b57",
    State.PAUSED: "#a1d99b",
    State.STOPPING: "#e6550d",
    State.DONE: "#756bb1",
    State.IDENTIFYING: "#e377c2",
}
UNKNOWN_STATE_COLOUR = "#333333"


class PlotInputError(ParticlebotError, ValueError):
    """The log cannot be plotted (missing, empty, not a log, no STATUS frames)."""


@dataclass
class LogRecords:
    records: list[Record]
    warnings: list[str] = field(default_factory=list)


@dataclass
class ParticleSeries:
    """One particle's STATUS samples, times in seconds since the session started."""

    particle_id: int
    times: list[float] = field(default_factory=list)
    states: list[int] = field(default_factory=list)
    s_n: list[int] = field(default_factory=list)
    intensity: list[int] = field(default_factory=list)
    radius_um: list[int] = field(default_factory=list)
    resets: list[ResetMark] = field(default_factory=list)
    """Resets seen between two of its STATUS frames (at the later one's time)."""

    @property
    def radius_mm(self) -> list[float]:
        return [value / 1000.0 for value in self.radius_um]

    @property
    def last_s_n(self) -> int | None:
        """The latest S_n estimated (0 means not estimated yet, so it does not count)."""
        return next((value for value in reversed(self.s_n) if value), None)

    @property
    def label(self) -> str:
        s_n = self.last_s_n
        return f"id {self.particle_id}" + ("" if s_n is None else f"  S_n {s_n}")

    def sample_period(self) -> float:
        """The typical spacing of this particle's STATUS frames (their median gap)."""
        gaps = [b - a for a, b in zip(self.times, self.times[1:], strict=False) if b > a]
        return statistics.median(gaps) if gaps else DEFAULT_STATUS_PERIOD_S


@dataclass(frozen=True)
class ResetMark:
    t: float
    cause: str


@dataclass(frozen=True)
class StateBand:
    state: int
    start: float
    end: float


@dataclass
class CommandMark:
    """A command sent to the swarm; resends of the same command (a campaign) add to sends."""

    t: float
    name: str
    detail: str = ""
    sends: int = 1
    failed: bool = False

    @property
    def label(self) -> str:
        text = self.name + (f" {self.detail}" if self.detail else "")
        if self.sends > 1:
            text += f" (sent {self.sends}x)"
        return text + (" [send failed]" if self.failed else "")


@dataclass
class SessionSeries:
    """Everything the plot draws, extracted from a log's records."""

    particles: list[ParticleSeries]
    commands: list[CommandMark]
    duration: float
    radio: str = ""
    started: str = ""
    warnings: list[str] = field(default_factory=list)
    start: float = 0.0
    """The time axis shows start..end (seconds since the session started): the whole session,
    or the run or window asked for."""
    end: float | None = None
    world: WorldTrack | None = None
    """A simulated radio's truth, times in seconds since the session started (None: a real
    radio, or a log from before the world was logged)."""

    @property
    def shown_end(self) -> float:
        return self.duration if self.end is None else self.end

    @property
    def stop_times(self) -> list[float]:
        return [c.t for c in self.commands if c.name == "STOP" and not c.failed]

    @property
    def status_frames(self) -> int:
        return sum(len(p.times) for p in self.particles)

    def particle(self, particle_id: int) -> ParticleSeries:
        return next(p for p in self.particles if p.particle_id == particle_id)


@dataclass(frozen=True)
class PlotResult:
    output: Path
    particles: int
    status_frames: int
    warnings: list[str]


def read_records(path: Path) -> LogRecords:
    """A log's records. Unlike logs.jsonl.read_log this never raises on a bad line: a torn last
    line (a killed session) or a damaged one is skipped with a warning, since a plot of the rest is
    still worth having."""
    try:
        data = path.read_bytes()
    except FileNotFoundError:
        raise PlotInputError(f"no log file {path}") from None
    except OSError as exc:
        raise PlotInputError(f"cannot read {path}: {exc.strerror or exc}") from None
    lines = data.split(b"\n")
    # A complete log ends with a newline, so only a killed writer leaves text after the last one.
    last = len(lines)
    result = LogRecords([])
    for number, line in enumerate(lines, start=1):
        if not line.strip():
            continue
        try:
            record = json.loads(line)
        except ValueError:
            record = None
        if not isinstance(record, dict):
            if number == last:
                result.warnings.append(
                    f"{path}:{number}: last line is truncated (session killed?); skipped"
                )
            else:
                result.warnings.append(f"{path}:{number}: not a JSON object; skipped")
            continue
        result.records.append(record)
    if not result.records:
        raise PlotInputError(f"{path} holds no log records (empty, or not a particlebot log)")
    return result


def _time(record: Record) -> float | None:
    value = record.get("t")
    if isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value):
        return float(value)
    return None


def _int_field(fields: Record, name: str) -> int:
    value = fields[name]
    if not isinstance(value, int) or isinstance(value, bool):
        raise TypeError(name)
    return value


def extract(records: Sequence[Record], warnings: Iterable[str] = ()) -> SessionSeries:
    """Per-particle STATUS series and the commands sent. Particles come ordered by their latest
    S_n (nearest the light first), those never estimated last, ties by id."""
    notes = list(warnings)
    # Logs written before the end record took the session's clock stamped it with the host's wall
    # clock, which a sped-up virtual radio's clock outruns: it is no guide to when frames came.
    timed = [(t, r) for r in records if r.get("kind") != "end" and (t := _time(r)) is not None]
    if not timed:
        raise PlotInputError("the log holds no timed records")
    t0 = min(t for t, _ in timed)
    end = max(t for t, _ in timed) - t0
    session = next((r for r in records if r.get("kind") == "session"), {})
    series: dict[int, ParticleSeries] = {}
    commands: list[CommandMark] = []
    malformed = 0
    last_counters: dict[int, tuple[int, int]] = {}
    for t, record in sorted(timed, key=lambda item: item[0]):
        kind = record.get("kind")
        if kind == "frame" and record.get("type") == "STATUS":
            try:
                sender = record["sender"]
                fields = record["fields"]
                sample = (
                    _int_field(fields, "state"),
                    _int_field(fields, "s_n"),
                    _int_field(fields, "intensity"),
                    _int_field(fields, "radius_um"),
                )
                if not isinstance(sender, int):
                    raise TypeError("sender")
            except (KeyError, TypeError):
                malformed += 1
                continue
            particle = series.setdefault(sender, ParticleSeries(sender))
            particle.times.append(t - t0)
            particle.states.append(sample[0])
            particle.s_n.append(sample[1])
            particle.intensity.append(sample[2])
            particle.radius_um.append(sample[3])
            _find_reset(particle, fields, t - t0, last_counters)
        elif kind == "tx" and record.get("type") in MARKED_COMMANDS:
            _add_command(commands, record, t - t0)
    if malformed:
        notes.append(f"{malformed} STATUS records without usable fields; skipped")
    world: WorldTrack | None = None
    try:
        world = read_world(r for _, r in timed)
    except WorldRecordError as exc:
        notes.append(f"the world's records are damaged ({exc}); drawn without them")
    if world is not None:
        world.body_t = world.body_t - t0
        world.radius_t = world.radius_t - t0
    if not series:
        raise PlotInputError("the log holds no STATUS frames: nothing to plot")
    ordered = sorted(
        series.values(),
        key=lambda p: (p.last_s_n is None, p.last_s_n or 0, p.particle_id),
    )
    return SessionSeries(
        particles=ordered,
        commands=commands,
        duration=end,
        radio=str(session.get("radio", "")),
        started=str(session.get("started", "")),
        warnings=notes,
        world=world,
    )


def _find_reset(
    particle: ParticleSeries,
    fields: Record,
    t: float,
    last_counters: dict[int, tuple[int, int]],
) -> None:
    """Adds a ResetMark when this STATUS shows a reset since the particle's previous one (logs
    from before STATUS carried the counters have none to show)."""
    try:
        counters = (_int_field(fields, "resets"), _int_field(fields, "uptime_ms"))
        cause = _int_field(fields, "last_reset_cause")
    except (KeyError, TypeError):
        return
    previous = last_counters.get(particle.particle_id)
    last_counters[particle.particle_id] = counters
    if previous is not None and restarted(*previous, *counters):
        particle.resets.append(ResetMark(t, reset_cause(cause)))


def select(session: SessionSeries, start: float | None, end: float | None) -> SessionSeries:
    """The part of a session between start and end (seconds since it started; None: its
    beginning or end). Particles with no STATUS in it are left out."""
    low = 0.0 if start is None else start
    high = session.duration if end is None else end
    if high <= low:
        raise PlotInputError(f"the window {low:g}..{high:g} s is empty")
    particles = []
    for particle in session.particles:
        keep = [i for i, t in enumerate(particle.times) if low <= t <= high]
        if not keep:
            continue
        particles.append(
            ParticleSeries(
                particle.particle_id,
                times=[particle.times[i] for i in keep],
                states=[particle.states[i] for i in keep],
                s_n=[particle.s_n[i] for i in keep],
                intensity=[particle.intensity[i] for i in keep],
                radius_um=[particle.radius_um[i] for i in keep],
                resets=[r for r in particle.resets if low <= r.t <= high],
            )
        )
    if not particles:
        raise PlotInputError(
            f"no STATUS frames between {low:g} and {high:g} s (the session lasts "
            f"{session.duration:.1f} s)"
        )
    return SessionSeries(
        particles=particles,
        commands=[c for c in session.commands if low <= c.t <= high],
        duration=session.duration,
        radio=session.radio,
        started=session.started,
        warnings=session.warnings,
        start=low,
        end=high,
        world=None if session.world is None else _world_window(session.world, low, high),
    )


def _world_window(world: WorldTrack, low: float, high: float) -> WorldTrack:
    bodies = (world.body_t >= low) & (world.body_t <= high)
    radii = (world.radius_t >= low) & (world.radius_t <= high)
    return dataclasses.replace(
        world,
        body_t=world.body_t[bodies],
        x=world.x[bodies],
        y=world.y[bodies],
        r=world.r[bodies],
        radius_t=world.radius_t[radii],
        commanded=world.commanded[radii],
    )


def run_window(records: Sequence[Record], run_id: int) -> tuple[float, float | None]:
    """Where run run_id lies, in seconds since the session started: from its first START to the
    next START of another run (None: the end of the log). PlotInputError names the runs there are
    when it has none."""
    timed = sorted(
        ((t, r) for r in records if r.get("kind") != "end" and (t := _time(r)) is not None),
        key=lambda item: item[0],
    )
    if not timed:
        raise PlotInputError("the log holds no timed records")
    t0 = timed[0][0]
    start: float | None = None
    runs: list[int] = []
    for t, record in timed:
        if record.get("kind") != "tx" or record.get("type") != "START":
            continue
        fields = record.get("fields")
        run = fields.get("run_id") if isinstance(fields, dict) else None
        if not isinstance(run, int):
            continue
        if run not in runs:
            runs.append(run)
        if run == run_id and start is None:
            start = t - t0
        elif run != run_id and start is not None:
            return start, t - t0
    if start is None:
        known = ", ".join(str(r) for r in runs) or "none"
        raise PlotInputError(f"no START of run {run_id} in the log (runs started: {known})")
    return start, None


def _add_command(commands: list[CommandMark], record: Record, t: float) -> None:
    name = str(record["type"])
    fields = record.get("fields") or {}
    detail = ""
    if name == "START":
        method = fields.get("method", "?")
        try:
            method_name = Method(method).name
        except (TypeError, ValueError):
            method_name = str(method)
        detail = f"run {fields.get('run_id', '?')} {method_name}"
    failed = "error" in record
    previous = commands[-1] if commands else None
    # The console repeats a command until every particle confirms it; a repeat carries the same
    # name and run, and drawing each one would bury the plot in lines.
    if previous is not None and previous.name == name and previous.detail == detail:
        previous.sends += 1
        previous.failed = previous.failed and failed
        return
    commands.append(CommandMark(t, name, detail, failed=failed))


def state_bands(
    particle: ParticleSeries, session_end: float, stops: Sequence[float] = ()
) -> list[StateBand]:
    """The states as sampled: each STATUS holds until the next one, the last for one STATUS period
    (not past the session's end), and a silence of more than GAP_PERIODS periods is left empty.
    A STOP sent (stops: its times) between two samples, the later of which shows the particle
    obeyed it, ends the earlier state at the STOP: particles act on STOP when it arrives."""
    period = particle.sample_period()
    bands: list[StateBand] = []
    begins = list(particle.times)
    for index, (t, state) in enumerate(zip(particle.times, particle.states, strict=True)):
        begin = begins[index]
        if index + 1 < len(particle.times):
            following = particle.times[index + 1]
            held = following if following - t <= GAP_PERIODS * period else t + period
            stop = next((s for s in stops if t < s < held), None)
            if stop is not None and particle.states[index + 1] in OBEYED_STOP_STATES:
                held = begins[index + 1] = stop
        else:
            held = max(t, min(t + period, session_end))
        if bands and bands[-1].state == state and bands[-1].end == begin:
            bands[-1] = StateBand(state, bands[-1].start, held)
        else:
            bands.append(StateBand(state, begin, held))
    return bands


def _state_name(state: int) -> str:
    try:
        return State(state).name
    except ValueError:
        return f"state {state}"


def _particle_colours(count: int) -> list[Any]:
    # Ten particles or fewer get clearly distinct hues; bigger swarms a perceptual ramp in S_n
    # order, where neighbours in the line are neighbours in colour.
    from matplotlib import colormaps

    if count <= 10:
        return [colormaps["tab10"](index) for index in range(count)]
    ramp = colormaps["viridis"]
    return [ramp(0.9 * index / max(1, count - 1)) for index in range(count)]


TOP_VIEW_WIDTH = 7.0
"""Inches of the top view beside the time panels, when the log holds the world's truth."""


def render(session: SessionSeries, title: str) -> Figure:
    """The session as a figure: radius, state timeline and intensity on one time axis, and, when
    the log holds the world's truth, a top view of the particles' paths beside them."""
    count = len(session.particles)
    world = session.world if session.world is not None and len(session.world.body_t) else None
    truth_radii = world is not None and len(world.radius_t) > 1
    # Heights in inches grow with the swarm: the state panel needs a readable row per particle and
    # the radius panel room for a legend line per particle beside it.
    radius_height = max(3.0, 0.18 * count + 0.6)
    state_height = max(1.6, 0.28 * count)
    intensity_height = 2.2
    height = radius_height + state_height + intensity_height + 1.4
    figure = Figure(
        figsize=(13 + (TOP_VIEW_WIDTH if world is not None else 0), height),
        dpi=100,
        layout="constrained",
    )
    FigureCanvasAgg(figure)
    panels: Any = figure
    if world is not None:
        halves: Any = figure.subfigures(1, 2, width_ratios=[13, TOP_VIEW_WIDTH])
        panels, top = halves[0], halves[1]
    radius_ax, state_ax, intensity_ax = panels.subplots(
        3, 1, sharex=True, height_ratios=[radius_height, state_height, intensity_height]
    )
    colours = _particle_colours(count)
    period = statistics.median(p.sample_period() for p in session.particles)
    sampled = "intensity is" if truth_radii else "radius and intensity are"
    figure.suptitle(
        f"{title}\n{sampled} sampled at STATUS times (about every {period:.1f} s per particle): "
        "lines join samples, they do not trace the motion in between",
        fontsize=11,
    )

    colour_of = {p.particle_id: c for p, c in zip(session.particles, colours, strict=True)}
    handles: dict[int, Any] = {}
    if world is not None and truth_radii:
        for column, particle_id in enumerate(world.ids):
            particle = next((p for p in session.particles if p.particle_id == particle_id), None)
            (handles[particle_id],) = radius_ax.plot(
                world.radius_t,
                world.commanded[:, column] * 1000,
                linewidth=0.9,
                color=colour_of.get(particle_id, "#999999"),
                label=particle.label if particle is not None else f"id {particle_id}",
            )
    for colour, particle in zip(colours, session.particles, strict=True):
        if not truth_radii:
            (handles[particle.particle_id],) = radius_ax.plot(
                particle.times,
                particle.radius_mm,
                marker="o",
                markersize=3,
                linewidth=1.0,
                color=colour,
                label=particle.label,
            )
        intensity_ax.plot(
            particle.times,
            particle.intensity,
            marker="o",
            markersize=2.5,
            linewidth=1.0,
            color=colour,
        )
    radius_ax.set_ylabel("commanded radius (mm)")
    radius_ax.set_title(
        "commanded radius per particle, "
        + ("the simulation's truth every 0.1 s" if truth_radii else "from STATUS radius_um"),
        fontsize=10,
    )
    radius_ax.grid(True, alpha=0.3)
    # Rows of the state panel follow the wave (S_n); the legend is where a person looks an id up.
    radius_ax.legend(
        handles=[handles[key] for key in sorted(handles)],
        title="particle",
        loc="upper left",
        bbox_to_anchor=(1.005, 1.0),
        fontsize=8,
        title_fontsize=9,
    )

    seen_states: set[int] = set()
    any_reset = False
    for row, particle in enumerate(session.particles):
        for reset in particle.resets:
            any_reset = True
            state_ax.plot(
                [reset.t],
                [row],
                marker="X",
                markersize=11,
                color=RESET_COLOUR,
                markeredgecolor="white",
                zorder=5,
            )
            state_ax.annotate(
                f"reset ({reset.cause})",
                (reset.t, row),
                xytext=(7, -3),
                textcoords="offset points",
                fontsize=8,
                color=RESET_COLOUR,
                fontweight="bold",
            )
        for band in state_bands(particle, session.shown_end, session.stop_times):
            seen_states.add(band.state)
            state_ax.broken_barh(
                [(band.start, band.end - band.start)],
                (row - 0.4, 0.8),
                facecolors=STATE_COLOURS.get(band.state, UNKNOWN_STATE_COLOUR),
                edgecolor="none",
            )
    state_ax.set_yticks(range(count), [p.label for p in session.particles], fontsize=8)
    state_ax.set_ylim(count - 0.5, -0.5)
    state_ax.set_title("state per particle (as reported in STATUS)", fontsize=10)
    state_ax.grid(True, axis="x", alpha=0.3)
    state_handles: list[Any] = [
        Patch(color=STATE_COLOURS.get(state, UNKNOWN_STATE_COLOUR), label=_state_name(state))
        for state in sorted(seen_states)
    ]
    if any_reset:
        state_handles.append(
            Line2D(
                [],
                [],
                marker="X",
                color=RESET_COLOUR,
                markeredgecolor="white",
                linestyle="",
                markersize=9,
                label="reset",
            )
        )
    state_ax.legend(
        handles=state_handles,
        title="state",
        loc="upper left",
        bbox_to_anchor=(1.005, 1.0),
        fontsize=8,
        title_fontsize=9,
    )

    intensity_ax.set_ylabel("intensity\n(ADC counts, 0-1023)")
    intensity_ax.set_title("light intensity per particle (mean of healthy sensors)", fontsize=10)
    intensity_ax.grid(True, alpha=0.3)
    intensity_ax.set_xlabel("time since the session started (s)")
    span = max(session.shown_end - session.start, 1.0)
    intensity_ax.set_xlim(session.start, session.start + span)

    label_at = blended_transform_factory(radius_ax.transData, radius_ax.transAxes)
    previous_t: float | None = None
    height = 0.98
    for command in session.commands:
        colour = "#b2182b" if command.name == "STOP" else "#2166ac"
        for ax in (radius_ax, state_ax, intensity_ax):
            ax.axvline(command.t, color=colour, linestyle="--", linewidth=1.2)
        # Labels of commands close in time are stacked so they stay readable, and a label in the
        # right part of the plot sits left of its line so the axes do not clip it.
        close = previous_t is not None and command.t - previous_t < 0.3 * span
        height = height - 0.08 if close and height > 0.6 else 0.98
        previous_t = command.t
        right_side = command.t - session.start > 0.6 * span
        radius_ax.text(
            command.t,
            height,
            f" {command.label} @ {command.t:.1f} s ",
            transform=label_at,
            color=colour,
            fontsize=8,
            fontweight="bold",
            va="top",
            ha="right" if right_side else "left",
            bbox={"facecolor": "white", "edgecolor": "none", "alpha": 0.8, "pad": 1.0},
        )
    if world is not None:
        draw_top_view(top.subplots(), world, colour_of)
    return figure


def draw_top_view(ax: Any, world: WorldTrack, colour_of: dict[int, Any]) -> None:
    """The floor from above: obstacles, the lamp, each particle's path (its start drawn as an
    outline, its end as a disc of its radius then) and the centroid's track."""
    from matplotlib.patches import Circle as Disc
    from matplotlib.patches import Rectangle

    for x_min, x_max, y_min, y_max in world.rects:
        ax.add_patch(
            Rectangle((x_min, y_min), x_max - x_min, y_max - y_min, color="#777777", zorder=1)
        )
    for circle_x, circle_y, radius in world.circles:
        ax.add_patch(Disc((circle_x, circle_y), radius, color="#777777", zorder=1))
    for ox, oy, radius in world.objects:
        ax.add_patch(Disc((ox, oy), radius, facecolor="#d9c7a3", edgecolor="#8c6d3f", zorder=2))
    for column, particle_id in enumerate(world.ids):
        colour = colour_of.get(particle_id, "#999999")
        xs, ys = world.x[:, column], world.y[:, column]
        ax.plot(xs, ys, color=colour, linewidth=0.7, alpha=0.8, zorder=3)
        ax.add_patch(
            Disc((xs[0], ys[0]), world.r[0, column], fill=False, edgecolor=colour, alpha=0.5,
                 linestyle="--", linewidth=0.8, zorder=3)
        )  # fmt: skip
        ax.add_patch(
            Disc((xs[-1], ys[-1]), world.r[-1, column], facecolor=colour, alpha=0.55,
                 edgecolor=colour, zorder=4)
        )  # fmt: skip
    cx, cy = world.centroid
    ax.plot(cx, cy, color="black", linewidth=2.0, zorder=5, label="centroid")
    ax.plot([cx[0]], [cy[0]], marker="o", color="black", markersize=5, zorder=6)
    ax.plot([cx[-1]], [cy[-1]], marker="s", color="black", markersize=5, zorder=6)
    lamp_x, lamp_y, lamp_h = world.lamp
    ax.plot(
        [lamp_x], [lamp_y], marker="*", markersize=18, color="#f2b705",
        markeredgecolor="#8a6500", zorder=7, linestyle="",
        label=f"lamp ({lamp_h * 100:.0f} cm above the photocells)",
    )  # fmt: skip
    before = math.hypot(cx[0] - lamp_x, cy[0] - lamp_y)
    after = math.hypot(cx[-1] - lamp_x, cy[-1] - lamp_y)
    span = world.body_t[-1] - world.body_t[0]
    ax.set_title(
        f"top view (the simulation's truth): paths and centroid\n"
        f"centroid {(before - after) * 100:+.1f} cm toward the lamp in {span:.0f} s "
        f"({before:.2f} m -> {after:.2f} m)",
        fontsize=10,
    )
    # The swarm, the lamp and the obstacles near them, with a margin of a particle or two.
    xs_all = [float(world.x.min()), float(world.x.max()), lamp_x]
    ys_all = [float(world.y.min()), float(world.y.max()), lamp_y]
    margin = 2 * float(world.r.max())
    ax.set_xlim(min(xs_all) - margin, max(xs_all) + margin)
    ax.set_ylim(min(ys_all) - margin, max(ys_all) + margin)
    # The floor's true proportions, in a panel as tall as they need.
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="best", fontsize=8)


def plot_log(
    log: Path,
    output: Path,
    *,
    run: int | None = None,
    start: float | None = None,
    end: float | None = None,
) -> PlotResult:
    """Reads log and writes its plot as a PNG to output (PlotInputError if it cannot): the whole
    session, one run (from its START to the next), or the window start..end (seconds since the
    session started)."""
    loaded = read_records(log)
    session = extract(loaded.records, loaded.warnings)
    what = ""
    if run is not None:
        run_start, run_end = run_window(loaded.records, run)
        start = run_start if start is None else max(start, run_start)
        end = run_end if end is None or run_end is None else min(end, run_end)
        what = f", run {run}"
    if start is not None or end is not None:
        session = select(session, start, end)
        what += f", {session.start:.1f}-{session.shown_end:.1f} s"
    for particle in session.particles:
        for reset in particle.resets:
            session.warnings.append(
                f"particle {particle.particle_id} reset at {reset.t:.1f} s ({reset.cause})"
            )
    title = f"particlebot session {log.name}{what}: {len(session.particles)} particles"
    if session.radio:
        title += f" on {session.radio}"
    if session.started:
        title += f", started {session.started}"
    figure = render(session, title)
    try:
        figure.savefig(output, format="png")
    except OSError as exc:
        raise PlotInputError(f"cannot write {output}: {exc.strerror or exc}") from None
    return PlotResult(output, len(session.particles), session.status_frames, session.warnings)
