"""A run's whole trajectory in files other tools open: HOOMD-blue's GSD (OVITO reads it, freud and
MDAnalysis analyse it) and, if asked, extended XYZ (OVITO, ASE, VMD with its plugin).

A frame is written at every dump interval, beside the CSV's row. Its particles are every body:
the swarm's particles (type "particle", or "dead" once dead), then the passive objects ("object"),
then the round obstacles ("obstacle", still), each with its position, velocity and diameter in a
2-D box of the world's walls. What GSD has no field for goes in the frame's log, as HOOMD writes
its own logged quantities:

  log/particles/phase      each body's place in its cycle (0..1; NaN when not cycling)
  log/particles/alive      1 while alive (objects and obstacles: 1)
  log/particlebot/time_s, centroid, distance_to_light   the CSV row's figures
  log/particlebot/lamp     x, y and height above the photocells (m)
  log/particlebot/rectangles   the rectangular obstacles, x_min x_max y_min y_max (frame 0)

Units are SI (m, m/s), as everywhere in the simulator.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Protocol, TextIO

import numpy as np
import numpy.typing as npt

from particlebot.fileio import atomic_path, write_text
from particlebot.sim.world.world import World

if TYPE_CHECKING:
    import gsd.hoomd

TYPES = ["particle", "dead", "object", "obstacle"]
PARTICLE, DEAD, OBJECT, OBSTACLE = range(len(TYPES))
GSD_FILE = "trajectory.gsd"
XYZ_FILE = "trajectory.xyz"


class Bodies:
    """Every body of the world at one moment, in the order the trajectory files list them."""

    def __init__(self, world: World) -> None:
        state = world.state()
        objects = state.objects
        circles = world.arena.circle_array()
        n, m, c = len(state.x), len(objects), len(circles)
        self.step = world.steps
        self.t = state.t
        self.half_width = world.params.half_width
        self.xy = np.zeros((n + m + c, 2))
        self.xy[:n, 0], self.xy[:n, 1] = state.x, state.y
        self.xy[n : n + m] = objects[:, 0:2]
        self.xy[n + m :] = circles[:, 0:2]
        self.velocity = np.zeros((n + m + c, 2))
        self.velocity[:n, 0], self.velocity[:n, 1] = state.vx, state.vy
        self.velocity[n : n + m] = objects[:, 2:4]
        self.radius = np.concatenate([state.radius, objects[:, 4], circles[:, 2]])
        self.typeid = np.full(n + m + c, OBSTACLE, dtype=np.uint32)
        self.typeid[:n] = np.where(state.alive, PARTICLE, DEAD)
        self.typeid[n : n + m] = OBJECT
        self.alive = np.ones(n + m + c, dtype=np.uint8)
        self.alive[:n] = state.alive
        self.phase = np.full(n + m + c, np.nan)
        self.phase[:n] = world.phase()
        self.centroid = world.centroid()
        self.distance = world.light_distance()
        lamp = world.lamp
        self.lamp = (lamp.x, lamp.y, lamp.height)
        self.rectangles = world.arena.rect_array()


class TrajectoryLog(Protocol):
    """What Run needs of a trajectory file: a frame per dump, closed at the end."""

    path: Path

    def write(self, world: World) -> None: ...

    def close(self) -> None: ...


class GsdLog:
    """Appends a GSD frame per dump; opened fresh, or to continue a resumed run."""

    def __init__(self, path: Path, file: gsd.hoomd.HOOMDTrajectory) -> None:
        self.path = path
        self._file = file

    @classmethod
    def create(cls, path: Path) -> GsdLog:
        import gsd.hoomd

        return cls(path, gsd.hoomd.open(str(path), "x"))

    @classmethod
    def resume(cls, path: Path, up_to_step: int) -> GsdLog:
        """Continues the file from a snapshot at up_to_step: frames written after it (the run
        went on past its last snapshot before it stopped) are dropped, since the resumed run
        writes them again."""
        import gsd.hoomd

        if not path.is_file():
            return cls.create(path)
        with gsd.hoomd.open(str(path), "r") as old:
            steps = [int(frame.configuration.step) for frame in old]
            keep = sum(1 for step in steps if step <= up_to_step)
            if keep < len(steps):
                with (
                    atomic_path(path) as temporary,
                    gsd.hoomd.open(str(temporary), "w") as new,
                ):
                    for index in range(keep):
                        new.append(old[index])
        return cls(path, gsd.hoomd.open(str(path), "a"))

    def write(self, world: World) -> None:
        self._file.append(gsd_frame(Bodies(world), first=len(self._file) == 0))
        self._file.flush()

    def close(self) -> None:
        self._file.close()


def gsd_frame(bodies: Bodies, first: bool = False) -> gsd.hoomd.Frame:
    import gsd.hoomd

    frame = gsd.hoomd.Frame()
    count = len(bodies.radius)
    frame.configuration.step = bodies.step
    frame.configuration.dimensions = 2
    width = 2 * bodies.half_width
    frame.configuration.box = [width, width, 0, 0, 0, 0]
    frame.particles.N = count
    frame.particles.types = TYPES
    frame.particles.typeid = bodies.typeid
    frame.particles.position = _in_3d(bodies.xy)
    frame.particles.velocity = _in_3d(bodies.velocity)
    frame.particles.diameter = (2 * bodies.radius).astype(np.float32)
    frame.log = {
        "particles/phase": bodies.phase.astype(np.float32),
        "particles/alive": bodies.alive,
        "particlebot/time_s": np.array([bodies.t]),
        "particlebot/centroid": np.array(bodies.centroid),
        "particlebot/distance_to_light": np.array([bodies.distance]),
        "particlebot/lamp": np.array(bodies.lamp),
    }
    if first:
        frame.log["particlebot/rectangles"] = bodies.rectangles
    return frame


def _in_3d(xy: npt.NDArray[np.float64]) -> npt.NDArray[np.float32]:
    out = np.zeros((len(xy), 3), dtype=np.float32)
    out[:, :2] = xy
    return out


class XyzLog:
    """Appends an extended-XYZ frame per dump (text: one line per body)."""

    PROPERTIES = "species:S:1:pos:R:3:velo:R:3:radius:R:1:phase:R:1:alive:I:1"

    def __init__(self, path: Path, stream: TextIO) -> None:
        self.path = path
        self._stream = stream

    @classmethod
    def create(cls, path: Path) -> XyzLog:
        return cls(path, path.open("x", encoding="utf-8"))

    @classmethod
    def resume(cls, path: Path, up_to_step: int) -> XyzLog:
        """Continues the file, dropping frames after up_to_step (see GsdLog.resume)."""
        if not path.is_file():
            return cls.create(path)
        lines = path.read_text(encoding="utf-8").splitlines(keepends=True)
        kept: list[str] = []
        index = 0
        while index + 1 < len(lines):
            count = int(lines[index])
            header = lines[index + 1]
            step = int(header.split("Step=", 1)[1].split()[0])
            frame = lines[index : index + 2 + count]
            if step > up_to_step or len(frame) < 2 + count:
                break
            kept += frame
            index += 2 + count
        write_text(path, "".join(kept))
        return cls(path, path.open("a", encoding="utf-8"))

    def write(self, world: World) -> None:
        b = Bodies(world)
        width, half = 2 * b.half_width, b.half_width
        # The walls' square as the cell (a unit depth, so that the cell is not flat).
        lines = [
            f"{len(b.radius)}\n",
            f'Lattice="{width:g} 0 0 0 {width:g} 0 0 0 1" Origin="{-half:g} {-half:g} 0" '
            f'pbc="F F F" Properties={self.PROPERTIES} Time={b.t:.9g} Step={b.step}\n',
        ]
        for i in range(len(b.radius)):
            x, y = b.xy[i]
            vx, vy = b.velocity[i]
            lines.append(
                f"{TYPES[b.typeid[i]]} {x:.9g} {y:.9g} 0 {vx:.9g} {vy:.9g} 0 "
                f"{b.radius[i]:.9g} {b.phase[i]:.6g} {b.alive[i]}\n"
            )
        self._stream.write("".join(lines))
        self._stream.flush()

    def close(self) -> None:
        self._stream.close()
