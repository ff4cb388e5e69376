"""Table S3 through the paper's camera, end to end: simulate the dead study's runs, film them as
the published simulator drew them, track them every 30 s and read the speed with one pixel scale.

    PYTHONPATH=host python research/paper_camera.py --cells 10:0,100:0 --seeds 1-11 \
        --results data/studies/camera

Resumable: rows already in RESULTS/camera-runs.csv are not run again.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from particlebot.studies.camera import film_dead_runs


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cells", required=True, help="N:DEAD_FRACTION,... e.g. 10:0,100:0.2")
    parser.add_argument("--seeds", default="1-11", help="FIRST-LAST (1-11)")
    parser.add_argument("--duration-s", type=float, default=7200.0, help="simulated (7200)")
    parser.add_argument("--skip-s", type=float, default=1800.0, help="left out (1800)")
    parser.add_argument("--results", default="data/studies/camera", help="output folder")
    parser.add_argument("--runs", help="the runs' folders (default RESULTS/runs; large)")
    args = parser.parse_args()
    try:
        cells = [(int(n), float(f)) for n, f in (c.split(":") for c in args.cells.split(","))]
        first, last = (int(v) for v in args.seeds.split("-"))
    except ValueError:
        print(f"paper_camera: --cells {args.cells!r} / --seeds {args.seeds!r}", file=sys.stderr)
        return 2
    runs = Path(args.runs) if args.runs else None
    film_dead_runs(
        cells, range(first, last + 1), args.duration_s, args.skip_s, Path(args.results), runs
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
