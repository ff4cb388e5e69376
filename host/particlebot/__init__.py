"""particlebot: firmware tooling, base-station console and virtual particles for particle robots."""
