"""The tracker against synthetic runs whose every disc is known: centroid accuracy at the paper's
camera geometry, straight and tilted, and what it must not mistake for the swarm."""

from __future__ import annotations

import math
from dataclasses import replace

import cv2
import numpy as np
import pytest

from particlebot.analysis.camera import Camera
from particlebot.analysis.geometry import from_field
from particlebot.analysis.render import Renderer, Scene, Stray
from particlebot.analysis.synthetic import BlobSpec, SwarmFrame, breathing_blob
from particlebot.analysis.tracker import (
    Circle,
    Detection,
    SwarmTracker,
    TrackerSettings,
    flag_spikes,
    track,
)
from particlebot.analysis.video import open_video
from tests.analysis.conftest import CLIP_SIZE, FOOT_CM, LAMP_CM, Clip


def errors(clip: Clip) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Per frame: distance to the region's true centroid, to the mean of the particle centres,
    and the quality."""
    with open_video(clip.path) as source:
        result = track(source, SwarmTracker(clip.geometry))
    assert len(result.detections) == len(clip.truth)
    to_region, to_centres = [], []
    for detection, truth in zip(result.detections, clip.truth, strict=True):
        to_region.append(
            math.hypot(detection.x_cm - truth.region_x_cm, detection.y_cm - truth.region_y_cm)
        )
        to_centres.append(
            math.hypot(detection.x_cm - truth.mean_x_cm, detection.y_cm - truth.mean_y_cm)
        )
    return np.array(to_region), np.array(to_centres), [d.quality for d in result.detections]


@pytest.mark.slow
@pytest.mark.parametrize("name", ["paper_clip", "tilted_clip"])
def test_the_centroid_is_within_1_cm_median_and_3_cm_worst_of_the_truth(
    name: str, request: pytest.FixtureRequest
) -> None:
    clip: Clip = request.getfixturevalue(name)
    to_region, to_centres, quality = errors(clip)
    print(
        f"{name}: region centroid error median {np.median(to_region):.2f} cm, worst "
        f"{to_region.max():.2f} cm; mean of centres median {np.median(to_centres):.2f} cm, "
        f"worst {to_centres.max():.2f} cm"
    )
    assert quality == ["ok"] * len(quality)
    assert np.median(to_region) <= 1.0
    assert to_region.max() <= 3.0
    # S6's caveat, measured: the region leans toward expanded particles and fills the gaps
    # between them, so it sits further from the mean of the centres than from its own truth.
    assert np.median(to_centres) > np.median(to_region)


@pytest.mark.parametrize("name", ["lamp_stand_clip", "rough_clip"])
def test_lab_footage_tracks_within_1_cm_median_and_3_cm_worst_over_every_written_frame(
    name: str, request: pytest.FixtureRequest
) -> None:
    clip: Clip = request.getfixturevalue(name)
    with open_video(clip.path) as source:
        result = track(source, SwarmTracker(clip.geometry))
    rows = [d.row() for d in result.detections]
    written = [
        math.hypot(row.x_cm - truth.region_x_cm, row.y_cm - truth.region_y_cm)
        for row, truth in zip(rows, clip.truth, strict=True)
        if math.isfinite(row.x_cm)
    ]
    print(
        f"{name}: {len(written)} of {len(rows)} frames written, error median "
        f"{np.median(written):.2f} cm, worst {max(written):.2f} cm; {result.counts()}"
    )
    assert len(written) >= 0.9 * len(rows)
    assert np.median(written) <= 1.0
    assert max(written) <= 3.0


def test_the_lamps_foot_and_arm_stay_out_of_a_swarm_beside_them(lamp_stand_clip: Clip) -> None:
    tracker = SwarmTracker(lamp_stand_clip.geometry)
    with open_video(lamp_stand_clip.path) as source:
        result = track(source, tracker)
    # The first frame's foot and arm (one region beside the head) became scenery, around the
    # foot's middle.
    (outline,) = tracker.scenery
    foot_px = lamp_stand_clip.geometry.to_image([FOOT_CM])[0]
    assert cv2.pointPolygonTest(outline, (float(foot_px[0]), float(foot_px[1])), False) > 0
    last, truth = result.detections[-1], lamp_stand_clip.truth[-1]
    # The line's near end is within a few cm of the foot's rim (9 cm radius) at the end.
    end = breathing_blob(
        BlobSpec(
            count=5,
            layout="line",
            start_cm=(150.0, 95.0),
            lamp_cm=LAMP_CM,
            speed_mm_s=12.0,
            duration_s=66.0,
            fps=1.0,
            seed=3,
        )
    )[-1]
    gap = np.hypot(end.x_cm - FOOT_CM[0], end.y_cm - FOOT_CM[1]) - end.r_cm - 9.0
    assert gap.min() < 8.0
    assert not last.dropped
    assert math.hypot(last.x_cm - truth.region_x_cm, last.y_cm - truth.region_y_cm) < 1.0
    # The foot never joins the outline: against the truth, the area reads as it did far away
    # (the closing bridges the line's gaps, so both read above the union of the discs).
    first = result.detections[0].area_cm2 / lamp_stand_clip.truth[0].region_area_cm2
    assert last.area_cm2 / truth.region_area_cm2 == pytest.approx(first, rel=0.1)


def test_a_frame_pushed_off_its_neighbours_is_dropped_and_written_without_a_centroid() -> None:
    detections = [Detection(float(k), k, 100.0 + 0.1 * k, 50.0, 300.0) for k in range(7)]
    detections[3].x_cm += 6.0  # one frame 6 cm off, under the 8 cm a jump needs
    flag_spikes(detections, spike_cm=TrackerSettings().spike_cm)
    assert [d.quality for d in detections] == ["ok"] * 3 + ["spike"] + ["ok"] * 3
    row = detections[3].row()
    assert row.quality == "spike" and math.isnan(row.x_cm) and math.isnan(row.y_cm)
    assert all(math.isfinite(d.row().x_cm) for d in detections if not d.dropped)


def test_the_lamp_is_found_where_it_stands_and_masked(paper_clip: Clip) -> None:
    with open_video(paper_clip.path) as source:
        tracker = SwarmTracker(paper_clip.geometry)
        tracker.detect(source.first, 0.0, 0)
    (lamp,) = tracker.lamps
    # Its head is 35 cm up, seen 18 % further out from the camera's nadir: corrected.
    assert math.dist(lamp.floor_cm, LAMP_CM) < 2.0
    assert lamp.radius_px * paper_clip.geometry.cm_per_px() > 7.0  # beyond the head's rim


def _one_frame(
    frame: SwarmFrame, scene: Scene, settings: TrackerSettings | None = None
) -> tuple[SwarmTracker, list[str], tuple[float, float]]:
    tracker = SwarmTracker(from_field(285.0, 160.0, scene.camera.image_size), settings)
    detection = tracker.detect(Renderer(scene).render(frame), frame.t_s, 0)
    return tracker, detection.flags, (detection.x_cm, detection.y_cm)


def test_glare_specks_and_an_empty_floor_are_not_a_swarm() -> None:
    camera = Camera.paper(CLIP_SIZE)
    strays = (
        Stray(
            60.0, 120.0, 20.0, 60.0, soft=True
        ),  # a soft-box's reflection, brighter than dim discs
        Stray(250.0, 30.0, 2.0, 230.0),
        Stray(140.0, 20.0, 1.0, 200.0),
    )
    scene = Scene(camera, lamp_cm=LAMP_CM, strays=strays, particle_level=45.0)
    blob = breathing_blob(BlobSpec(start_cm=(200.0, 100.0), lamp_cm=LAMP_CM, duration_s=0.0))[0]
    _, flags, (x, y) = _one_frame(blob, scene)
    _, rx, ry = blob.region()
    assert flags == []
    assert math.hypot(x - rx, y - ry) < 1.0
    nobody = SwarmFrame(0.0, np.zeros(0), np.zeros(0), np.zeros(0))
    _, flags, (x, _) = _one_frame(nobody, scene)
    assert flags == ["lost"]
    assert math.isnan(x)


def test_a_swarm_reaching_into_the_lamp_mask_is_flagged() -> None:
    scene = Scene(Camera.paper(CLIP_SIZE), lamp_cm=LAMP_CM)
    near = breathing_blob(BlobSpec(start_cm=(82.0, 62.0), lamp_cm=LAMP_CM, duration_s=0.0))[0]
    _, flags, _ = _one_frame(near, scene)
    assert "lamp" in flags


def test_a_given_lamp_circle_is_masked_instead_of_searched() -> None:
    scene = Scene(Camera.paper(CLIP_SIZE), lamp_cm=LAMP_CM)
    blob = breathing_blob(BlobSpec(duration_s=0.0))[0]
    settings = TrackerSettings(lamp=Circle(LAMP_CM[0], LAMP_CM[1], 15.0))
    tracker, flags, _ = _one_frame(blob, scene, settings)
    assert flags == []
    assert tracker.lamps[0].given and tracker.lamps[0].floor_cm == LAMP_CM


def test_parallax_of_a_tall_outline_is_undone_with_its_height() -> None:
    camera = Camera.paper(CLIP_SIZE)
    scene = Scene(camera, lamp_cm=LAMP_CM, particle_height_cm=12.0)
    # Far from the nadir, where parallax is largest: 225/213 x 110 cm from the centre.
    blob = breathing_blob(BlobSpec(start_cm=(250.0, 120.0), duration_s=0.0))[0]
    _, rx, ry = blob.region()
    floor = SwarmTracker(from_field(285.0, 160.0, CLIP_SIZE))
    raised = SwarmTracker(from_field(285.0, 160.0, CLIP_SIZE).at_height(12.0))
    image = Renderer(scene).render(blob)
    naive, corrected = floor.detect(image, 0.0, 0), raised.detect(image, 0.0, 0)
    assert math.hypot(naive.x_cm - rx, naive.y_cm - ry) > 4.0
    assert math.hypot(corrected.x_cm - rx, corrected.y_cm - ry) < 1.0


def test_a_centroid_that_leaps_is_flagged_and_the_swarm_is_followed_not_the_largest() -> None:
    scene = Scene(Camera.paper(CLIP_SIZE), lamp_cm=None)
    small = breathing_blob(BlobSpec(count=4, start_cm=(80.0, 80.0), duration_s=0.0))[0]
    big = breathing_blob(BlobSpec(count=12, start_cm=(220.0, 80.0), duration_s=0.0))[0]
    tracker = SwarmTracker(from_field(285.0, 160.0, CLIP_SIZE), TrackerSettings(lamp="none"))
    renderer = Renderer(scene)
    first = tracker.detect(renderer.render(small), 0.0, 0)
    assert first.flags == []
    both = SwarmFrame(
        1.0,
        *(np.concatenate([getattr(small, a), getattr(big, a)]) for a in ("x_cm", "y_cm", "r_cm")),
    )
    followed = tracker.detect(renderer.render(both), 1.0, 1)
    assert followed.flags == [] and abs(followed.x_cm - first.x_cm) < 1.0
    leapt = tracker.detect(renderer.render(replace(big, t_s=2.0)), 2.0, 2)
    assert "jump" in leapt.flags


def test_ctrl_c_keeps_what_was_tracked(paper_clip: Clip) -> None:
    seen: list[int] = []

    def stop_at_the_fifth(frame: object, detection: object, tracker: object) -> None:
        seen.append(1)
        if len(seen) == 5:
            raise KeyboardInterrupt

    with open_video(paper_clip.path) as source:
        result = track(source, SwarmTracker(paper_clip.geometry), on_frame=stop_at_the_fifth)
    assert result.interrupted
    assert len(result.detections) == 5 and result.frames_read == 5
