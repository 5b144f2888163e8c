"""Ray caster against analytic geometry (to 1e-9 m)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from radioslam.scene import cast_rays, scene_from_mapping


def _room(half=4.0, inner=None):
    walls = [{"points": [[-half, -half], [half, -half], [half, half], [-half, half], [-half, -half]],
              "material": "concrete"}]
    if inner:
        walls.append(inner)
    return scene_from_mapping({"version": 1, "name": "room", "walls": walls,
                               "trajectory": {"poses": [[0, 0, 0]]}})


def test_square_room_along_each_array_normal():
    scene = _room(4.0)
    angles = np.arange(4) * np.pi / 2
    hits = cast_rays(np.zeros(2), angles, scene.segments, scene.material_array("transmission"), 3, 100)
    assert np.allclose(hits.distance[:, 0], 4.0, atol=1e-9, rtol=0)
    assert np.allclose(hits.cos_incidence[:, 0], 1.0)
    assert np.all(hits.segment[:, 1] == -1)  # concrete is opaque


@given(st.floats(-3.5, 3.5), st.floats(-3.5, 3.5), st.floats(-np.pi, np.pi))
@settings(max_examples=200, deadline=None)
def test_distance_to_square_room_is_analytic(x, y, angle):
    scene = _room(4.0)
    d = np.array([np.cos(angle), np.sin(angle)])
    hits = cast_rays(np.array([x, y]), np.array([angle]), scene.segments,
                     scene.material_array("transmission"), 1, 100)
    with np.errstate(divide="ignore", over="ignore"):
        tx = np.where(d[0] > 0, (4 - x) / d[0], np.where(d[0] < 0, (-4 - x) / d[0], np.inf))
        ty = np.where(d[1] > 0, (4 - y) / d[1], np.where(d[1] < 0, (-4 - y) / d[1], np.inf))
    expected = min(tx, ty)
    assert hits.distance[0, 0] == pytest.approx(expected, abs=1e-9)
    normal_axis = 0 if tx < ty else 1
    assert hits.cos_incidence[0, 0] == pytest.approx(abs(d[normal_axis]), abs=1e-9)


def test_glass_transmits_to_the_wall_behind():
    glass = {"points": [[2.0, -1.0], [2.0, 1.0]], "material": "glass"}
    scene = _room(4.0, glass)
    hits = cast_rays(np.zeros(2), np.array([0.0, np.pi]), scene.segments,
                     scene.material_array("transmission"), 3, 100)
    assert hits.distance[0, :2] == pytest.approx([2.0, 4.0], abs=1e-9)
    t = 0.70  # glass field transmission
    assert hits.transmission[0, :2] == pytest.approx([1.0, t**2])
    assert hits.segment[0, 2] == -1  # stopped at the concrete
    assert hits.distance[1, 0] == pytest.approx(4.0) and hits.segment[1, 1] == -1


def test_max_range_drops_far_hits():
    scene = _room(4.0)
    hits = cast_rays(np.zeros(2), np.array([0.0]), scene.segments, scene.material_array("transmission"), 3, 3.0)
    assert not hits.valid.any()
