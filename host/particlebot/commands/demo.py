"""`particlebot demo`: a virtual swarm at a lamp is started with method D, watched, and stopped."""

from __future__ import annotations

import argparse
import itertools
from dataclasses import dataclass, field
from pathlib import Path

from particlebot.commands._arguments import add_log_options
from particlebot.commands._common import fail, has_terminal, opened_swarm
from particlebot.commands.plot import write_plot
from particlebot.logs.jsonl import LogError
from particlebot.options import NON_NEGATIVE, POSITIVE, SPEED, Bounds, float_arg, int_arg
from particlebot.protocol import PARAM_SPECS, Param, State
from particlebot.radio import RadioError
from particlebot.radio.virtual import MAX_PARTICLES, VirtualRadio
from particlebot.sim.scenarios import presets
from particlebot.sim.swarm import ParticleSnapshot, SimSwarm, SwarmConfig
from particlebot.swarm.api import Swarm
from particlebot.swarm.results import NotConfirmed, ParticlesMissing, StopReport, SwarmError


@dataclass
class DemoResult:
    particle_id: int
    start_distance: float
    end_distance: float
    rank: int
    s_n: int | None
    state: str
    intensity: int | None = None

    @property
    def ok(self) -> bool:
        return self.s_n == self.rank


@dataclass
class DemoScript:
    """The demo, written against the Swarm API as any script would be: wait for every particle,
    START (method D), wait for every S_n, let the line creep towards the lamp, STOP. It runs on
    the console's script thread, or directly without a terminal; all times are the radio's
    (simulated) clock, so it does the same at any speed."""

    swarm: Swarm
    world: SimSwarm
    cycle_steps: int = 100
    locomote_s: float = 12.0
    listen_timeout_s: float = 5.0
    estimate_timeout_s: float = 15.0
    start_snapshot: list[ParticleSnapshot] = field(default_factory=list)
    s_n: dict[int, int] = field(default_factory=dict)
    stop_report: StopReport | None = None
    failure: str | None = None

    def __call__(self) -> int:
        swarm = self.swarm
        expected = self.world.count
        try:
            swarm.wait_for(count=expected, timeout=self.listen_timeout_s)
        except ParticlesMissing as exc:
            swarm.note(f"demo: {exc}; starting those heard")
        self.start_snapshot = self.world.snapshot()
        try:
            run = swarm.start("D", cycle_steps=self.cycle_steps)
        except NotConfirmed as exc:
            self.failure = str(exc)
        else:
            if swarm.wait_until(lambda: self._every_s_n_in(run.run_id), self.estimate_timeout_s):
                swarm.note(f"demo: every particle reported S_n: {dict(sorted(self.s_n.items()))}")
                swarm.sleep(self.locomote_s)
            else:
                self.failure = f"only {len(self.s_n)} of {expected} particles reported S_n"
        self.stop_report = swarm.stop()
        if not self.stop_report.confirmed and self.failure is None:
            self.failure = self.stop_report.text
        return 0 if self.failure is None and self.all_ranks_match() else 1

    def _every_s_n_in(self, run_id: int) -> bool:
        for particle in self.swarm.particles():
            if (
                particle.run_id == run_id
                and particle.s_n
                and particle.state not in (None, State.IDLE, State.ESTIMATING)
            ):
                self.s_n[particle.id] = particle.s_n
        return len(self.s_n) >= self.world.count

    def results(self) -> list[DemoResult]:
        """One line per particle, ranked by distance to the lamp when START went out."""
        before = self.start_snapshot or self.world.snapshot()
        after = {p.id: p for p in self.world.snapshot()}
        ranked = sorted(before, key=lambda p: p.ground_distance)
        heard = {particle.id: particle for particle in self.swarm.particles()}
        results = []
        for rank, snapshot in enumerate(ranked, start=1):
            particle = heard.get(snapshot.id)
            state = "unheard"
            if particle is not None and particle.state is not None:
                state = particle.state.name
            end = after.get(snapshot.id, snapshot)
            results.append(
                DemoResult(
                    particle_id=snapshot.id,
                    start_distance=snapshot.ground_distance,
                    end_distance=end.ground_distance,
                    rank=rank,
                    s_n=self.s_n.get(snapshot.id),
                    state=state,
                    intensity=None if particle is None else particle.intensity,
                )
            )
        return results

    def all_ranks_match(self) -> bool:
        results = self.results()
        return bool(results) and all(result.ok for result in results)


def summary(script: DemoScript) -> str:
    lines = [
        "particle  distance at START  after   rank  S_n  state     ",
    ]
    for result in script.results():
        lines.append(
            f"{result.particle_id:>8}  {result.start_distance:>15.3f} m  {result.end_distance:.3f}"
            f"  {result.rank:>4}  {result.s_n if result.s_n is not None else '-':>3}  "
            f"{result.state:<9} {'ok' if result.ok else 'MISMATCH'}"
        )
    moved = [r.start_distance - r.end_distance for r in script.results()]
    if moved:
        lines.append(f"the line moved {sum(moved) / len(moved) * 1000:.0f} mm towards the lamp")
    if script.stop_report is not None:
        lines.append(script.stop_report.text)
    if script.failure:
        lines.append(f"FAILED: {script.failure}")
    verdict = "every S_n equals the particle's rank by distance to the lamp"
    lines.append(verdict if script.all_ranks_match() else "S_n does NOT match the ranks")
    if not script.all_ranks_match():
        lines.extend(unresolved_neighbours(script.results()))
    return "\n".join(lines)


def unresolved_neighbours(results: list[DemoResult]) -> list[str]:
    """Explains mismatches that are method D's resolution limit rather than a fault.

    Method D counts readings within COUNT_TOLERANCE of each other as one level, so two neighbours
    far from the lamp, whose readings differ less than that, share an S_n.
    """
    tolerance = PARAM_SPECS[Param.COUNT_TOLERANCE].default
    lines = []
    for near, far in itertools.pairwise(results):
        if near.intensity is None or far.intensity is None:
            continue
        if abs(near.intensity - far.intensity) <= tolerance:
            lines.append(
                f"particles {near.particle_id} and {far.particle_id} read {near.intensity} and "
                f"{far.intensity}, within +-{tolerance} (COUNT_TOLERANCE): method D counts them "
                "as one level; the light field cannot rank them"
            )
    return lines


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--particles",
        type=int_arg(Bounds(minimum=1, maximum=MAX_PARTICLES)),
        default=10,
        help=f"how many, 1..{MAX_PARTICLES} (default 10)",
    )
    parser.add_argument(
        "--speed",
        type=float_arg(SPEED),
        help="times real time, or max (default 2 live, 20 headless)",
    )
    parser.add_argument(
        "--run-s", type=float_arg(POSITIVE), default=12.0, help="simulated seconds of cycling"
    )
    parser.add_argument(
        "--seed", type=int_arg(NON_NEGATIVE), default=1, help="random seed of the particles"
    )
    parser.add_argument("--no-ui", action="store_true", help="print a summary, no live console")
    parser.add_argument("--no-log", action="store_true", help="do not write a session log")
    add_log_options(parser)


def run(args: argparse.Namespace) -> int:
    ui = not args.no_ui and has_terminal()
    speed = args.speed if args.speed is not None else (2.0 if ui else 20.0)
    config = SwarmConfig(scenario=presets.line(args.particles, seed=args.seed), seed=args.seed)
    try:
        world = SimSwarm(config)
    except (OSError, ImportError) as exc:
        return fail(
            f"the virtual particles need the native firmware library ({exc}); run: make native"
        )
    radio = VirtualRadio(world, url=f"virtual://{args.particles}?speed={speed:g}", speed=speed)
    log_dir = None if args.no_log else Path(args.log_dir)
    log_path: Path | None = None
    try:
        # A person watches the console: the simulation keeps its pace on its own thread.
        with opened_swarm(radio, log_dir, stepped=False if ui else None) as swarm:
            log_path = swarm.log_path
            script = DemoScript(swarm, world, locomote_s=args.run_s)
            if ui:
                from particlebot.console.app import ConsoleApp  # Textual only when shown

                try:
                    code = ConsoleApp(swarm, script=script).run()
                except KeyboardInterrupt:
                    return 130
                code = 130 if code is None else code
            else:
                print(
                    f"Virtual swarm of {args.particles} particles in a line from a lamp, "
                    f"{speed:g}x real time; START method D, then STOP.",
                    flush=True,
                )
                try:
                    code = script()
                except KeyboardInterrupt:
                    return 130
            print(summary(script))
            print(f"simulated {world.t:.1f} s at {world.achieved_speed:.1f}x real time")
    except (RadioError, LogError, SwarmError) as exc:
        return fail(str(exc))
    # Drawn once the log is closed, so it holds the whole session; a failed plot is reported but
    # does not turn a good demo into a failed one.
    if not ui and log_path is not None:
        write_plot(log_path)
    return code
