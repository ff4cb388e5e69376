"""Benchmarks of the firmware-in-the-loop emulation: speed, servo timing, method-D round length.

    python benchmarks/bench_sim.py [--quick] [--json FILE]

Needs `make firmware harness`. Prints, for the README:
1. emulated seconds per wall second for 1 and 5 particles (idle, and 5 while running a wave);
2. the servo's frame timing while particles sample their photocells and the radio is busy: pulse
   period and width jitter, and how many frames of a cycle show the step before theirs
   (repeated), the step after (skipped), or no commanded width exactly (an edge delayed by
   another interrupt);
3. how long a method-D estimation round takes for 5, 10 and 20 particles at 9600 baud: from
   START until the last INTENSITY broadcast of the round has reached every particle, against
   the airtime lower bound, and whether every S_n came out right.
"""

from __future__ import annotations

import argparse
import json
import os
import random
import statistics
import time
from collections.abc import Sequence
from pathlib import Path

from particlebot.firmware.native import NativeParticle, estimate
from particlebot.protocol import (
    BROADCAST_ID,
    PARAM_SPECS,
    Intensity,
    Method,
    Param,
    Ping,
    Start,
    encode_frame,
)
from particlebot.sim.air.medium import BASE, NOISE
from particlebot.sim.clock import CPU_HZ
from particlebot.sim.particles.emulated.harness import ServoPulse
from particlebot.sim.particles.emulated.servo import (
    contracted_width,
    cycle_profile_us,
    cycle_starts,
    missed_frames,
    period_errors_us,
    servo_step_s,
)
from particlebot.sim.swarm import Level, SimSwarm, SwarmConfig
from particlebot.sim.swarm.base import BaseStation, packet_frames

CYCLE_STEPS = 75
STEP_S = servo_step_s()  # one servo step, as the firmware defines it
CYCLE_T_S = CYCLE_STEPS * STEP_S
INTENSITY_FRAME_BYTES = 8 + Intensity.PAYLOAD_SIZE  # 14: the frame overhead and 6 payload bytes
REPEATS = PARAM_SPECS[Param.BROADCAST_REPEATS].default


def start_message(
    run_id: int,
    method: Method = Method.COUNTING,
    cycle_steps: int = CYCLE_STEPS,
    wave_size: int = 0,
) -> Start:
    return Start(
        run_id=run_id,
        method=int(method),
        cycle_steps=cycle_steps,
        wave_size=wave_size,
        update_interval_s=0,
        phototaxis=0,
    )


# ---- 1. speed --------------------------------------------------------------------------------


def emulation_speed(count: int, seconds: float, running: bool) -> float:
    """Emulated seconds per wall second for `count` particles over `seconds` of emulated time
    (after boot), idle (periodic STATUS only) or running a method-D wave."""
    params = {Param.ROUND_MS: 1000}
    with SimSwarm(SwarmConfig(level=Level.EMULATED, count=count, params=params)) as swarm:
        base = BaseStation(swarm)
        swarm.run_for(0.5)
        if running:
            base.send(start_message(1))
            swarm.run_for(1.2)
        began_wall, began = time.perf_counter(), swarm.time_s
        swarm.run_for(seconds)
        return (swarm.time_s - began) / (time.perf_counter() - began_wall)


# ---- 2. servo timing under load ---------------------------------------------------------------


def commanded_cycle_us(steps: int) -> list[int]:
    """The pulse (us) the firmware logic commands at each step 0..steps of a cycle with the
    default settings, from the logic itself (the native library): what a frame must show exactly
    unless an interrupt delayed one of its edges."""
    with NativeParticle() as particle:
        particle.set_adc([600] * 6)
        particle.tick(100)
        particle.receive(encode_frame(start_message(1, cycle_steps=steps, wave_size=1), 0, 0))
        # Alone, S_n = 1 and t_I = 0: the cycle starts ROUND_MS after START.
        begin = 100 + PARAM_SPECS[Param.ROUND_MS].default
        pulses = []
        for k in range(steps + 1):
            particle.tick(begin + k * round(STEP_S * 1000))
            pulses.append(particle.servo_pulse_us)
        return pulses


EXACT_US = 0.3
"""A frame shows a commanded pulse exactly, within the harness's resolution (1/8 us) and the
interrupts' equal entry latency."""


def step_errors(
    pulses: Sequence[ServoPulse], contracted: float, commanded: list[int]
) -> tuple[int, int, int, int]:
    """For the frames of every cycle wholly in pulses: how many show their own step, the step
    before (a repeat: the new width came after the frame began), the step after (a skip), or none
    of them exactly (an interrupt delayed an edge by some microseconds). Step 0 of each cycle is
    placed where the most frames match exactly, near where eq. 4's rising flank puts it."""
    on_time = late = early = jittered = 0
    index = {round(p.start_s * 1e6): i for i, p in enumerate(pulses)}
    offset = contracted - commanded[0]  # the resting pulse as measured, less as commanded

    def shows(frame: int, step: int) -> bool:
        if not 0 <= step <= CYCLE_STEPS:
            return False
        return abs(pulses[frame].width_us - offset - commanded[step]) <= EXACT_US

    for start in cycle_starts(pulses, CYCLE_STEPS, contracted):
        guess = index[round(start * 1e6)]
        candidates = [j for j in range(guess - 3, guess + 4) if 0 <= j <= len(pulses) - CYCLE_STEPS]
        if not candidates:
            continue  # not wholly recorded
        j = max(candidates, key=lambda c: sum(shows(c + k, k) for k in range(CYCLE_STEPS)))
        for k in range(1, CYCLE_STEPS):
            if shows(j + k, k):
                on_time += 1
            elif shows(j + k, k - 1):
                late += 1
            elif shows(j + k, k + 1):
                early += 1
            else:
                jittered += 1
    return on_time, late, early, jittered


def servo_timing(seconds: float) -> dict[str, float]:
    """Five particles run a wave while the base station PINGs them all every 0.5 s (each PING
    brings five 54-byte STATUS frames onto the air) and noise takes ~25 % of the channel's
    serial capacity; every particle keeps sampling its photocells throughout."""
    rng = random.Random(5)
    with SimSwarm(
        SwarmConfig(level=Level.EMULATED, count=5, params={Param.ROUND_MS: 1000})
    ) as swarm:
        base = BaseStation(swarm)
        swarm.run_for(0.5)
        resting = [contracted_width(sim.servo_pulses[-20:]) for sim in swarm.emulated.sims]
        base.send(start_message(1))
        swarm.run_for(1.1)
        measure_from = swarm.time_s
        next_ping = swarm.time_s
        while swarm.time_s < measure_from + seconds:
            if swarm.time_s >= next_ping:
                base.send(Ping(target=BROADCAST_ID))
                next_ping += 0.5
            swarm.inject(rng.randbytes(rng.randint(5, 20)))
            swarm.run_for(0.05)
        periods: list[float] = []
        rest_widths: list[float] = []
        missed = on_time = late = early = jittered = 0
        commanded = commanded_cycle_us(CYCLE_STEPS)
        # The logic's arithmetic is eq. 4 through the calibration table (to the microsecond).
        profile = cycle_profile_us(CYCLE_STEPS)
        assert all(abs(c - p) <= 1 for c, p in zip(commanded, profile, strict=True))
        for sim, contracted in zip(swarm.emulated.sims, resting, strict=True):
            pulses = [p for p in sim.servo_pulses if p.start_s >= measure_from]
            periods += [abs(e) for e in period_errors_us(pulses)]
            missed += missed_frames(pulses)
            # Whole cycles, also one under way when the measurement began.
            since_start = [p for p in sim.servo_pulses if p.start_s >= measure_from - 1.6]
            cycles = cycle_starts(since_start, CYCLE_STEPS, contracted)
            rest_widths += [
                abs(p.width_us - contracted)
                for p in pulses
                if not any(c - STEP_S / 2 <= p.start_s <= c + CYCLE_T_S for c in cycles)
            ]
            counts = step_errors(since_start, contracted, commanded)
            on_time, late, early = on_time + counts[0], late + counts[1], early + counts[2]
            jittered += counts[3]
        periods.sort()
        rest_widths.sort()
        return {
            "frames": len(periods) + 5,
            "period_error_p50_us": statistics.median(periods),
            "period_error_p99_us": periods[int(0.99 * (len(periods) - 1))],
            "period_error_max_us": periods[-1],
            "rest_width_error_p99_us": rest_widths[int(0.99 * (len(rest_widths) - 1))],
            "rest_width_error_max_us": rest_widths[-1],
            "missed_frames": missed,
            "cycle_frames_checked": on_time + late + early + jittered,
            "cycle_frames_repeated_step": late,
            "cycle_frames_skipped_step": early,
            "cycle_frames_edge_delayed": jittered,
        }


# ---- 3. method-D round ------------------------------------------------------------------------


def round_duration(count: int, round_ms: int) -> dict[str, float | int | bool]:
    """One method-D round of `count` particles in a line (0.155 m apart, the nearest 0.10 m
    from the lamp's foot): START from the base station to the last INTENSITY of the round
    delivered to every particle."""
    with SimSwarm(
        SwarmConfig(level=Level.EMULATED, count=count, params={Param.ROUND_MS: round_ms})
    ) as swarm:
        base = BaseStation(swarm)
        swarm.run_for(0.5)
        wall = time.perf_counter()
        started = base.send(start_message(1))
        swarm.run_until(started + round_ms / 1000 + 0.3)
        wall = time.perf_counter() - wall
        statuses = base.ping_all(timeout_s=3.0)
        last_delivery = 0
        copies = dropped = 0
        heard: dict[int, dict[int, int]] = {i: {} for i in range(count)}
        for copy in swarm.air.receptions:
            if copy.packet.source in (BASE, NOISE) or copy.receiver == BASE:
                continue
            frames = [f for f in packet_frames(copy.packet) if isinstance(f.message, Intensity)]
            if not frames:
                continue
            copies += len(frames)
            if not copy.delivered:
                dropped += len(frames)
                continue
            last_delivery = max(last_delivery, copy.last)
            for frame in frames:
                assert isinstance(frame.message, Intensity)
                heard[copy.receiver][frame.sender] = frame.message.intensity
        own = {
            heard_frame.frame.sender: message.intensity
            for heard_frame, message in base.frames(Intensity)
            if isinstance(message, Intensity)
        }
        s_n = [statuses[i].s_n if i in statuses else 0 for i in swarm.ids]
        consistent = all(
            s_n[i] == estimate(Method.COUNTING, own[swarm.ids[i]], list(heard[i].values()))
            for i in range(count)
            if swarm.ids[i] in own
        )
        bound = (count - 1) * REPEATS * INTENSITY_FRAME_BYTES * 10 / 9600
        return {
            "particles": count,
            "round_ms": round_ms,
            "duration_s": last_delivery / CPU_HZ - started,
            "airtime_lower_bound_s": bound,
            "all_heard_everyone": all(len(h) == count - 1 for h in heard.values()),
            "s_n_equal_rank": s_n == list(range(1, count + 1)),
            "s_n_match_native_estimate": consistent,
            "intensity_copies": copies,
            "intensity_copies_dropped": dropped,
            "wall_s": wall,
        }


def describe(result: dict[str, float | int | bool]) -> str:
    return (
        f"K={result['particles']:2d} ROUND_MS={result['round_ms']:4d}: "
        f"{result['duration_s']:.3f} s (airtime bound {result['airtime_lower_bound_s']:.3f} s); "
        f"everyone heard everyone: {result['all_heard_everyone']}; S_n = rank: "
        f"{result['s_n_equal_rank']}; S_n = native estimate of what it heard: "
        f"{result['s_n_match_native_estimate']}; INTENSITY frames dropped by full radio "
        f"buffers: {result['intensity_copies_dropped']} of {result['intensity_copies']} "
        "copies; "
        f"wall {result['wall_s']:.1f} s"
    )


ROUND_CANDIDATES_MS = (300, 500, 750, 1000, 1500, 2000, 3000, 4000)


def shortest_round(count: int) -> dict[str, float | int | bool] | None:
    """The shortest ROUND_MS (of ROUND_CANDIDATES_MS) whose round gives every particle every
    other's reading and its rank as S_n."""
    for round_ms in ROUND_CANDIDATES_MS:
        result = round_duration(count, round_ms)
        if result["all_heard_everyone"] and result["s_n_equal_rank"]:
            return result
    return None


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="shorter runs (a smoke check)")
    parser.add_argument("--json", type=Path, help="also write the figures here")
    args = parser.parse_args(argv)
    seconds = 3.0 if args.quick else 10.0
    results: dict[str, object] = {"cpus": os.cpu_count(), "load_before": os.getloadavg()[0]}

    print("1. emulation speed (emulated s per wall s)")
    speed = {
        "1 idle": emulation_speed(1, seconds, running=False),
        "5 idle": emulation_speed(5, seconds, running=False),
        "5 running a wave": emulation_speed(5, seconds, running=True),
    }
    for name, value in speed.items():
        print(f"   {name:18s} {value:6.2f}")
    results["speed"] = speed

    print("2. servo frames of 5 cycling particles, photocells sampled, radio busy")
    timing = servo_timing(seconds)
    for name, value in timing.items():
        print(
            f"   {name:28s} {value:8.2f}" if isinstance(value, float) else f"   {name:28s} {value}"
        )
    results["servo"] = timing

    print("3. method-D round at 9600 baud (START to last INTENSITY delivered everywhere)")
    rounds = []
    for count in (5, 10, 20):
        result = round_duration(count, 3000)
        rounds.append(result)
        print("   " + describe(result))
        if not args.quick:
            shortest = shortest_round(count)
            if shortest is not None:
                shortest["shortest_working"] = True
                rounds.append(shortest)
                print("   shortest that works: " + describe(shortest))
            else:
                print(f"   K={count}: no ROUND_MS up to {ROUND_CANDIDATES_MS[-1]} works")
    results["rounds"] = rounds
    results["load_after"] = os.getloadavg()[0]
    if args.json:
        args.json.write_text(json.dumps(results, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
