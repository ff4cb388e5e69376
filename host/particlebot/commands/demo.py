"""`particlebot demo`: a virtual swarm at a lamp is started with method D, watched, and stopped."""

from __future__ import annotations

import argparse
import enum
import itertools
from dataclasses import dataclass, field
from pathlib import Path

from particlebot.commands._common import fail, has_terminal, run_headless, station
from particlebot.commands.plot import write_plot
from particlebot.console.app import ConsoleApp
from particlebot.console.model import Campaign, ConsoleModel, state_name
from particlebot.logs.jsonl import LogError
from particlebot.protocol import PARAM_SPECS, Method, Param, State
from particlebot.radio import RadioError
from particlebot.radio.virtual import VirtualRadio
from particlebot.virtual.swarm import ParticleSnapshot, SwarmConfig, VirtualSwarm


class Phase(enum.Enum):
    LISTEN = "waiting to hear every particle"
    ESTIMATE = "START sent; waiting for every S_n"
    LOCOMOTE = "particles cycling"
    STOP = "STOP sent; waiting for every particle to confirm"
    DONE = "done"


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
    """The demo's steps, driven by poll() from the console's timer or a headless loop.

    All times are the radio's (simulated) clock, so the script does the same at any speed.
    """

    model: ConsoleModel
    swarm: VirtualSwarm
    cycle_steps: int = 100
    locomote_s: float = 12.0
    listen_timeout_s: float = 5.0
    estimate_timeout_s: float = 15.0
    phase: Phase = Phase.LISTEN
    started_at: float | None = None
    phase_at: float | None = None
    start_snapshot: list[ParticleSnapshot] = field(default_factory=list)
    s_n: dict[int, int] = field(default_factory=dict)
    stop_campaign: Campaign | None = None
    failure: str | None = None
    exit_code: int | None = None

    def poll(self) -> int | None:
        now = self.model.clock()
        if self.started_at is None:
            self.started_at = self.phase_at = now
        assert self.phase_at is not None
        in_phase = now - self.phase_at
        expected = len(self.swarm.members)
        if self.phase is Phase.LISTEN:
            heard = sum(1 for row in self.model.rows() if row.status is not None)
            if heard >= expected or in_phase > self.listen_timeout_s:
                self.start_snapshot = self.swarm.snapshot()
                self.model.start(Method.COUNTING, cycle_steps=self.cycle_steps)
                self._enter(Phase.ESTIMATE, now)
        elif self.phase is Phase.ESTIMATE:
            run_id = self.model.run_id
            for row in self.model.rows():
                status = row.status
                if (
                    status is not None
                    and status.run_id == run_id
                    and status.s_n
                    and status.state not in (State.IDLE, State.ESTIMATING)
                ):
                    self.s_n[row.id] = status.s_n
            if len(self.s_n) >= expected:
                self.model.note(f"demo: every particle reported S_n: {self.s_n}")
                self._enter(Phase.LOCOMOTE, now)
            elif in_phase > self.estimate_timeout_s:
                self.failure = f"only {len(self.s_n)} of {expected} particles reported S_n"
                self._begin_stop(now)
        elif self.phase is Phase.LOCOMOTE:
            if in_phase >= self.locomote_s:
                self._begin_stop(now)
        elif self.phase is Phase.STOP:
            assert self.stop_campaign is not None
            if self.stop_campaign.done:
                if not self.stop_campaign.success and self.failure is None:
                    self.failure = self.stop_campaign.outcome
                self._enter(Phase.DONE, now)
                self.exit_code = 0 if self.failure is None and self.all_ranks_match() else 1
        return self.exit_code

    def _begin_stop(self, now: float) -> None:
        self.stop_campaign = self.model.stop()
        self._enter(Phase.STOP, now)

    def _enter(self, phase: Phase, now: float) -> None:
        self.phase = phase
        self.phase_at = now

    def results(self) -> list[DemoResult]:
        """One line per particle, ranked by distance to the lamp when START went out."""
        before = self.start_snapshot or self.swarm.snapshot()
        after = {p.id: p for p in self.swarm.snapshot()}
        ranked = sorted(before, key=lambda p: p.ground_distance)
        rows = {row.id: row for row in self.model.rows()}
        results = []
        for rank, particle in enumerate(ranked, start=1):
            row = rows.get(particle.id)
            state = state_name(row.status.state) if row and row.status else "unheard"
            end = after.get(particle.id, particle)
            results.append(
                DemoResult(
                    particle_id=particle.id,
                    start_distance=particle.ground_distance,
                    end_distance=end.ground_distance,
                    rank=rank,
                    s_n=self.s_n.get(particle.id),
                    state=state,
                    intensity=row.status.intensity if row and row.status else None,
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
    if script.stop_campaign is not None:
        lines.append(script.stop_campaign.outcome)
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


def run(args: argparse.Namespace) -> int:
    ui = not args.no_ui and has_terminal()
    speed = args.speed if args.speed is not None else (2.0 if ui else 20.0)
    config = SwarmConfig(count=args.particles, seed=args.seed)
    try:
        swarm = VirtualSwarm(config)
    except (OSError, ImportError) as exc:
        return fail(
            f"the virtual particles need the native firmware library ({exc}); run: make native"
        )
    radio = VirtualRadio(swarm, url=f"virtual://{args.particles}?speed={speed:g}", speed=speed)
    log_dir = None if args.no_log else Path(args.log_dir)
    log_path: Path | None = None
    try:
        with station(radio, log_dir) as base:
            log_path = base.log_path
            script = DemoScript(base.model, swarm, locomote_s=args.run_s)
            if ui:
                app = ConsoleApp(
                    base.model,
                    radio_name=radio.url,
                    log_path=None if base.log_path is None else str(base.log_path),
                    on_tick=script.poll,
                )
                try:
                    code = app.run()
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
                    code = run_headless(base.model, script.poll)
                except KeyboardInterrupt:
                    return 130
            print(summary(script))
            print(f"simulated {swarm.t:.1f} s at {swarm.achieved_speed:.1f}x real time")
    except (RadioError, LogError) as exc:
        return fail(str(exc))
    # Drawn once the log is closed, so it holds the whole session; a failed plot is reported but
    # does not turn a good demo into a failed one.
    if not ui and log_path is not None:
        write_plot(log_path)
    return code
