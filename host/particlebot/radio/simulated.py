"""What the radios of simulated swarms (virtual://, emulated://) share: the URL's options (the
scenario, the lamp, the air's faults, the photocells), and the base station's node on the swarm's
air, handing packets over through a queue."""

from __future__ import annotations

import queue
from dataclasses import replace
from pathlib import Path
from typing import Any, Self

from particlebot.options import NON_NEGATIVE, POSITIVE, SWITCH, Bounds, OptionError, parse_float
from particlebot.radio.base import (
    InvalidRadioUrlError,
    LinkState,
    Packet,
    Radio,
    RadioError,
    RadioUrl,
)
from particlebot.radio.faults import FAULT_OPTIONS, SIMULATION_OPTIONS, faults_from_url
from particlebot.sim.scenarios import presets
from particlebot.sim.scenarios.scenario import LampSpec, PlacementKind, Scenario, ScenarioError
from particlebot.sim.swarm.config import Level, SwarmConfig
from particlebot.sim.swarm.swarm import SimSwarm, TruthListener
from particlebot.sim.world.photocells import MAX_SPREAD

PHOTOCELL_SPREAD = Bounds(minimum=0, maximum=MAX_SPREAD)
SHAPE_OPTIONS = frozenset({"lamp", "start", "spacing"})
"""Options that shape a line or a blob; a scenario file places everything itself."""
OPTIONS = frozenset(
    {
        *SHAPE_OPTIONS,
        "speed",
        "kinematics",
        "noise",
        "photocell_spread",
        *FAULT_OPTIONS,
        *SIMULATION_OPTIONS,
    }
)
"""What both simulated radios take; emulated:// adds the image's own (elf, base_baud, buffer)."""


def parse_count(url: RadioUrl, default: int, maximum: int) -> int:
    """How many particles: the part after scheme://."""
    try:
        count = int(url.target or str(default))
    except ValueError:
        raise InvalidRadioUrlError(
            f"{url.text}: the number of particles goes after {url.scheme}://, "
            f"e.g. {url.scheme}://{default}"
        ) from None
    if not 1 <= count <= maximum:
        raise InvalidRadioUrlError(f"{url.text}: 1..{maximum} particles, not {count}")
    return count


def parse_lamp(url: RadioUrl) -> LampSpec:
    """lamp=X,Y,H in metres (H above the photocells), or the default lamp."""
    if "lamp" not in url.options:
        return LampSpec()
    parts = url.options["lamp"].split(",")
    try:
        if len(parts) != 3:
            raise OptionError("three numbers")
        x, y = (parse_float(part) for part in parts[:2])
        height = parse_float(parts[2], POSITIVE)
    except OptionError:
        raise InvalidRadioUrlError(
            f"{url.text}: lamp=X,Y,H in metres, H above the photocells, e.g. lamp=0,0,0.28"
        ) from None
    return LampSpec(x, y, height)


def parse_scenario(url: RadioUrl, default_count: int, maximum: int) -> Scenario:
    """scenario=line (the default: a line away from the lamp, shaped by start=, spacing= and
    lamp=), blob (an SI Algorithm-5 blob start= metres from the lamp, 1.5 by default) or the
    path of a scenario file (TOML, or the published .cfg), which places everything itself: the
    number after scheme:// then overrides its particles."""
    name = url.options.get("scenario", "line").strip()
    seed = url.get_int("seed", 1, NON_NEGATIVE)
    if name.lower() in presets.NAMES:
        count = parse_count(url, default_count, maximum)
        lamp = parse_lamp(url)
        if name.lower() == "blob":
            if "spacing" in url.options:
                raise InvalidRadioUrlError(
                    f"{url.text}: spacing= shapes a line; a blob's particles touch"
                )
            start = url.get_float("start", presets.BLOB_START_M, NON_NEGATIVE)
            return presets.blob(count, start=start, lamp=lamp, seed=seed)
        return presets.line(
            count,
            start=url.get_float("start", presets.LINE_START_M, NON_NEGATIVE),
            spacing=url.get_float("spacing", presets.CONTRACTED_SPACING_M, POSITIVE),
            lamp=lamp,
            seed=seed,
        )
    shaped = sorted(SHAPE_OPTIONS & set(url.options))
    if shaped:
        raise InvalidRadioUrlError(
            f"{url.text}: {', '.join(shaped)} shape a line or a blob; the scenario file {name} "
            "places the particles and the lamp itself"
        )
    try:
        scenario = presets.read_file(Path(name))
    except ScenarioError as exc:
        raise InvalidRadioUrlError(f"{url.text}: scenario {exc}") from None
    if url.target:
        count = parse_count(url, default_count, maximum)
        if scenario.swarm.placement is PlacementKind.FILE:
            raise InvalidRadioUrlError(
                f"{url.text}: the scenario file lists its particles' places: leave out the "
                f"number ({url.scheme}://?scenario={name})"
            )
        scenario = presets.with_particles(scenario, count)
    elif not 1 <= scenario.swarm.particles <= maximum:
        raise InvalidRadioUrlError(
            f"{url.text}: {url.scheme}:// runs 1..{maximum} particles, the scenario has "
            f"{scenario.swarm.particles}"
        )
    if "seed" in url.options:
        scenario = replace(scenario, seed=seed)
    return scenario


def swarm_config_from_url(
    url: RadioUrl,
    level: Level,
    *,
    default_count: int,
    maximum: int,
    extra: frozenset[str] = frozenset(),
    **options: Any,
) -> SwarmConfig:
    """The swarm a simulated radio's URL describes (InvalidRadioUrlError says what is wrong):
    scenario=line|blob|PATH with start=, spacing=, lamp=, seed=; the air's loss= and delay_ms=;
    photocell_spread=, noise=, kinematics=0|1. options: the level's own settings."""
    url.check_options(set(OPTIONS | extra))
    scenario = parse_scenario(url, default_count, maximum)
    faults = faults_from_url(url)
    return SwarmConfig(
        scenario=scenario,
        level=level,
        seed=url.get_int("seed", 1, NON_NEGATIVE),
        loss=faults.loss,
        delay_us=faults.delay_s * 1_000_000,
        photocell_spread=url.get_float("photocell_spread", 0.0, PHOTOCELL_SPREAD),
        noise=url.get_float("noise", 0.0, NON_NEGATIVE),
        kinematics=url.get_int("kinematics", 1, SWITCH) != 0,
        keep_history=False,
        **options,
    )


class SwarmRadio(Radio):
    """The base station's radio on a simulated swarm's air. The simulation's thread hands packets
    over through a queue; the clock is the simulation's, so the console's ages and timeouts
    follow simulated time when it runs faster or slower than real time."""

    restart_advice = "open it again"
    """What to do once the simulation has failed (a backend names what to rebuild)."""
    faults_on_link = False  # the simulation models loss and delay on its air

    def __init__(
        self,
        swarm: SimSwarm,
        *,
        url: str,
        speed: float | None = None,
        owns_swarm: bool = False,
    ) -> None:
        """speed: step the swarm on its own thread at this pace (else the caller steps it).
        owns_swarm: close() ends the swarm too (its particles' processes, for emulated ones)."""
        super().__init__(url)
        self.swarm = swarm
        self.speed = speed
        self._owns_swarm = owns_swarm
        self._packets: queue.Queue[Packet] = queue.Queue()
        self._owns_thread = speed is not None
        swarm.add_base_listener(self._deliver)
        if speed is not None:
            self.swarm.start(speed)

    @classmethod
    def open_swarm(cls, config: SwarmConfig, url: RadioUrl) -> Self:
        """The radio on a new swarm of config, paced as the URL says (or stepped by the caller)."""
        speed = url.get_speed()  # checked either way
        try:
            swarm = SimSwarm(config)
        except ScenarioError as exc:
            raise InvalidRadioUrlError(f"{url.text}: scenario {exc}") from None
        except (OSError, ImportError, RuntimeError) as exc:
            raise RadioError(cls.missing_advice(exc)) from exc
        return cls(swarm, url=url.text, speed=None if url.caller_steps else speed, owns_swarm=True)

    @staticmethod
    def missing_advice(exc: BaseException) -> str:
        return f"The simulated swarm cannot start ({exc})"

    @property
    def stepped_by_caller(self) -> bool:
        """Whether the caller advances the simulation (advance) rather than a thread."""
        return not self._owns_thread

    def step_by_caller(self) -> None:
        """Stops the stepping thread: from now on the caller advances the simulation, as
        fast as it can and in step with its own work (particlebot.Swarm does at speed=max)."""
        if self._owns_thread:
            self.swarm.stop()
            self._owns_thread = False

    def advance(self, seconds: float) -> None:
        """Runs the simulation for seconds of its time (only when stepped_by_caller)."""
        if self._owns_thread:
            raise RuntimeError("the simulation steps on its own thread")
        self._check()
        self.swarm.run_for(seconds)

    def add_truth_listener(self, listener: TruthListener) -> None:
        """listener(record, epoch_s): the world's truth, stamped on this radio's clock."""
        swarm = self.swarm
        self.swarm.add_truth_listener(lambda record, t: listener(record, swarm.epoch(t)))

    def _deliver(self, source: int, data: bytes, at: float) -> None:
        self._packets.put(
            Packet(data=data, source=self.swarm.node_name(source), time=self.swarm.epoch(at))
        )

    def _check(self) -> None:
        """Raises RadioError once the simulation's thread has failed: without it nothing more will
        ever be heard, and a radio that just stays quiet would look like a silent swarm."""
        error = self.swarm.error
        if error is not None:
            self._set_link(LinkState.LOST, f"the simulation stopped: {error}")
            raise RadioError(f"The simulated swarm stopped ({error}); {self.restart_advice}")

    def now(self) -> float:
        return self.swarm.epoch()

    def send(self, data: bytes) -> None:
        self._check()
        self.swarm.send_from_base(data)

    def receive(self, timeout: float | None = None) -> Packet | None:
        self._check()
        try:
            return self._packets.get(timeout=timeout)
        except queue.Empty:
            self._check()
            return None

    def close(self) -> None:
        if self._owns_swarm:
            self.swarm.close()  # its thread first, then the particles
        elif self._owns_thread:
            self.swarm.stop()
        super().close()
