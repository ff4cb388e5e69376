"""Calibrating particles: their photocells (SI S3, eqs. 7-14) and their servo table.

- `readings`: photocell readings at known distances (or lux) as a CSV, written as they are taken.
- `photocells`: each cell's gamma and gain fitted, the fleet's law rho' = scale * x.
- `positions`: Fig. S5, a line's positions estimated by eqs. 14-15 before and after calibration.
- `servo`: the nine-point table from measured radii, and a write order the firmware accepts.
- `placements`, `prompts`: where particles go for each reading; who puts them there (a person
  asked, or the tool on a simulated swarm).
- `bench`, `servo_bench`: both calibrations done with particles through the Swarm API.
- `session`: the bench's swarm (opened on a radio), its particles, who places them, readings.
- `reports`: what the calibrations say when done, as text (and the servo points as a CSV).
- `figures`: what they look like.
"""
