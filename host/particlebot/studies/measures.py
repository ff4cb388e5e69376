"""How a study turns one run's outcome into its numbers (speed, gap passage, carrying, annexing)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from particlebot.errors import ParticlebotError
from particlebot.studies.published import R_MAX_M, R_MIN_M
from particlebot.studies.spec import SimOutcome, WorldSetup

CONTACT_M = 2 * R_MAX_M + 0.005
"""Two particles whose centres are closer than this are taken as joined: both fully expanded and
within the magnets' 5 mm reach (the published attraction is negligible beyond a few mm)."""


class MeasureError(ParticlebotError, ValueError):
    """The outcome does not hold what the measure needs (a track too short, no object)."""


@dataclass(frozen=True)
class SpeedTowardLight:
    """Mean speed of the centroid toward the lamp, leaving out the first skip_s seconds (the
    paper leaves out 30 min while Algorithm 5's sparse placement settles): the drop in the
    centroid's distance to the lamp from skip_s to the end, over that time. Positive = toward
    the light, as in Tables S3 and S4."""

    skip_s: float

    def evaluate(self, setup: WorldSetup, outcome: SimOutcome) -> dict[str, float]:
        track = outcome.track
        end = float(track.time_s[-1])
        if end <= self.skip_s:
            raise MeasureError(
                f"the track ends at {end:g} s, not after the {self.skip_s:g} s left out"
            )
        start_distance = float(np.interp(self.skip_s, track.time_s, track.distance_m))
        speed = (start_distance - float(track.distance_m[-1])) / (end - self.skip_s)
        return {"speed_mm_s": speed * 1000.0}


@dataclass(frozen=True)
class GapPassage:
    """Fig. S18's success: the fraction of the robot's particles whose centres are past the far
    face of the obstacle (x > wall_far_x, on the lamp's side) when the run ends. 1 = the whole
    robot went through the gap, 0 = none of it."""

    wall_far_x: float

    def evaluate(self, setup: WorldSetup, outcome: SimOutcome) -> dict[str, float]:
        x = outcome.final_xy[: setup.particles, 0]
        return {"success": float(np.mean(x > self.wall_far_x))}


@dataclass(frozen=True)
class ObjectCarry:
    """Fig. S19: how far the passive object moved toward the lamp (m), how far the swarm's
    centroid did (from the initial centroid, the study frame's origin, to the particles' mean at
    the end: the published CSV's centroid counts the object as a body too), and whether the
    object is still touching the swarm at the end (1) or was left behind or pushed off (0)."""

    def evaluate(self, setup: WorldSetup, outcome: SimOutcome) -> dict[str, float]:
        if (
            setup.passive_object is None
            or outcome.object_start is None
            or outcome.object_end is None
        ):
            raise MeasureError("the carry measure needs a passive object's start and end")
        lamp = (setup.lamp_x, setup.lamp_y)
        before = math.dist(outcome.object_start, lamp)
        after = math.dist(outcome.object_end, lamp)
        reach = setup.passive_object.radius_factor * R_MIN_M + R_MAX_M + 0.005
        swarm = outcome.final_xy[: setup.particles]
        gaps = np.hypot(*(swarm - np.asarray(outcome.object_end)).T)
        centre = swarm.mean(axis=0)
        return {
            "object_advance_m": before - after,
            "swarm_advance_m": math.hypot(*lamp) - math.dist((centre[0], centre[1]), lamp),
            "object_carried": float(gaps.min() <= reach),
        }


@dataclass(frozen=True)
class RobotAdvance:
    """Fig. S21: the robot is the largest group of joined particles at the end (dead ones that
    detached and free ones not yet annexed are not part of it). Its centroid's mean speed toward
    the lamp from the initial centroid (the study frame's origin), the angle between its
    displacement and the lamp's bearing, and its size relative to the particles it began with."""

    centre: str = "founders"
    """Whose centroid moves: 'founders', the robot's particles at the end that it began with
    (free particles lie ahead of it, so annexing them would move an all-particle centroid
    forward by where they lay, not by how the robot moved), or 'all' of the robot's particles."""

    def evaluate(self, setup: WorldSetup, outcome: SimOutcome) -> dict[str, float]:
        xy = outcome.final_xy
        # scipy is imported where it works, so that `particlebot study --help` does not load it.
        from scipy.sparse import coo_matrix
        from scipy.sparse.csgraph import connected_components
        from scipy.spatial import cKDTree

        pairs = cKDTree(xy).query_pairs(CONTACT_M, output_type="ndarray")
        graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(len(xy),) * 2)
        _, labels = connected_components(graph, directed=False)
        robot = labels == np.bincount(labels).argmax()
        moving = robot.copy()
        if self.centre == "founders" and robot[: setup.particles].any():
            moving[setup.particles :] = False
        centre = xy[moving].mean(axis=0)
        lamp = np.array([setup.lamp_x, setup.lamp_y])
        advance = float(np.hypot(*lamp) - np.hypot(*(lamp - centre)))
        heading = math.degrees(math.atan2(centre[1], centre[0]) - math.atan2(lamp[1], lamp[0]))
        duration = float(outcome.track.time_s[-1] - outcome.track.time_s[0])
        return {
            "robot_speed_mm_s": advance / duration * 1000.0,
            "heading_error_deg": (heading + 180.0) % 360.0 - 180.0,
            "robot_size_ratio": float(robot.sum()) / setup.particles,
        }
