"""STOP pressed right after the base station restarts during a run at 50 % loss: how often it is
called confirmed while a particle still moves, over many seeds, with and without the grace period.

    python benchmarks/bench_stop_restart.py [--seeds 100] [--particles 6 10] [--loss 0.5]

For each seed a session starts a run on virtual particles and is closed (the console quit, the
laptop rebooted); a new session, which has heard nobody, sends STOP 0.5 s after it opens. Its
verdict is set against what the particles' logic really does. Prints one line per particle count
and grace period, for the console page ("Who must confirm a STOP"); tests/swarm/test_roster.py runs
50 seeds at 10 particles.
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections import Counter

from particlebot import Swarm
from particlebot.firmware.native import NativeParticle
from particlebot.protocol import State
from particlebot.radio.virtual import VirtualRadio
from particlebot.sim.swarm import SimSwarm, SwarmConfig
from particlebot.swarm.campaigns import Verdict
from particlebot.swarm.roster import STOPPED_STATES
from particlebot.swarm.tracker import STOP_GRACE_S


def still_moving(world: SimSwarm) -> int:
    """Particles whose logic is not stopped, whatever the radio said."""
    moving = 0
    for firmware in world.native.firmware:
        assert isinstance(firmware, NativeParticle)
        moving += State(firmware.status().state) not in STOPPED_STATES
    return moving


def restart_and_stop(
    seed: int, count: int, loss: float, grace: float
) -> tuple[Verdict, int, float]:
    """(the STOP's verdict, particles still moving, seconds to the verdict) for one seed."""
    world = SimSwarm(SwarmConfig(count=count, seed=seed, loss=loss, kinematics=False))
    with Swarm(VirtualRadio(world, url="virtual://"), log_dir=None) as first:
        first.wait_for(count=count, timeout=60)
        first.send_start("D", cycle_steps=75)
        first.sleep(4.0)
    with Swarm(VirtualRadio(world, url="virtual://"), log_dir=None, stop_grace=grace) as second:
        second.sleep(0.5)
        report = second.stop()
    return report.verdict, still_moving(world), report.seconds


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=100)
    parser.add_argument("--particles", type=int, nargs="+", default=[6, 10])
    parser.add_argument("--loss", type=float, default=0.5)
    args = parser.parse_args()
    for count in args.particles:
        for grace in (STOP_GRACE_S, 0.0):
            began = time.perf_counter()
            verdicts: Counter[Verdict] = Counter()
            false = 0
            seconds = []
            for seed in range(1, args.seeds + 1):
                verdict, moving, took = restart_and_stop(seed, count, args.loss, grace)
                verdicts[verdict] += 1
                false += verdict is Verdict.CONFIRMED and moving > 0
                seconds.append(took)
            print(
                f"{count} particles, {args.seeds} seeds, loss {args.loss:g}, grace {grace:g} s: "
                f"{verdicts[Verdict.CONFIRMED]} confirmed ({false} falsely), "
                f"{verdicts[Verdict.UNCONFIRMED]} unconfirmed, {verdicts[Verdict.FAILED]} failed; "
                "verdict after "
                f"{statistics.median(seconds):.1f} s median, {max(seconds):.1f} s at most "
                f"({time.perf_counter() - began:.0f} s wall)",
                flush=True,
            )


if __name__ == "__main__":
    main()
