"""Closed-loop phototaxis measured as the paper measured it (SI S6, Table S2): a simulated swarm
STARTed with phototaxis on finds the lamp by itself; its centroid every 30 s, the frame turned so
the lamp lies on +y, a one-tailed t-test on the steps toward it, speeds in % of the contracted
diameter per cycle. The numbers come from the session log (the world's truth it records), through
the same analysis `particlebot stats` runs on a tracked video."""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from particlebot.analysis.sources import load_source
from particlebot.analysis.stats import StatsResult, StatsSettings, analyse
from particlebot.protocol import Param, State
from particlebot.radio.simulated import SwarmRadio
from particlebot.swarm.api import Swarm, method_letter, method_of

PROGRESS_S = 60.0
"""A long run reports its progress every minute of simulated time."""


@dataclass(frozen=True)
class PhototaxisTrial:
    """One START: the method, the cycle (T = cycle_steps x 20 ms), how long, what is set first."""

    method: str = "D"
    cycle_steps: int = 150
    duration_s: float = 1800.0
    phototaxis: bool = True
    params: Mapping[Param, int] = field(default_factory=dict)
    """Set (and confirmed) on every particle before START."""

    @property
    def label(self) -> str:
        settings = ", ".join(f"{p.name} {v}" for p, v in self.params.items())
        letter = method_letter(method_of(self.method))
        return letter + (f" ({settings})" if settings else "")


@dataclass(frozen=True)
class PhototaxisResult:
    trial: PhototaxisTrial
    url: str
    log: Path
    stats: StatsResult
    particles: int
    done: int
    """Particles that stopped by themselves (Algorithm 3: their light no longer increased)."""
    toward_lamp_m: float
    """How much nearer the lamp the centroid came from START to STOP."""


def run_phototaxis(
    url: str,
    trial: PhototaxisTrial,
    log_dir: Path,
    *,
    log_name: str | None = None,
    progress: Callable[[float], None] | None = None,
) -> PhototaxisResult:
    """Opens a simulated radio (url, stepped as fast as it runs), waits for every particle,
    sets trial.params, STARTs, lets the swarm run trial.duration_s of simulated time, STOPs, and
    analyses the session log. progress(simulated seconds since START) every PROGRESS_S.
    RadioError, SwarmError and SourceError say what went wrong in one line."""
    with Swarm.open(url, log_dir=log_dir, log_name=log_name, stepped=True) as swarm:
        radio = swarm.radio
        if not isinstance(radio, SwarmRadio):
            raise ValueError(f"{url}: closed-loop phototaxis needs a simulated radio")
        count = radio.swarm.count
        swarm.wait_for(count=count, timeout=30)
        for param, value in trial.params.items():
            swarm.set(param, value)
        swarm.start(trial.method, cycle_steps=trial.cycle_steps, phototaxis=trial.phototaxis)
        elapsed = 0.0
        while elapsed < trial.duration_s:
            step = min(PROGRESS_S, trial.duration_s - elapsed)
            swarm.sleep(step)
            elapsed += step
            if progress is not None:
                progress(elapsed)
        done = sum(p.state == State.DONE for p in swarm.particles())
        swarm.stop()
        log = swarm.log_path
    assert log is not None
    (series,) = load_source(log)
    stats = analyse(series, StatsSettings())
    return PhototaxisResult(
        trial=trial,
        url=url,
        log=log,
        stats=stats,
        particles=count,
        done=done,
        toward_lamp_m=_toward_lamp_m(stats),
    )


def _toward_lamp_m(stats: StatsResult) -> float:
    """The centroid's last sample along +y (toward the lamp) from the first, in metres."""
    y = stats.sample_y_cm[np.isfinite(stats.sample_y_cm)]
    return float(y[-1] - y[0]) / 100 if len(y) > 1 else math.nan
