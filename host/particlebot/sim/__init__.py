"""Simulated swarms: one world, one air, three levels of particles.

- world/      the 2-D physical world every level shares: discs, friction, magnets, obstacles, the
              lamp and its light (sim.world.light), the photocells' differences;
- air/        the one 802.15.4 medium between the particles' radios and the base station's;
- particles/  what runs in each particle, at three levels of fidelity behind one world:
              model/ (vectorised controllers: up to 10^6 particles, radio idealised),
              native/ (the firmware logic, firmware/lib, through ctypes),
              emulated/ (the flashed image, particle.elf, in simavr);
- swarm/      one clock stepping world, particles and air; the base station's node; pacing;
- scenarios/  where things are (placements, lamp, obstacles): the one scenario type;
- runs/       run folders of `particlebot simulate`;
- clock.py    the one time unit (CPU cycles at 8 MHz) and why.
"""
