"""`particlebot demo`: a blob of virtual particles, each running the firmware logic, STARTed with
phototaxis on, crawls toward a lamp in the 2-D world; then the run measured as Table S2 was."""

from __future__ import annotations

import argparse
import json
import math
import tempfile
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from rich.text import Text

from particlebot.commands._arguments import add_log_options
from particlebot.commands._common import fail, has_terminal, opened_swarm
from particlebot.commands._kernels import prepare_kernels
from particlebot.commands.plot import write_plot
from particlebot.console.worldmap import MapParticle, render_map
from particlebot.logs.jsonl import LogError
from particlebot.options import NON_NEGATIVE, POSITIVE, SPEED, Bounds, float_arg, int_arg
from particlebot.progress import ProgressBar
from particlebot.radio import RadioError
from particlebot.radio.sizes import VIRTUAL_MAX_PARTICLES as MAX_PARTICLES
from particlebot.swarm.api import METHODS, Swarm, method_letter, method_of
from particlebot.swarm.results import ParticlesMissing, StopReport, SwarmError

if TYPE_CHECKING:  # the simulator is imported where the demo runs, so that --help stays quick
    from particlebot.radio.simulated import SwarmRadio

PROGRESS_S = 30.0
"""Without a terminal the run reports how far the swarm has come every 30 s of its time."""
EXPANDED_M = 0.0005


@dataclass
class DemoScript:
    """The demo, written against the Swarm API as any script would be: wait for every particle,
    START (phototaxis on), let the swarm crawl toward the lamp, STOP. It runs on the console's
    script thread, or directly without a terminal; all times are the radio's (simulated) clock,
    so it does the same at any speed."""

    swarm: Swarm
    method: str = "A"
    cycle_steps: int = 150
    run_s: float = 300.0
    listen_timeout_s: float = 15.0
    report: Callable[[str], None] | None = None
    """Where progress goes without a terminal (the console shows the swarm itself)."""
    start_distance_m: float = math.nan
    stop_report: StopReport | None = None
    failure: str | None = None
    track: list[tuple[float, float]] = field(default_factory=list)

    @property
    def radio(self) -> SwarmRadio:
        from particlebot.radio.simulated import SwarmRadio

        radio = self.swarm.radio
        assert isinstance(radio, SwarmRadio)
        return radio

    def __call__(self) -> int:
        swarm = self.swarm
        expected = self.radio.swarm.count
        try:
            swarm.wait_for(count=expected, timeout=self.listen_timeout_s)
        except ParticlesMissing as exc:
            swarm.note(f"demo: {exc}; starting those heard")
        self.start_distance_m = self.distance_m()
        try:
            swarm.start(self.method, cycle_steps=self.cycle_steps, phototaxis=True)
        except SwarmError as exc:
            self.failure = str(exc)
        else:
            elapsed = 0.0
            while elapsed < self.run_s:
                step = min(PROGRESS_S, self.run_s - elapsed)
                swarm.sleep(step)
                elapsed += step
                moved = self.start_distance_m - self.distance_m()
                text = f"demo: {elapsed:.0f} s, the swarm {moved * 100:+.1f} cm toward the lamp"
                swarm.note(text)
                if self.report is not None:
                    self.report(text)
        self.stop_report = swarm.stop()
        if not self.stop_report.confirmed and self.failure is None:
            self.failure = self.stop_report.text
        return 0 if self.failure is None else 1

    def centroid(self) -> tuple[float, float]:
        snapshot = self.radio.swarm.snapshot()
        return (
            float(np.mean([p.x for p in snapshot])),
            float(np.mean([p.y for p in snapshot])),
        )

    def distance_m(self) -> float:
        lamp = self.radio.swarm.world.lamp
        x, y = self.centroid()
        return math.hypot(x - lamp.x, y - lamp.y)

    def world_map(self, width: int, height: int) -> Text:
        """The console's top view: the particles as their truth has them, by state."""
        world = self.radio.swarm
        states = {p.id: p.state for p in self.swarm.particles()}
        r_min = world.world.params.r_min
        particles = [
            MapParticle(p.id, p.x, p.y, p.radius_um * 1e-6 > r_min + EXPANDED_M, states.get(p.id))
            for p in world.snapshot()
        ]
        centroid = self.centroid()
        if not self.track or math.dist(self.track[-1], centroid) > 0.005:
            self.track.append(centroid)
        lamp = world.world.lamp
        return render_map(particles, (lamp.x, lamp.y), self.track, width, height)


@dataclass(frozen=True)
class DemoFigures:
    """Table S2's figures of the run (SI S6), from its session log."""

    particles: int
    method: str
    simulated_s: float
    toward_lamp_m: float
    average_pct: float
    peak_pct: float
    average_mm_s: float
    p_value: float
    cycle_s: float

    def lines(self) -> list[str]:
        return [
            f"centroid every 30 s, lamp on +y: {self.toward_lamp_m * 100:+.1f} cm toward the "
            f"lamp in {self.simulated_s:.0f} s",
            f"average speed {self.average_pct:.2f} % min. diameter/cycle "
            f"({self.average_mm_s:.3f} mm/s, cycle {self.cycle_s:g} s), peak "
            f"{self.peak_pct:.2f} %; one-tailed t-test p = {self.p_value:.2e}",
            "Table S2 (the paper's nine phototaxis experiments): 1.79-3.13 % average, every "
            "p < 0.01",
        ]

    def as_json(self) -> str:
        return json.dumps(
            {
                "particles": self.particles,
                "method": self.method,
                "simulated_s": round(self.simulated_s, 3),
                "centroid_toward_lamp_m": round(self.toward_lamp_m, 4),
                "speed_pct_min_diameter_per_cycle": round(self.average_pct, 3),
                "peak_pct_min_diameter_per_cycle": round(self.peak_pct, 3),
                "speed_mm_s": round(self.average_mm_s, 4),
                "cycle_s": self.cycle_s,
                "p_value": self.p_value,
            }
        )


def figures(log: Path, particles: int, method: str) -> DemoFigures:
    """The run's Table S2 figures from its session log (SourceError when it cannot say)."""
    from particlebot.analysis.sources import load_source
    from particlebot.analysis.stats import StatsSettings, analyse

    (series,) = load_source(log)
    stats = analyse(series, StatsSettings())
    y = stats.sample_y_cm[np.isfinite(stats.sample_y_cm)]
    return DemoFigures(
        particles=particles,
        method=method,
        simulated_s=float(series.t_s[-1] - series.t_s[0]),
        toward_lamp_m=float(y[-1] - y[0]) / 100,
        average_pct=stats.average_pct,
        peak_pct=stats.peak_pct,
        average_mm_s=stats.average_mm_s,
        p_value=stats.p_value,
        cycle_s=stats.cycle_s,
    )


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--particles",
        type=int_arg(Bounds(minimum=1, maximum=MAX_PARTICLES)),
        default=10,
        help=f"how many, 1..{MAX_PARTICLES} (default 10)",
    )
    parser.add_argument(
        "--method",
        choices=sorted({k.upper() for k in METHODS if len(k) == 1}),
        default="A",
        help="how each particle estimates its place (default A: direct, eqs. 14-16)",
    )
    parser.add_argument(
        "--speed",
        type=float_arg(SPEED),
        help="times real time, or max (default 10 live, max without a terminal)",
    )
    parser.add_argument(
        "--run-s",
        type=float_arg(POSITIVE),
        default=300.0,
        help="simulated seconds from START to STOP (default 300)",
    )
    parser.add_argument(
        "--start-m",
        type=float_arg(Bounds(minimum=0.2, maximum=10.0)),
        default=1.0,
        help="the blob's first particle this far from the lamp's foot, m (default 1.0)",
    )
    parser.add_argument(
        "--seed", type=int_arg(NON_NEGATIVE), default=3, help="random seed of the blob (3)"
    )
    parser.add_argument("--no-ui", action="store_true", help="print a summary, no live console")
    parser.add_argument(
        "--json", action="store_true", help="end with the run's figures as one JSON line"
    )
    parser.add_argument(
        "--no-animation", action="store_true", help="no MP4 of the top view (it takes a while)"
    )
    parser.add_argument("--no-log", action="store_true", help="do not keep the session log")
    add_log_options(parser)


def run(args: argparse.Namespace) -> int:
    ui = not args.no_ui and not args.json and has_terminal()
    speed = args.speed if args.speed is not None else (10.0 if ui else math.inf)
    shown = "max" if math.isinf(speed) else f"{speed:g}"
    url = (
        f"virtual://{args.particles}?scenario=blob&start={args.start_m:g}&seed={args.seed}"
        f"&speed={shown}"
    )
    method = method_letter(method_of(args.method))
    try:
        prepare_kernels()  # before the console or the run's clock starts
    except KeyboardInterrupt:
        return 130
    with tempfile.TemporaryDirectory(prefix="particlebot-demo-") as scratch:
        # The figures come from the session log: without one to keep, a scratch one.
        log_dir = Path(scratch) if args.no_log else Path(args.log_dir)
        try:
            code, log = _run_swarm(args, ui, url, speed, method, log_dir)
        except (RadioError, LogError, SwarmError) as exc:
            return fail(str(exc))
        if log is None:
            return code
        from particlebot.analysis.sources import SourceError

        try:
            result = figures(log, args.particles, method)
        except SourceError as exc:
            return fail(f"the run cannot be measured: {exc}")
        for line in result.lines():
            print(line)
        significant = result.p_value < 0.01 and result.toward_lamp_m > 0
        print(
            "the swarm moved toward the lamp, significantly (p < 0.01), as in Table S2"
            if significant
            else "not a significant move toward the lamp (p >= 0.01): run it longer (--run-s)"
        )
        if not ui and not args.no_log:
            # Drawn once the log is closed, so it holds the whole session; a failed picture is
            # reported but does not turn a good demo into a failed one.
            write_plot(log)
            if not args.no_animation:
                _write_animation(log)
        if args.json:
            print(result.as_json())
        return code


def _run_swarm(
    args: argparse.Namespace, ui: bool, url: str, speed: float, method: str, log_dir: Path
) -> tuple[int, Path | None]:
    # A person watches the console: the simulation keeps its pace on its own thread.
    stepped = False if ui else None
    with opened_swarm(url, log_dir, stepped=stepped, announce_log=not args.no_log) as swarm:
        log = swarm.log_path
        report = None if ui else (lambda text: print(text, flush=True))
        script = DemoScript(swarm, method=method, run_s=args.run_s, report=report)
        if ui:
            from particlebot.console.app import ConsoleApp  # Textual only when shown

            try:
                code = ConsoleApp(swarm, script=script, world_map=script.world_map).run()
            except KeyboardInterrupt:
                return 130, None
            code = 130 if code is None else code
        else:
            pace = "as fast as it runs" if math.isinf(speed) else f"{speed:g}x real time"
            print(
                f"Virtual swarm of {args.particles} particles (the firmware logic) in a blob "
                f"{args.start_m:g} m from a lamp, {pace}; START method {method} with "
                f"phototaxis on, {args.run_s:g} s, then STOP.",
                flush=True,
            )
            try:
                code = script()
            except KeyboardInterrupt:
                return 130, None
        if script.stop_report is not None:
            print(script.stop_report.text)
        if script.failure:
            print(f"FAILED: {script.failure}")
        print(f"simulated {script.radio.swarm.time_s:.1f} s")
    return code, log


def _write_animation(log: Path) -> None:
    from particlebot.analysis.animation import AnimationError, write_animation

    output = log.with_suffix(".mp4")
    bars: dict[str, ProgressBar] = {}

    def progress(stage: str, done: int, total: int) -> None:
        # A bar per stage (drawing the frames, then encoding them): each takes minutes.
        if stage not in bars:
            for earlier in bars.values():
                earlier.finish()
            bars[stage] = ProgressBar(f"animation {output.name}: {stage}", total)
            bars[stage].start(show_now=False)
        bars[stage].update(done)

    try:
        write_animation(log, output, progress=progress)
    except AnimationError as exc:
        print(f"particlebot: no animation: {exc}")
    else:
        print(f"Animation: {output}")
    finally:
        for bar in bars.values():
            bar.finish()
