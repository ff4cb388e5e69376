"""What the calibrations say when they are done: the photocell fit, Fig. S5's check table and
the servo points, as text (and the servo points as a CSV)."""

from __future__ import annotations

from pathlib import Path

from particlebot.calibration.bench import SensorOutcome, calibration_table
from particlebot.calibration.positions import PositionCheck
from particlebot.calibration.servo_bench import ServoOutcome


def sensors_text(outcome: SensorOutcome) -> str:
    """The fit in one line, each particle's corrections, and the notes."""
    calibration = outcome.calibration
    law = calibration.law
    gammas = [g / 1000 for c in calibration.corrections.values() for g in c.gamma_milli]
    gains = [g / 1000 for c in calibration.corrections.values() for g in c.gain_milli]
    levels = len({(r.distance_cm, r.lux) for r in outcome.readings.rows})
    lines = [
        f"Fitted {len(calibration.fits)} particle(s) on {levels} light levels: gamma "
        f"{min(gammas):.3f}-{max(gammas):.3f}, gain {min(gains):.3f}-{max(gains):.3f}; law "
        f"rho' = {law.scale:.5g} x ({law.unit}, "
        f"{'the fleet file' + chr(39) + 's' if calibration.kept_law else 'new'})",
        calibration_table(calibration),
    ]
    lines += [f"  note: {note}" for note in outcome.notes]
    return "\n".join(lines)


def check_text(check: PositionCheck, lamp_height_cm: float) -> str:
    """Fig. S5 as a table: each particle's true and estimated position, raw and calibrated,
    then the RMS and worst errors."""
    lines = [
        f"Fig. S5: {len(check.particles)} particles, {check.trials} trial(s); reference particle "
        f"{check.reference_id}, lamp {lamp_height_cm:g} cm above the photocells"
    ]
    after = check.has_after
    lines.append(
        "    id  true cm   raw: estimate cm" + ("   calibrated: estimate cm" if after else "")
    )
    for p in check.particles:
        line = f"  {p.id:>4}  {p.true_cm:>7.1f}   {p.before_mean:>7.1f} +- {p.before_sd:<5.1f}"
        if after:
            line += f"      {p.after_mean:>7.1f} +- {p.after_sd:<5.1f}"
        lines.append(line)
    summary = f"RMS error: raw {check.rms_before():.1f} cm"
    worst = f"worst particle's mean: raw {check.worst_before():.1f} cm"
    if after:
        summary += f", calibrated {check.rms_after():.1f} cm"
        worst += f", calibrated {check.worst_after():.1f} cm"
    lines.append(f"{summary}; {worst}")
    return "\n".join(lines)


def servo_text(outcome: ServoOutcome) -> str:
    """The table written and read back, and the notes."""
    lines = [
        f"Wrote and read back particle {outcome.particle_id}'s table: "
        f"{', '.join(map(str, outcome.table.pulses))} us"
    ]
    lines += [f"  note: {note}" for note in outcome.notes]
    return "\n".join(lines)


def write_servo_points(outcome: ServoOutcome, path: Path) -> None:
    """Each point's pulse and measured radius beside the table's, as a CSV."""
    path.parent.mkdir(parents=True, exist_ok=True)
    lines = ["point,pulse_us,radius_mm,table_pulse_us,table_radius_mm"]
    lines += [
        f"{k},{p},{r:.2f},{t},{target:.2f}"
        for k, (p, r, t, target) in enumerate(
            zip(
                outcome.pulses,
                outcome.radii_mm,
                outcome.table.pulses,
                outcome.table.targets_mm,
                strict=True,
            )
        )
    ]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
