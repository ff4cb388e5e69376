"""Pictures of big swarms: drawn as dense as the swarm is, in the colours of their phases."""

from __future__ import annotations

import numpy as np
import pytest
from matplotlib.colors import to_rgba

from particlebot.sim.runs.pictures import DISC_LIMIT, RESTING, Frame, View, _raster, draw_swarm
from particlebot.sim.scenarios.placement import algorithm5
from particlebot.sim.world.arena import Arena

R = 0.0775


def resting_frame(count: int) -> Frame:
    xy = algorithm5(count, R, np.random.default_rng(1)).xy
    return Frame(
        t=0.0,
        x=xy[:, 0],
        y=xy[:, 1],
        radius=np.full(count, R),
        phase=np.full(count, np.nan),
        alive=np.ones(count, dtype=np.bool_),
        loose=np.zeros(count, dtype=np.bool_),
        objects=np.zeros((0, 5)),
    )


@pytest.mark.parametrize(
    ("width_in", "painted"),
    [
        (11.0, (0.5, 0.85)),  # discs of ~4 pixels: the gaps between particles show
        (3.0, (0.95, 1.0)),  # a pixel across: cells shaded by how much the particles cover
    ],
)
def test_a_swarm_too_big_for_discs_is_drawn_as_dense_as_it_is(
    width_in: float, painted: tuple[float, float]
) -> None:
    frame = resting_frame(DISC_LIMIT + 1)
    view = View.around(frame, (-100.0, 0.0), Arena(), "big")
    figure = draw_swarm(frame, view, (width_in, width_in))

    image = _raster(frame, view, frame.colours(), figure)

    # The swarm's bulk: half its reach around its centre, where Algorithm 5 covers ~60 %.
    height, width = image.shape[:2]
    x0, x1, y0, y1 = view.bounds
    cx, cy = frame.x.mean(), frame.y.mean()
    reach = 0.5 * np.hypot(frame.x - cx, frame.y - cy).max()
    gx = x0 + (np.arange(width) + 0.5) * (x1 - x0) / width
    gy = y0 + (np.arange(height) + 0.5) * (y1 - y0) / height
    alpha = image[..., 3][np.hypot(gx[None, :] - cx, gy[:, None] - cy) < reach]
    assert painted[0] < (alpha > 0).mean() <= painted[1]
    assert 0.45 < alpha.mean() < 0.85
    colours = image[..., :3][image[..., 3] > 0]
    np.testing.assert_allclose(colours, np.broadcast_to(to_rgba(RESTING)[:3], colours.shape))
