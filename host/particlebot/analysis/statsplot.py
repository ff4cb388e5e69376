"""The statistics drawn: the track in the paper's frame (lamp up) and each interval's speed."""

from __future__ import annotations

from pathlib import Path

import numpy as np

# Agg renders to files only (headless lab PCs and CI); Figure + FigureCanvasAgg keep no global
# state between plots, unlike pyplot.
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from particlebot.analysis.stats import StatsResult


def plot_stats(result: StatsResult, path: Path) -> Path:
    figure = Figure(figsize=(11, 4.6), layout="constrained")
    track_axes, speed_axes = figure.subplots(1, 2, width_ratios=[1, 1.5])

    track_axes.plot(result.track_x_cm, result.track_y_cm, color="0.75", lw=0.8, label="track")
    track_axes.plot(
        result.sample_x_cm,
        result.sample_y_cm,
        "o-",
        color="tab:blue",
        ms=3.5,
        lw=1.2,
        label=f"every {result.interval_s:g} s",
    )
    track_axes.plot([0], [0], "ks", ms=6, label="start (origin)")
    reach = float(np.nanmax(np.abs(np.concatenate([result.track_x_cm, result.track_y_cm]))))
    if result.lamp_distance_cm <= 1.2 * reach:
        track_axes.plot([0], [result.lamp_distance_cm], "*", color="goldenrod", ms=14, label="lamp")
    track_axes.text(
        0.03,
        0.97,
        f"lamp: +y, {result.lamp_distance_cm:.0f} cm from the start",
        transform=track_axes.transAxes,
        va="top",
        color="darkgoldenrod",
        fontsize=9,
    )
    track_axes.set_aspect("equal", adjustable="datalim")
    track_axes.set_xlabel("x (cm), lamp's right")
    track_axes.set_ylabel("y (cm), toward the lamp")
    track_axes.set_title(f"{result.name}: centroid, lamp on +y")
    track_axes.grid(alpha=0.3)
    track_axes.legend(loc="lower right", fontsize=8)

    speeds = result.speeds_mm_s
    colours = ["tab:green" if v >= 0 else "tab:red" for v in speeds]
    minutes = (result.step_t_s + result.interval_s / 2) / 60
    speed_axes.bar(minutes, speeds, width=result.interval_s / 60 * 0.85, color=colours)
    speed_axes.axhline(0, color="black", lw=0.8)
    speed_axes.axhline(
        result.average_mm_s,
        color="tab:blue",
        ls="--",
        label=f"average {result.average_mm_s:.3f} mm/s ({result.average_pct:.2f} %D/cycle)",
    )
    speed_axes.plot(
        [], [], " ", label=f"peak {result.peak_mm_s:.3f} mm/s ({result.peak_pct:.2f} %D/cycle)"
    )
    speed_axes.plot(
        [], [], " ", label=f"one-tailed p = {result.p_value:.3g} ({result.steps} steps)"
    )
    speed_axes.set_xlabel("time (min)")
    speed_axes.set_ylabel(f"speed toward the lamp per {result.interval_s:g} s (mm/s)")
    secondary = speed_axes.secondary_yaxis(
        "right",
        functions=(
            lambda v: result.percent_per_cycle(1.0) * v,
            lambda p: p / result.percent_per_cycle(1.0),
        ),
    )
    secondary.set_ylabel(
        f"% of {result.min_diameter_cm * 10:.0f} mm per {result.cycle_s:g} s cycle"
    )
    speed_axes.set_title("speed over each interval")
    speed_axes.grid(alpha=0.3, axis="y")
    speed_axes.legend(loc="best", fontsize=8)
    FigureCanvasAgg(figure).print_png(str(path))
    return path
