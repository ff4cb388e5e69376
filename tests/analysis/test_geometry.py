"""Camera geometry: field size, marked points and a checkerboard against an exact camera model."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from particlebot.analysis.camera import Camera
from particlebot.analysis.geometry import (
    GeometryError,
    from_checkerboard,
    from_field,
    from_points,
    parse_field,
    parse_point,
    polygon_area_centroid,
)
from particlebot.analysis.render import render_checkerboard
from tests.analysis.conftest import CLIP_SIZE, FIELD_CORNERS_CM, marked_corners

TILTED = Camera.paper((1280, 720), pitch_deg=2.0, roll_deg=-1.5, yaw_deg=1.0)
FIELD_GRID = np.stack(np.meshgrid(np.linspace(0, 285, 12), np.linspace(0, 160, 8)), -1).reshape(
    -1, 2
)


def test_the_field_spans_the_picture_edge_to_edge() -> None:
    geometry = from_field(285.0, 160.0, (1920, 1080))
    # Pixel centres sit on integers, so the picture's outer edges are at -0.5 and size - 0.5.
    corners = geometry.to_floor([[-0.5, -0.5], [1919.5, 1079.5], [959.5, 539.5]])
    assert corners == pytest.approx(np.array([[0, 0], [285, 160], [142.5, 80]]))
    assert geometry.cm_per_px() == pytest.approx(285 / 1920, rel=0.01)
    # The same geometry at half size maps corresponding pixels to the same floor points.
    half = geometry.resized(960, 540)
    assert half.to_floor([[-0.5, -0.5], [959.5, 539.5]]) == pytest.approx(
        np.array([[0, 0], [285, 160]])
    )


def test_a_straight_down_camera_agrees_with_the_field_geometry() -> None:
    # Square pixels: 16:9 of 285 cm is 160.3 cm, which the paper rounds to 160.
    height_cm = 285.0 * CLIP_SIZE[1] / CLIP_SIZE[0]
    camera = replace(Camera.paper(CLIP_SIZE), nadir_cm=(142.5, height_cm / 2))
    exact = camera.floor_geometry()
    field = from_field(285.0, height_cm, CLIP_SIZE)
    pixels = camera.project(FIELD_GRID)
    assert field.to_floor(pixels) == pytest.approx(exact.to_floor(pixels), abs=1e-6)
    # Rounding to 160 stretches y by 0.2 %: 0.3 cm at the far edge.
    rounded = from_field(285.0, 160.0, CLIP_SIZE).to_floor(pixels)
    assert np.abs(rounded - exact.to_floor(pixels)).max() < 0.35


def test_four_marked_corners_recover_a_tilted_camera_to_a_millimetre() -> None:
    geometry = marked_corners(TILTED)
    found = geometry.to_floor(TILTED.project(FIELD_GRID))
    worst = float(np.hypot(*(found - FIELD_GRID).T).max())
    assert worst < 0.1  # clicks rounded to half a pixel
    assert geometry.residual_cm is not None and geometry.residual_cm < 1e-6  # 4 points fit exactly
    # Assuming the field's centre is below the camera: 2.5 degrees of tilt put it 9 cm off.
    assert geometry.nadir_cm is not None
    assert np.hypot(geometry.nadir_cm[0] - 142.5, geometry.nadir_cm[1] - 80) < 12


def test_a_checkerboard_on_the_floor_gives_the_homography() -> None:
    picture = render_checkerboard(TILTED, (9, 6), 10.0, (100.0, 40.0))
    geometry = from_checkerboard(picture, (9, 6), 10.0, (100.0, 40.0))
    found = geometry.to_floor(TILTED.project(FIELD_GRID))
    error = np.hypot(*(found - FIELD_GRID).T)
    # A 80 x 50 cm board extrapolated to a 285 x 160 cm field: the corners of the field are
    # furthest from the data.
    assert float(np.median(error)) < 0.3
    assert float(error.max()) < 1.5
    with pytest.raises(GeometryError, match="no checkerboard with 7x7"):
        from_checkerboard(picture, (7, 7), 10.0)


def test_points_that_cannot_make_a_homography_are_refused() -> None:
    size = (1280, 720)
    with pytest.raises(GeometryError, match="at least 4"):
        from_points([((0, 0), (0, 0))] * 3, size)
    on_a_line = [((100.0 * i, 50.0 * i), (10.0 * i, 5.0 * i)) for i in range(4)]
    with pytest.raises(GeometryError, match="one line"):
        from_points(on_a_line, size)
    pixels = TILTED.project(FIELD_CORNERS_CM)
    mirrored = [
        ((float(u), float(v)), (x, 160 - y))
        for (u, v), (x, y) in zip(pixels, FIELD_CORNERS_CM, strict=True)
    ]
    with pytest.raises(GeometryError, match="mirrored"):
        from_points(mirrored, size)


def test_options_parse_or_say_what_is_wrong() -> None:
    assert parse_field("285x160") == (285.0, 160.0)
    assert parse_point("10,20.5=0,0") == ((10.0, 20.5), (0.0, 0.0))
    for bad in ("285", "285x", "0x160", "axb"):
        with pytest.raises(GeometryError, match="--field"):
            parse_field(bad)
    with pytest.raises(GeometryError, match="U,V=X,Y"):
        parse_point("10,20")


def test_a_raised_plane_maps_back_to_the_floor_below_it() -> None:
    raised = TILTED.floor_geometry().at_height(12.0)
    pixels = TILTED.project(FIELD_GRID, height_cm=12.0)
    assert raised.to_floor(pixels) == pytest.approx(FIELD_GRID, abs=1e-6)
    with pytest.raises(GeometryError, match="between the floor and the camera"):
        TILTED.floor_geometry().at_height(300.0)


def test_polygon_area_and_centroid() -> None:
    l_shape = [(0, 0), (4, 0), (4, 1), (1, 1), (1, 3), (0, 3)]
    area, cx, cy = polygon_area_centroid(l_shape)
    # Two rectangles: 4x1 centred (2, 0.5) and 1x2 centred (0.5, 2).
    assert area == pytest.approx(6.0)
    assert (cx, cy) == pytest.approx(((4 * 2 + 2 * 0.5) / 6, (4 * 0.5 + 2 * 2) / 6))
    assert polygon_area_centroid(l_shape[::-1]) == pytest.approx((area, cx, cy))
