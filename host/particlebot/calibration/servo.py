"""Servo calibration's arithmetic: the nine-point table from radii measured at held pulses, and an
order of SET_PARAMs that the firmware's monotonicity check accepts at every step.

The firmware turns a radius into a pulse through SERVO_CAL_0..8: point k is the pulse of radius
R_min + k/8 (R_max - R_min), linear in between (firmware/lib/actuation). A person measures the
radius each of nine held pulses gives; the new table is that measured curve read backwards at
the nine radii the table stands for. The firmware refuses any single SET that would leave the
table neither rising nor falling, so a new table is written point by point in an order where
every intermediate table is monotonic.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from particlebot.calibration.photocells import CalibrationError
from particlebot.protocol import PARAM_SPECS, Param

POINTS = 9
TABLE_PARAMS = tuple(Param(Param.SERVO_CAL_0 + k) for k in range(POINTS))
PULSE_MIN = PARAM_SPECS[Param.SERVO_CAL_0].min
PULSE_MAX = PARAM_SPECS[Param.SERVO_CAL_0].max


def target_radii_mm(r_min_um: int, r_max_um: int) -> list[float]:
    """The radius each table point stands for (mm)."""
    return [(r_min_um + k * (r_max_um - r_min_um) / (POINTS - 1)) / 1000 for k in range(POINTS)]


def _direction(values: Sequence[float]) -> int:
    """+1 rising, -1 falling (non-strictly), 0 neither; a flat table counts as rising."""
    steps = np.diff(np.asarray(values, dtype=float))
    if np.all(steps >= 0):
        return 1
    if np.all(steps <= 0):
        return -1
    return 0


def monotonic(table: Sequence[int]) -> bool:
    """Whether the firmware takes this table: its pulses never fall, or never rise."""
    return _direction(table) != 0


def check_measurements(pulses: Sequence[int], radii_mm: Sequence[float]) -> None:
    """CalibrationError unless the radius strictly grows, or strictly shrinks, with the pulse
    (in the order the points were held): names the first point out of line."""
    order = np.argsort(pulses, kind="stable")
    p = [pulses[i] for i in order]
    r = [radii_mm[i] for i in order]
    if len(set(p)) != len(p):
        raise CalibrationError("two points were held at the same pulse: each needs its own")
    rising = r[-1] > r[0]
    for i in range(1, len(r)):
        if (r[i] <= r[i - 1]) if rising else (r[i] >= r[i - 1]):
            a, b = int(order[i - 1]), int(order[i])
            word = "above" if rising else "below"
            raise CalibrationError(
                f"the radius is not monotonic in the pulse: point {b} ({r[i]:g} mm at {p[i]} us) "
                f"is not {word} point {a} ({r[i - 1]:g} mm at {p[i - 1]} us); measure them again"
            )


@dataclass(frozen=True)
class ServoTable:
    """The new table and what it is based on."""

    pulses: tuple[int, ...]
    targets_mm: tuple[float, ...]
    extrapolated: tuple[int, ...]
    """Points whose radius lies outside what was measured (the end segments extended)."""


def table_from_measurements(
    pulses: Sequence[int], radii_mm: Sequence[float], targets_mm: Sequence[float]
) -> ServoTable:
    """The pulse for each target radius: the measured curve, linear between measured points and
    along its end segments beyond them, clamped to the pulses a servo takes."""
    check_measurements(pulses, radii_mm)
    order = np.argsort(radii_mm)
    r = np.asarray(radii_mm, dtype=float)[order]
    p = np.asarray(pulses, dtype=float)[order]
    new: list[int] = []
    extrapolated: list[int] = []
    for k, target in enumerate(targets_mm):
        if target < r[0] or target > r[-1]:
            extrapolated.append(k)
            i = 0 if target < r[0] else len(r) - 2
            slope = (p[i + 1] - p[i]) / (r[i + 1] - r[i])
            value = p[i] + slope * (target - r[i])
        else:
            value = float(np.interp(target, r, p))
        new.append(int(min(max(round(value), PULSE_MIN), PULSE_MAX)))
    if not monotonic(new):
        raise CalibrationError(f"the new table {new} would not be monotonic")
    return ServoTable(tuple(new), tuple(targets_mm), tuple(extrapolated))


def _greedy(current: list[int], target: Sequence[int], sign: int) -> list[tuple[int, int]]:
    """Writes for two tables monotonic the same way (sign +1 rising, -1 falling): the lowest
    point that must come down first, else the highest that must go up; each keeps every
    intermediate table monotonic (the points it lies between are already where they may be)."""
    writes: list[tuple[int, int]] = []
    table = list(current)
    while True:
        lower = [k for k in range(POINTS) if sign * target[k] < sign * table[k]]
        higher = [k for k in range(POINTS) if sign * target[k] > sign * table[k]]
        if lower:
            k = lower[0]
        elif higher:
            k = higher[-1]
        else:
            return writes
        table[k] = target[k]
        writes.append((k, target[k]))


def write_order(current: Sequence[int], new: Sequence[int]) -> list[tuple[int, int]]:
    """(point, pulse) SETs that take the particle's table from current to new, each leaving a
    table the firmware accepts. Tables that run opposite ways pass through a flat one."""
    if len(current) != POINTS or len(new) != POINTS:
        raise ValueError(f"servo tables have {POINTS} points")
    if not monotonic(new):
        raise CalibrationError(f"the table {list(new)} is not monotonic: the firmware refuses it")
    now, then = _direction(current), _direction(new)
    if now == 0:
        raise CalibrationError(f"the particle's table {list(current)} is not monotonic")
    if now == then:
        return _greedy(list(current), new, now)
    flat = [new[0]] * POINTS
    return _greedy(list(current), flat, now) + _greedy(flat, new, then)
