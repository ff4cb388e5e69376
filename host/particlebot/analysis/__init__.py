"""Experiment analysis: the swarm tracked on video, the paper's statistics, synthetic ground truth.

Modules, in the order an experiment flows through them:

- `geometry`: where an image pixel lies on the floor (field size, marked points, a checkerboard).
- `video`: opening and writing videos, with errors a person can act on.
- `tracker`: SI S6's pipeline made robust: the swarm's region and centroid in every frame.
- `trackfile`: the TRACK.csv the tracker writes and the statistics read.
- `sheet`: overlays and the contact sheet that show what the tracker saw.
- `simcsv`: the published simulator's CSV and config formats (ours writes them too).
- `sources`: centroid series from a track, a simulator's CSV or run folder (and later a log).
- `stats`: Table S2: sampling, the lamp on +y, one-tailed t-test, speeds; `statsplot` draws it.
- `camera`, `synthetic`, `render`: top-view videos of known swarms, the tracker's ground truth.
"""
