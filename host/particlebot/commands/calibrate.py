"""`particlebot calibrate sensors|check|servo`: photocells fitted and corrected (SI S3), Fig. S5's
check of position estimates, and a particle's servo table measured point by point."""

from __future__ import annotations

import argparse
import datetime as dt
import sys
from collections.abc import Callable
from contextlib import AbstractContextManager
from pathlib import Path
from typing import TYPE_CHECKING, TextIO

from particlebot.commands._arguments import add_radio_options
from particlebot.commands._common import fail, sigterm_as_interrupt
from particlebot.options import (
    DISTANCE_CM,
    LENGTH_CM,
    NON_NEGATIVE,
    POSITIVE,
    Bounds,
    OptionError,
    float_arg,
    int_arg,
    parse_float,
)
from particlebot.protocol import PARAM_SPECS, Param

if TYPE_CHECKING:
    from particlebot.calibration.bench import Bench, SensorOutcome
    from particlebot.calibration.readings import Readings
    from particlebot.swarm.api import Swarm

DEFAULT_DISTANCES = "20,40,70,100"
DEFAULT_LAMP_HEIGHT_CM = PARAM_SPECS[Param.REF_DISTANCE_MM].default / 10
DEFAULT_SPACING_CM = PARAM_SPECS[Param.DIAMETER_MM].default / 10
"""Fig. S5's line: particles touching, one contracted diameter apart."""
OUTPUT_DIR = Path("calibration")
PARTICLE_ID = Bounds(minimum=1, maximum=253)
SENSORS_HELP = """\
Fits each photocell's gamma (eq. 7) and a gain so that every photocell of every particle follows
one law, rho' = scale * r^2, which is what eq. 14 (method A) assumes; writes SENSOR_GAMMA_0..5 and
SENSOR_GAIN_0..5 to each particle (confirmed), has one particle put right under the lamp to
capture method A's V_x (REF_VALUE, with REF_DISTANCE_MM = the lamp's height) for all of them, and
records it all in the fleet file. Readings: each particle at each --distances (a circle around
the point under the lamp), or a --line rotated --steps times, or under each --lux; the readings
go to a CSV as they are taken, and --readings FILE fits such a file again. On a simulated radio
(virtual://, emulated://; add photocell_spread=0.1 to give its photocells something to
calibrate) the tool places the particles itself."""
CHECK_HELP = """\
Fig. S5: a line of particles from the point under the lamp, --trials times; each particle's
distance estimated from its reading by eqs. 14-15, with the nearest particle's reading as V_x,
against where it stands: from the raw photocell readings (what an uncalibrated particle reads) and
from the particle's own, calibrated, intensity. Mean and standard deviation per particle, RMS
error, a plot. --readings FILE draws a file this command wrote."""
SERVO_HELP = """\
Makes particle ID hold each of nine pulses (SERVO_HOLD; its own table's by default) while you
measure its radius, centre to rim, in mm; Enter takes the value in brackets, b goes back a
point, r holds the point again, q quits. Then the new table (the pulses of the radii R_min ..
R_max the table stands for) is shown, written in an order the firmware accepts, read back,
recorded in the fleet file and drawn. The hold is renewed while you measure and ends when the
command does, Ctrl-C included. Answers may come from a file: nine radii, then an empty line to
write (particlebot calibrate servo 3 < radii.txt)."""


def number_list(bounds: Bounds, *, whole: bool = False) -> Callable[[str], list[float]]:
    """An argparse `type=`: comma-separated numbers within bounds."""

    def parse(text: str) -> list[float]:
        values = []
        for part in text.split(","):
            try:
                value = parse_float(part.strip(), bounds)
            except OptionError as exc:
                raise argparse.ArgumentTypeError(f"each value {exc}") from None
            if whole and value != int(value):
                raise argparse.ArgumentTypeError(f"each value must be a whole number, not {part}")
            values.append(value)
        return values

    return parse


def id_list(text: str) -> list[int]:
    """An argparse `type=`: particle ids, e.g. 1-9,12."""
    ids: set[int] = set()
    for part in text.split(","):
        first, dash, last = part.strip().partition("-")
        try:
            low = int(first)
            high = int(last) if dash else low
        except ValueError:
            raise argparse.ArgumentTypeError(f"ids are like 1-9,12, not '{text}'") from None
        if not 1 <= low <= high <= 253:
            raise argparse.ArgumentTypeError(f"particle ids are 1..253, not '{part.strip()}'")
        ids.update(range(low, high + 1))
    return sorted(ids)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    actions = parser.add_subparsers(dest="calibrate_action", metavar="WHAT", required=True)
    sensors = actions.add_parser(
        "sensors", help="fit and write each photocell's gamma and gain", description=SENSORS_HELP
    )
    _particle_options(sensors)
    light = sensors.add_mutually_exclusive_group()
    light.add_argument(
        "--distances",
        type=number_list(DISTANCE_CM),
        help=f"floor distances (cm) from the point under the lamp (default {DEFAULT_DISTANCES})",
    )
    light.add_argument(
        "--lux",
        type=number_list(Bounds(above=0, maximum=1e6)),  # full sunlight is 10^5 lx
        help="illuminances (lx) read with a lux meter instead",
    )
    sensors.add_argument(
        "--line",
        action="store_true",
        help="the distances are a line's places, one per particle in id order, the line moved on "
        "one place each step",
    )
    sensors.add_argument(
        "--steps", type=int_arg(Bounds(minimum=2, maximum=100)), default=3, help="--line steps"
    )
    sensors.add_argument("--reference-id", type=int_arg(PARTICLE_ID), help="V_x from this one")
    sensors.add_argument("--readings", type=Path, help="fit this readings CSV; measure nothing")
    sensors.add_argument(
        "--no-write", action="store_true", help="fit and show, write nothing to the particles"
    )
    sensors.add_argument(
        "--check",
        action="store_true",
        help="then Fig. S5's check (see calibrate check) on the same particles, --trials times",
    )
    _trials_option(sensors)
    sensors.add_argument(
        "--new-law",
        action="store_true",
        help="a new fleet law instead of the fleet file's (a new lamp: calibrate every particle)",
    )
    _reading_options(sensors, frames=5)

    check = actions.add_parser(
        "check",
        help="Fig. S5: a line's positions estimated from its readings",
        description=CHECK_HELP,
    )
    _particle_options(check)
    place = check.add_mutually_exclusive_group()
    place.add_argument(
        "--spacing-cm",
        type=float_arg(LENGTH_CM),
        help=f"a place every SPACING cm from under the lamp (default {DEFAULT_SPACING_CM:g})",
    )
    place.add_argument(
        "--positions",
        type=number_list(DISTANCE_CM),
        help="each particle's place (cm), in id order",
    )
    _trials_option(check)
    check.add_argument("--readings", type=Path, help="draw this readings CSV; measure nothing")
    _reading_options(check, frames=3)

    servo = actions.add_parser(
        "servo", help="measure and write a particle's servo table", description=SERVO_HELP
    )
    servo.add_argument("id", type=int_arg(PARTICLE_ID), help="the particle (1..253)")
    add_radio_options(servo)
    servo.add_argument("--fleet", type=Path, help="fleet file (default ./fleet.toml if there)")
    servo.add_argument(
        "--pulses",
        type=number_list(Bounds(minimum=500, maximum=2500), whole=True),
        help="nine pulses (us) to hold (default: the particle's own table)",
    )
    servo.add_argument("-o", "--output", type=Path, help="CSV of the points (and a PNG beside)")


def _trials_option(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--trials",
        type=int_arg(Bounds(minimum=1, maximum=100)),
        default=5,
        help="Fig. S5's trials: the line laid out afresh each time (5, as in the paper)",
    )


def _particle_options(parser: argparse.ArgumentParser) -> None:
    add_radio_options(parser)
    parser.add_argument("--fleet", type=Path, help="fleet file (default ./fleet.toml if there)")
    parser.add_argument(
        "--ids", type=id_list, help="the particles, e.g. 1-9 (default: the fleet's)"
    )
    parser.add_argument(
        "--count", type=int_arg(Bounds(minimum=1, maximum=253)), help="or: the first N heard"
    )


def _reading_options(parser: argparse.ArgumentParser, frames: int) -> None:
    parser.add_argument(
        "--lamp-height-cm",
        type=float_arg(POSITIVE),
        help=f"lamp centre above the photocells (default {DEFAULT_LAMP_HEIGHT_CM:g}, SI S3)",
    )
    parser.add_argument(
        "--frames",
        type=int_arg(Bounds(minimum=1, maximum=50)),
        default=frames,
        help=f"STATUS reports averaged per reading ({frames})",
    )
    parser.add_argument(
        "--settle-s",
        type=float_arg(Bounds(minimum=0, maximum=600)),
        default=1.0,
        help="seconds after each placement before reading (1)",
    )
    parser.add_argument("-o", "--output", type=Path, help="readings CSV (a PNG goes beside it)")
    parser.add_argument("--no-plot", action="store_true", help="no plot")


def run(args: argparse.Namespace) -> int:
    from particlebot.calibration.photocells import CalibrationError
    from particlebot.calibration.prompts import NobodyAnswers, Quit
    from particlebot.calibration.readings import ReadingsError
    from particlebot.fleet import FleetFileError
    from particlebot.logs.jsonl import LogError
    from particlebot.radio import RadioError
    from particlebot.swarm.results import SwarmError

    action = args.calibrate_action
    out = sys.stdout
    try:
        with sigterm_as_interrupt():
            if action == "servo":
                return _servo(args, out)
            if action == "sensors":
                return _sensors(args, out)
            return _check(args, out)
    except NobodyAnswers:
        return fail(
            f"calibrate {action}: nobody can answer the prompt (no input): stopped, nothing more "
            "was written; answer on a terminal, or give the answers on stdin"
        )
    except Quit:
        print("Stopped as asked: nothing more was written.", file=out)
        return 1
    except KeyboardInterrupt:
        print(f"\nparticlebot: calibrate {action}: interrupted; nothing more was written", file=out)
        return 130
    except (
        CalibrationError,
        ReadingsError,
        RadioError,
        LogError,
        FleetFileError,
        SwarmError,
        ValueError,
    ) as exc:
        return fail(f"calibrate {action}: {exc}")
    except OSError as exc:  # an output place that cannot be written (-o under a file, /proc)
        where = exc.filename if exc.filename else "its outputs"
        return fail(f"calibrate {action}: cannot write {where}: {exc.strerror or exc}")


# ---- shared --------------------------------------------------------------------------------------


def _stamp() -> str:
    return dt.datetime.now().strftime("%Y%m%d-%H%M%S")


def _opened(args: argparse.Namespace, out: TextIO) -> AbstractContextManager[Swarm]:
    from particlebot.calibration import session

    fleet = session.fleet_path(args.fleet)
    return session.opened(args.radio, Path(args.log_dir), fsync=args.fsync, fleet=fleet, out=out)


def _outputs(args: argparse.Namespace, name: str) -> tuple[Path, Path]:
    csv_path = args.output or OUTPUT_DIR / f"{name}-{_stamp()}.csv"
    return csv_path, csv_path.with_suffix(".png")


# ---- sensors -------------------------------------------------------------------------------------


def _sensors(args: argparse.Namespace, out: TextIO) -> int:
    from particlebot.calibration import session
    from particlebot.calibration.bench import Bench, calibrate_sensors, readings_meta
    from particlebot.calibration.placements import line, lux_levels, ring
    from particlebot.calibration.prompts import Prompter
    from particlebot.calibration.readings import read_readings
    from particlebot.calibration.reports import sensors_text

    lamp_height = args.lamp_height_cm or DEFAULT_LAMP_HEIGHT_CM
    fleet_path = session.fleet_path(args.fleet)
    csv_path, png_path = _outputs(args, "sensors")
    if args.readings is not None:
        readings = read_readings(args.readings)
        lamp_height = readings.lamp_height_cm or lamp_height
        png_path = args.readings.with_suffix(".png") if args.output is None else png_path
    if args.readings is not None and (args.no_write or not args.radio):
        outcome = calibrate_sensors(readings, lamp_height, bench=None, fleet_path=fleet_path)
        print(sensors_text(outcome), file=out)
        _plot_sensors(args, outcome, lamp_height, png_path, out)
        return 0
    levels = args.lux or args.distances or []
    if args.readings is None and levels and len(set(levels)) < 2:
        what = (
            "--lux needs two or more illuminances"
            if args.lux
            else ("--distances needs two or more different distances")
        )
        raise ValueError(f"{what}: a gamma is the slope between two light levels or more")
    with _opened(args, out) as swarm:
        placer = session.placer(swarm, args.radio, Prompter(), out)
        bench = Bench(swarm, placer, out, args.frames, args.settle_s)
        if args.readings is None:
            ids = session.particle_ids(swarm, args.radio, args.ids, args.count)
            bench.check_at_rest(ids)
            if args.lux:
                if session.simulated(args.radio):
                    raise ValueError("simulated particles are placed by distance: use --distances")
                plan = lux_levels(ids, args.lux)
            else:
                distances = args.distances or number_list(NON_NEGATIVE)(DEFAULT_DISTANCES)
                plan = line(ids, distances, args.steps) if args.line else ring(ids, distances)
            meta = readings_meta("calibration", args.radio, lamp_height, args.frames)
            readings = session.measure(bench, plan, csv_path, meta)
        else:
            ids = readings.ids()
            swarm.wait_for(ids=ids)
            bench.check_at_rest(ids)
        outcome = calibrate_sensors(
            readings,
            lamp_height,
            bench=None if args.no_write else bench,
            fleet_path=fleet_path,
            new_law=args.new_law,
            reference_id=args.reference_id,
        )
        print(sensors_text(outcome), file=out)
        if args.check:
            check_csv = csv_path.with_name(f"{csv_path.stem}-check.csv")
            checked = _measure_line(args, bench, ids, lamp_height, check_csv)
            _report_check(
                checked, lamp_height, None if args.no_plot else check_csv.with_suffix(".png"), out
            )
        if fleet_path is not None and outcome.written:
            print(f"Recorded in {fleet_path}.", file=out)
        elif outcome.written:
            print(
                "No fleet file: the calibration lives in the particles (and the readings); "
                "`particlebot fleet init` makes one, so that the fleet's law is kept",
                file=out,
            )
    _plot_sensors(args, outcome, lamp_height, png_path, out)
    return 0


def _plot_sensors(
    args: argparse.Namespace, outcome: SensorOutcome, lamp_height: float, path: Path, out: TextIO
) -> None:
    from particlebot.calibration.figures import plot_photocells

    if args.no_plot:
        return
    law = outcome.calibration.law
    corrections = dict(outcome.calibration.corrections)
    plot_photocells(outcome.readings, corrections, law.scale, law.unit, lamp_height, path)
    print(f"Plot: {path}", file=out)


# ---- check (Fig. S5) -----------------------------------------------------------------------------


def _check(args: argparse.Namespace, out: TextIO) -> int:
    from particlebot.calibration import session
    from particlebot.calibration.bench import Bench
    from particlebot.calibration.prompts import Prompter
    from particlebot.calibration.readings import read_readings

    lamp_height = args.lamp_height_cm or DEFAULT_LAMP_HEIGHT_CM
    csv_path, png_path = _outputs(args, "check")
    if args.readings is not None:
        readings = read_readings(args.readings)
        lamp_height = readings.lamp_height_cm or lamp_height
        if args.output is None:
            png_path = args.readings.with_suffix(".png")
    else:
        with _opened(args, out) as swarm:
            placer = session.placer(swarm, args.radio, Prompter(), out)
            bench = Bench(swarm, placer, out, args.frames, args.settle_s)
            ids = session.particle_ids(swarm, args.radio, args.ids, args.count)
            bench.check_at_rest(ids)
            readings = _measure_line(args, bench, ids, lamp_height, csv_path)
    _report_check(readings, lamp_height, None if args.no_plot else png_path, out)
    return 0


def _measure_line(
    args: argparse.Namespace, bench: Bench, ids: list[int], lamp_height: float, csv_path: Path
) -> Readings:
    """Fig. S5's line from the options: --positions (or --spacing-cm apart), --trials times."""
    from particlebot.calibration import session

    positions = getattr(args, "positions", None)
    if positions is None:
        spacing = getattr(args, "spacing_cm", None) or DEFAULT_SPACING_CM
        positions = [k * spacing for k in range(len(ids))]
    return session.measure_line(
        bench, ids, positions, args.trials, args.radio, lamp_height, csv_path
    )


def _report_check(
    readings: Readings, lamp_height: float, png_path: Path | None, out: TextIO
) -> None:
    from particlebot.calibration.figures import plot_positions
    from particlebot.calibration.positions import check_positions
    from particlebot.calibration.reports import check_text

    check = check_positions(readings, lamp_height)
    print(check_text(check, lamp_height), file=out)
    if png_path is not None:
        plot_positions(check, png_path)
        print(f"Plot: {png_path}", file=out)


# ---- servo ---------------------------------------------------------------------------------------


def _servo(args: argparse.Namespace, out: TextIO) -> int:
    from particlebot.calibration import session
    from particlebot.calibration.figures import plot_servo
    from particlebot.calibration.prompts import Prompter
    from particlebot.calibration.reports import servo_text, write_servo_points
    from particlebot.calibration.servo import POINTS
    from particlebot.calibration.servo_bench import ServoBench, calibrate_servo

    pulses = None
    if args.pulses is not None:
        if len(args.pulses) != POINTS:
            raise ValueError(f"--pulses takes {POINTS} pulses, not {len(args.pulses)}")
        pulses = [int(p) for p in args.pulses]
    csv_path = args.output or OUTPUT_DIR / f"servo-{args.id}-{_stamp()}.csv"
    with _opened(args, out) as swarm:
        bench = ServoBench(swarm, args.id, Prompter(), out)
        outcome = calibrate_servo(bench, pulses=pulses, fleet_path=session.fleet_path(args.fleet))
    print(servo_text(outcome), file=out)
    write_servo_points(outcome, csv_path)
    print(f"Points: {csv_path}", file=out)
    png = plot_servo(
        args.id,
        outcome.pulses,
        outcome.radii_mm,
        outcome.old_table,
        outcome.table,
        csv_path.with_suffix(".png"),
    )
    print(f"Plot: {png}", file=out)
    return 0
