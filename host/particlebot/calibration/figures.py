"""The calibrations drawn: photocell laws before and after, Fig. S5's positions, radius vs pulse."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

# Agg renders to files only (headless lab PCs and CI); Figure + FigureCanvasAgg keep no global
# state between plots, unlike pyplot.
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from particlebot.calibration.photocells import (
    DISTANCE_UNIT,
    Correction,
    corrected_reading,
    light_level,
    rho,
)
from particlebot.calibration.positions import PositionCheck
from particlebot.calibration.readings import Readings
from particlebot.calibration.servo import ServoTable
from particlebot.sim.world.light import SENSOR_COUNT


def _save(figure: Figure, path: Path) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    FigureCanvasAgg(figure).print_png(str(path))
    return path


def plot_photocells(
    readings: Readings,
    corrections: dict[int, Correction],
    scale: float,
    unit: str,
    lamp_height_cm: float,
    path: Path,
) -> Path:
    """Every photocell's resistance ratio against the light level as read (left: one power law
    per cell), and how far each calibrated cell stays from the fleet's law (right)."""
    from matplotlib.ticker import ScalarFormatter

    figure = Figure(figsize=(11, 4.6), layout="constrained")
    raw_axes, fixed_axes = figure.subplots(1, 2)
    ids = readings.ids()
    levels = np.array([light_level(row, lamp_height_cm) for row in readings.rows])
    worst = 0.0
    for colour, pid in zip(_colours(len(ids)), ids, strict=True):
        mine = [
            (level, row) for level, row in zip(levels, readings.rows, strict=True) if row.id == pid
        ]
        for k in range(SENSOR_COUNT):
            points = sorted((level, row.sensors[k]) for level, row in mine if row.healthy(k))
            if not points:
                continue
            x = np.array([level for level, _ in points])
            raw = np.array([rho(value) for _, value in points])
            label = f"particle {pid}" if k == 0 else None
            raw_axes.plot(x, raw, "o-", color=colour, ms=3, lw=0.7, alpha=0.8, label=label)
            if pid in corrections:
                c = corrections[pid]
                fixed = np.array(
                    [
                        rho(corrected_reading(value, c.gamma_milli[k], c.gain_milli[k]))
                        for _, value in points
                    ]
                )
                deviation = 100 * (fixed / (scale * x) - 1)
                worst = max(worst, float(np.max(np.abs(deviation))))
                fixed_axes.plot(x, deviation, "o-", color=colour, ms=3, lw=0.7, alpha=0.8)
    span = np.array([levels.min(), levels.max()])
    raw_axes.plot(span, scale * span, "k--", lw=1.2, label=f"the law: {scale:.4g} x")
    fixed_axes.axhline(0, color="black", lw=1.2, ls="--")
    x_label = "r^2 (m^2), r from the lamp to the photocells" if unit == DISTANCE_UNIT else "1 / lux"
    raw_axes.set_yscale("log")
    raw_axes.set_ylabel("rho = (1023 - V) / V: photocell over load resistance")
    raw_axes.set_title("as read: a power law per photocell (gamma, c)")
    raw_axes.legend(fontsize=7, ncol=2)
    fixed_axes.set_ylabel("rho' / (scale x) - 1 (%)")
    fixed_axes.set_title(f"calibrated: every photocell within {worst:.1f} % of the law")
    for axes in (raw_axes, fixed_axes):
        axes.set_xscale("log")
        axes.xaxis.set_major_formatter(ScalarFormatter())
        axes.xaxis.set_minor_formatter(ScalarFormatter())
        axes.tick_params(axis="x", which="minor", labelsize=7)
        axes.set_xlabel(x_label)
        axes.grid(alpha=0.3, which="both")
    figure.suptitle(
        f"{len(ids)} particles, {SENSOR_COUNT} photocells each: rho' = gain * rho^(1/gamma) "
        f"= {scale:.4g} x"
    )
    return _save(figure, path)


def _colours(count: int) -> list[tuple[float, float, float, float]]:
    from matplotlib import colormaps

    cmap = colormaps["viridis"]
    return [cmap(i / max(1, count - 1) * 0.9) for i in range(count)]


def plot_positions(check: PositionCheck, path: Path, title: str = "") -> Path:
    """Fig. S5(b): estimated against true floor distance, mean and one standard deviation over
    the trials, before and after calibration; and the error of each particle."""
    figure = Figure(figsize=(11, 4.6), layout="constrained")
    axes, error_axes = figure.subplots(1, 2, width_ratios=[1.1, 1])
    truth = np.array([p.true_cm for p in check.particles])
    raw = "raw readings (uncalibrated)"
    series = [(raw, "tab:red", "s", -0.8, [p.before_cm for p in check.particles])]
    if check.has_after:
        series.append(("calibrated", "tab:blue", "o", 0.8, [p.after_cm for p in check.particles]))
    top = float(truth.max()) * 1.15 + 5
    axes.plot([0, top], [0, top], color="0.6", lw=1, ls="--", label="estimate = truth")
    rms = {raw: check.rms_before(), "calibrated": check.rms_after()}
    for label, colour, marker, shift, values in series:
        means = np.array([np.mean(v) if v else np.nan for v in values])
        sds = np.array([np.std(v, ddof=1) if len(v) > 1 else 0.0 for v in values])
        text = f"{label}: RMS error {rms[label]:.1f} cm"
        axes.errorbar(
            truth + shift, means, yerr=sds, fmt=marker, color=colour, ms=5, capsize=3, label=text
        )
        error_axes.errorbar(
            truth + shift,
            means - truth,
            yerr=sds,
            fmt=marker + "-",
            color=colour,
            ms=5,
            lw=0.8,
            capsize=3,
            label=label,
        )
    for p in check.particles:
        axes.annotate(
            str(p.id),
            (p.true_cm, p.true_cm),
            textcoords="offset points",
            xytext=(-4, 8),
            fontsize=7,
        )
    axes.set_xlim(-5, top)
    axes.set_ylim(-5, top)
    axes.set_aspect("equal")
    axes.set_xlabel("true distance from the point under the lamp (cm)")
    axes.set_ylabel("estimated distance, eqs. 14-15 (cm)")
    axes.set_title(
        title or f"{len(check.particles)} particles, {check.trials} trial(s): mean and 1 s.d."
    )
    axes.grid(alpha=0.3)
    axes.legend(fontsize=8, loc="upper left")
    error_axes.axhline(0, color="black", lw=0.8)
    error_axes.set_xlabel("true distance (cm)")
    error_axes.set_ylabel("estimate - truth (cm)")
    error_axes.set_title(
        f"reference: particle {check.reference_id}, lamp {check.lamp_height_cm:g} cm above"
    )
    error_axes.grid(alpha=0.3)
    error_axes.legend(fontsize=8)
    return _save(figure, path)


def plot_servo(
    particle_id: int,
    held_pulses: Sequence[int],
    radii_mm: Sequence[float],
    old_table: Sequence[int],
    table: ServoTable,
    path: Path,
) -> Path:
    """Radius against pulse: what was measured, what the old table assumed, the new table."""
    figure = Figure(figsize=(7.5, 5), layout="constrained")
    axes = figure.subplots()
    order = np.argsort(held_pulses)
    axes.plot(
        np.asarray(held_pulses)[order],
        np.asarray(radii_mm)[order],
        "o-",
        color="tab:blue",
        label="measured while held",
    )
    axes.plot(old_table, table.targets_mm, "x--", color="0.5", label="old table (SERVO_CAL_0..8)")
    axes.plot(
        table.pulses, table.targets_mm, "s", color="tab:orange", ms=7, mfc="none", label="new table"
    )
    for k in table.extrapolated:
        axes.annotate(
            "extrapolated",
            (table.pulses[k], table.targets_mm[k]),
            textcoords="offset points",
            xytext=(6, -10),
            fontsize=7,
            color="tab:orange",
        )
    for radius in (table.targets_mm[0], table.targets_mm[-1]):
        axes.axhline(radius, color="0.85", lw=0.8, zorder=0)
    axes.set_xlabel("servo pulse (us)")
    axes.set_ylabel("radius (mm)")
    axes.set_title(f"particle {particle_id}: servo calibration")
    axes.grid(alpha=0.3)
    axes.legend(fontsize=8)
    return _save(figure, path)
