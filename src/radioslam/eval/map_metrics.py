"""Map quality against the scene's true walls (DESIGN.md §6 ★):

* ``map_error_m``: mean distance from the (aligned) map points to the nearest true wall;
* ``map_coverage``: the fraction of true wall length within 0.3 m of a map point.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from radioslam.scene.geometry import point_segment_distance

COVERAGE_RADIUS_M = 0.3
WALL_SAMPLE_M = 0.02


def map_error(points: np.ndarray, segments: np.ndarray) -> float:
    if len(points) == 0:
        return float("nan")
    return float(point_segment_distance(points, segments).min(axis=1).mean())


def wall_samples(segments: np.ndarray, spacing: float = WALL_SAMPLE_M) -> tuple[np.ndarray, np.ndarray]:
    """Points along every wall segment (N, 2) and the wall length each stands for (N,)."""
    length = np.linalg.norm(segments[:, 1] - segments[:, 0], axis=1)
    count = np.maximum(1, np.ceil(length / spacing).astype(int))
    seg = np.repeat(np.arange(len(segments)), count)
    frac = (np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count) + 0.5) / count[seg]
    pts = segments[seg, 0] + frac[:, None] * (segments[seg, 1] - segments[seg, 0])
    return pts, (length / count)[seg]


def map_coverage(points: np.ndarray, segments: np.ndarray, radius: float = COVERAGE_RADIUS_M) -> float:
    if len(points) == 0:
        return 0.0
    samples, weight = wall_samples(segments)
    near = cKDTree(points).query(samples, distance_upper_bound=radius)[0] <= radius
    return float(weight[near].sum() / weight.sum())
