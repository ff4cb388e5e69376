"""The base station on simulated air shared with virtual particles: virtual://N?lamp=X,Y,H."""

from __future__ import annotations

import math
import queue
from typing import Self

from particlebot.radio import InvalidRadioUrlError, Packet, Radio, RadioError, RadioUrl
from particlebot.virtual.light import Lamp
from particlebot.virtual.swarm import SwarmConfig, VirtualSwarm

OPTIONS = {"lamp", "speed", "spacing", "start", "seed", "kinematics", "noise"}


def swarm_config_from_url(url: RadioUrl) -> SwarmConfig:
    """virtual://N?lamp=X,Y,H&spacing=M&start=M&seed=S&kinematics=0|1&noise=SIGMA (metres)."""
    url.check_options(OPTIONS | {"speed"})
    try:
        count = int(url.target or "10")
    except ValueError:
        raise InvalidRadioUrlError(
            f"{url.text}: the number of particles goes after virtual://, e.g. virtual://10"
        ) from None
    if not 1 <= count <= 200:
        raise InvalidRadioUrlError(f"{url.text}: 1..200 virtual particles, not {count}")
    lamp = Lamp()
    if "lamp" in url.options:
        try:
            parts = [float(p) for p in url.options["lamp"].split(",")]
        except ValueError:
            parts = []
        if len(parts) != 3 or parts[2] <= 0:
            raise InvalidRadioUrlError(
                f"{url.text}: lamp=X,Y,H in metres, H above the photocells, e.g. lamp=0,0,0.28"
            )
        lamp = Lamp(parts[0], parts[1], parts[2])
    return SwarmConfig(
        count=count,
        lamp=lamp,
        start=url.get_float("start", 0.10),
        spacing=url.get_float("spacing", 0.155),
        kinematics=url.get_int("kinematics", 1) != 0,
        seed=url.get_int("seed", 1),
        noise=url.get_float("noise", 0.0),
    )


def parse_speed(url: RadioUrl) -> float:
    text = url.options.get("speed", "1")
    speed = math.inf if text == "max" else url.get_float("speed", 1.0)
    if speed <= 0:
        raise InvalidRadioUrlError(f"{url.text}: speed must be positive, or max")
    return speed


class VirtualRadio(Radio):
    """The base station's node on a VirtualSwarm's air. Its clock is the swarm's simulated one,
    so ages and timeouts in the console follow simulated time when the swarm runs faster."""

    def __init__(
        self,
        swarm: VirtualSwarm,
        *,
        url: str = "virtual://",
        speed: float | None = None,
    ) -> None:
        super().__init__(url)
        self.swarm = swarm
        self._packets: queue.Queue[Packet] = queue.Queue()
        self._owns_thread = speed is not None
        swarm.connect_base(self._deliver)
        if speed is not None:
            swarm.start(speed)

    @classmethod
    def from_url(cls, url: RadioUrl) -> Self:
        config = swarm_config_from_url(url)
        speed = parse_speed(url)
        try:
            swarm = VirtualSwarm(config)
        except (OSError, ImportError) as exc:
            raise RadioError(
                f"The virtual particles need the firmware logic built for this PC ({exc}). "
                "Run: make native"
            ) from exc
        return cls(swarm, url=url.text, speed=speed)

    def _deliver(self, data: bytes, source: int, at: float) -> None:
        self._packets.put(
            Packet(data=data, source=self.swarm.node_name(source), time=self.swarm.epoch(at))
        )

    def now(self) -> float:
        return self.swarm.epoch()

    def send(self, data: bytes) -> None:
        self.swarm.send_from_base(data)

    def receive(self, timeout: float | None = None) -> Packet | None:
        try:
            return self._packets.get(timeout=timeout)
        except queue.Empty:
            return None

    def close(self) -> None:
        if self._owns_thread:
            self.swarm.stop()
        super().close()
