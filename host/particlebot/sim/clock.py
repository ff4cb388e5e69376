"""The one clock of a simulated swarm: CPU cycles of the particles' 8 MHz ATmega32U4.

Every part of a simulation (the world, the particles, the air, the base station) counts time in
whole cycles from power-on, as simavr does, and nothing else. The unit is chosen for exactness:
- simavr steps the emulated particles in cycles, so they never round;
- the native firmware logic ticks in milliseconds (8,000 cycles) and the world steps every 10 ms
  (80,000 cycles): whole numbers too, so the three stay in step for ever;
- a character on a 9600-baud serial line takes 10 bits = 8,333 1/3 cycles, not a whole number.
  Serial lines are therefore timed in cycles x baud (an exact integer) and a byte is taken to
  have arrived at the first whole cycle at or after its stop bit ends, the same rounding as the
  simavr harness (sim/particles/emulated/particle_sim.c), so the air and the emulated UART agree
  to the cycle.
Seconds (floats) appear only at the edges: what a person reads, and the stamps on packets.
"""

from __future__ import annotations

CPU_HZ = 8_000_000
"""Cycles per second of the particles' CPU (the Fio v3's 8 MHz); simavr's clock too."""
CYCLES_PER_MS = CPU_HZ // 1000


def cycles(seconds: float) -> int:
    """Seconds as the nearest whole cycle."""
    return round(seconds * CPU_HZ)


def seconds(cycle: int) -> float:
    """A cycle count as seconds (for people and packet stamps)."""
    return cycle / CPU_HZ
