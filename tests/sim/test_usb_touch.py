"""The default image hands a 1200-baud USB touch to the bootloader: its watchdog is let bite."""

from __future__ import annotations

import pytest

from particlebot.sim import ParticleSim

pytestmark = pytest.mark.usefixtures("built_images")

# The core's USB code sets the watchdog to WDTO_120MS. A real chip resets 120 ms after the last
# watchdog reset; simavr 1.6 applies a new period only at the next one, which never comes, so
# here the particle's own 250 ms period runs out. Either way it resets, where a loop that kept
# feeding the watchdog would never let it.
LATEST_RESET_S = 0.3


def test_a_usb_touch_resets_the_particle_by_its_watchdog() -> None:
    with ParticleSim() as sim:
        sim.run_for(300_000)  # booted and looping, feeding its own 250 ms watchdog
        assert sim.resets == []
        touched_s = sim.time_s
        sim.usb_touch()
        reset = sim.run_until_reset(timeout_us=1_000_000)
        assert reset is not None, "the loop kept feeding the watchdog: no bootloader"
        assert reset.by_watchdog
        assert reset.time_s - touched_s <= LATEST_RESET_S


def test_without_a_touch_the_watchdog_never_bites() -> None:
    with ParticleSim() as sim:
        assert sim.run_until_reset(timeout_us=1_500_000) is None
