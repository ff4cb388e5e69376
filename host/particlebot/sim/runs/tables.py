"""A run folder as pandas DataFrames for a notebook: `particlebot.read_run(folder)`.

The centroid track comes from the run's CSV (every dump interval). The per-body frames come from
trajectory.gsd when the run wrote one (`simulate --gsd`: every dump interval), else from the
snapshots (every snapshot interval and at the end).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from particlebot.sim.runs.run import SNAPSHOTS, STATE_FILE, RunError
from particlebot.sim.runs.trajectory import DEAD, GSD_FILE, OBJECT, PARTICLE, TYPES
from particlebot.sim.scenarios.toml_file import read_scenario

if TYPE_CHECKING:
    import pandas as pd

TRACK_COLUMNS = {
    "Time": "t_s",
    "Centroid X": "centroid_x_m",
    "Centroid Y": "centroid_y_m",
    "Distance": "distance_m",
}
"""The published CSV's columns -> the track's."""
FRAME_COLUMNS = (
    "frame", "step", "t_s", "body", "kind", "x_m", "y_m", "vx_m_s", "vy_m_s", "radius_m",
    "phase", "alive",
)  # fmt: skip


@dataclass(frozen=True)
class RunTables:
    """What a run folder holds, as tables."""

    folder: Path
    track: pd.DataFrame
    """One row per CSV row: t_s, centroid_x_m, centroid_y_m, distance_m (to the lamp's foot)."""
    frames: pd.DataFrame
    """One row per body per frame: frame, step, t_s, body (its index), kind ("particle",
    "dead", "object", "obstacle"), x_m, y_m, vx_m_s, vy_m_s, radius_m, phase (0..1, NaN when
    not cycling), alive."""
    source: str
    """Where the frames come from: "trajectory.gsd" or "snapshots"."""


def read_run(folder: str | Path) -> RunTables:
    """The run folder's centroid track and per-body frames; RunError when it is not one."""
    import pandas as pd

    folder = Path(folder)
    if not (folder / STATE_FILE).is_file():
        raise RunError(f"{folder} is not a run folder (no {STATE_FILE})")
    scenario = read_scenario(folder / "scenario.toml")
    csv = folder / scenario.output.csv_name
    try:
        table = pd.read_csv(csv, skiprows=1, skipinitialspace=True, index_col=False)
    except (OSError, ValueError) as exc:
        raise RunError(f"{csv}: cannot be read ({exc})") from None
    track = table[list(TRACK_COLUMNS)].rename(columns=TRACK_COLUMNS)
    if (folder / GSD_FILE).is_file():
        frames, source = _frames_from_gsd(folder / GSD_FILE), GSD_FILE
    else:
        frames, source = _frames_from_snapshots(folder / SNAPSHOTS), SNAPSHOTS
    return RunTables(folder, track, pd.DataFrame(frames, columns=list(FRAME_COLUMNS)), source)


def _frames_from_gsd(path: Path) -> dict[str, object]:
    import gsd.hoomd

    columns: dict[str, list[np.ndarray]] = {name: [] for name in FRAME_COLUMNS}
    with gsd.hoomd.open(str(path), "r") as trajectory:
        for index, frame in enumerate(trajectory):
            count = int(frame.particles.N)
            position = frame.particles.position
            velocity = frame.particles.velocity
            _append(
                columns,
                frame=np.full(count, index),
                step=np.full(count, int(frame.configuration.step)),
                t_s=np.full(count, float(frame.log["particlebot/time_s"][0])),
                body=np.arange(count),
                kind=np.asarray(frame.particles.types)[frame.particles.typeid],
                x_m=position[:, 0].astype(np.float64),
                y_m=position[:, 1].astype(np.float64),
                vx_m_s=velocity[:, 0].astype(np.float64),
                vy_m_s=velocity[:, 1].astype(np.float64),
                radius_m=frame.particles.diameter.astype(np.float64) / 2,
                phase=frame.log["particles/phase"].astype(np.float64),
                alive=frame.log["particles/alive"].astype(bool),
            )
    return _joined(columns)


def _frames_from_snapshots(folder: Path) -> dict[str, object]:
    columns: dict[str, list[np.ndarray]] = {name: [] for name in FRAME_COLUMNS}
    for index, path in enumerate(sorted(folder.glob("step-*.npz"))):
        with np.load(path, allow_pickle=False) as snap:
            alive = snap["state_alive"].astype(bool)
            objects = snap["state_objects"].reshape(-1, 5)
            n, m = len(alive), len(objects)
            kinds = np.where(alive, TYPES[PARTICLE], TYPES[DEAD])
            _append(
                columns,
                frame=np.full(n + m, index),
                step=np.full(n + m, int(path.stem.removeprefix("step-"))),
                t_s=np.full(n + m, float(snap["state_t"])),
                body=np.arange(n + m),
                kind=np.concatenate([kinds, np.full(m, TYPES[OBJECT])]),
                x_m=np.concatenate([snap["state_x"], objects[:, 0]]),
                y_m=np.concatenate([snap["state_y"], objects[:, 1]]),
                vx_m_s=np.concatenate([snap["state_vx"], objects[:, 2]]),
                vy_m_s=np.concatenate([snap["state_vy"], objects[:, 3]]),
                radius_m=np.concatenate([snap["state_radius"], objects[:, 4]]),
                phase=np.concatenate([snap["state_phase"], np.full(m, np.nan)]),
                alive=np.concatenate([alive, np.ones(m, dtype=bool)]),
            )
    return _joined(columns)


def _append(columns: dict[str, list[np.ndarray]], **values: np.ndarray) -> None:
    for name, value in values.items():
        columns[name].append(np.asarray(value))


def _joined(columns: dict[str, list[np.ndarray]]) -> dict[str, object]:
    return {
        name: np.concatenate(parts) if parts else np.array([]) for name, parts in columns.items()
    }
