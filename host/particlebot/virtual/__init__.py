"""Virtual particles: the real firmware logic in a simulated light field, on simulated air."""

MAX_PARTICLES = 200
"""The most particles virtual:// and `particlebot demo` run (their ids are 1..MAX_PARTICLES)."""
