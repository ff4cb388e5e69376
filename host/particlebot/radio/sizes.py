"""How many particles the simulated radios run, apart from them, so that option checks (demo's
--particles) need not import the simulator."""

VIRTUAL_MAX_PARTICLES = 200
"""The most particles virtual:// and `particlebot demo` run (their ids are 1..200)."""
EMULATED_MAX_PARTICLES = 32
"""One harness process each; the firmware records at most 32 senders per round anyway."""
