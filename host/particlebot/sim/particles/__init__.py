"""Particles of the simulated world at three levels of fidelity.

- model/     vectorised controllers (the published light wave; what our firmware does): the
             World's Controller itself, every particle at once, the radio idealised;
- native/    the firmware logic (firmware/lib) built for the PC, one object per particle;
- emulated/  the flashed image (particle.elf) in simavr, one process per particle.

The two firmware levels share one interface, FirmwareParticles (interface.py): photocell
readings and bytes from the radio in, the servo's radius and bytes to the radio out, stepped on
the swarm's clock (particlebot.sim.swarm). Whatever the level, the world moves the bodies.
"""
