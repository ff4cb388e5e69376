"""Where a World steps: the backends' names and the error for one that cannot be had.

Kept apart from the CUDA backend so that the commands can offer `--device` without importing the
simulator (`particlebot --help` stays light).
"""

from __future__ import annotations

from typing import Literal

from particlebot.errors import ParticlebotError

Device = Literal["cpu", "cuda", "auto"]
DEVICES: tuple[str, ...] = ("auto", "cpu", "cuda")
"""The choices of World(device=...), `simulate --device` and `study --device`."""


class DeviceError(ParticlebotError, ValueError):
    """The device asked for cannot be had (one line: why)."""
