"""Loop closure: candidate submaps near the current pose (not the most recent ones), a
wide-window branch-and-bound match of the current scan (Hess et al. 2016 §V), and three
acceptance tests: the normalized score (mean point likelihood, in [0, 1], independent of
the number of points), geometric consistency with the graph (the match must agree with
the pose the odometry predicts, within their joint covariance: a χ²(3) gate), and the
information of the points that agree with the submap, which must fix every direction
(:mod:`radioslam.slam.degeneracy`): one wall in common lets the match slide along it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from radioslam.slam.branch_bound import BranchAndBound
from radioslam.slam.config import SlamConfig
from radioslam.slam.correlative import correlative_match
from radioslam.slam.degeneracy import matched_weak_direction
from radioslam.slam.refine import refine_pose
from radioslam.slam.se2 import wrap_angle

BRANCH_LEVELS = 4


@dataclass(frozen=True)
class LoopClosure:
    anchor: int  # the submap's first scan
    key: int  # the current scan
    relative: np.ndarray  # the current pose in the anchor's frame
    covariance: np.ndarray
    score: float


def mahalanobis2(measured: np.ndarray, predicted: np.ndarray, covariance: np.ndarray) -> float:
    d = measured - predicted
    d[2] = wrap_angle(d[2])
    return float(d @ np.linalg.solve(covariance, d))


def match_loop(matcher: BranchAndBound, points: np.ndarray, normals: np.ndarray, predicted: np.ndarray,
               drift_covariance: np.ndarray, cfg: SlamConfig, anchor: int, key: int) -> LoopClosure | None:
    """A verified loop closure of the scan against a submap's matcher (anchor frame), or None."""
    step = np.radians(cfg.angle_step_deg)
    grid = matcher.grid
    found = matcher.match(points, normals, predicted, cfg.loop_window_m,
                          np.radians(cfg.loop_window_deg), step, cfg.loop_min_score)
    if found.pose is None:
        return None
    # the response surface around the winner gives the covariance (Olson 2009 §IV)
    local = correlative_match(grid, points, normals, found.pose, cfg.window_m, np.radians(cfg.window_deg), step)
    if local.score < cfg.loop_min_score:
        return None
    pose = refine_pose(grid, points, normals, local.pose, grid.resolution, step)
    if mahalanobis2(pose, predicted, drift_covariance + local.covariance) > cfg.loop_gate_chi2:
        return None
    # the points that agree with the submap must fix every direction (Zhang et al. 2016), or the
    # match could slide along them
    if matched_weak_direction(grid, pose, points, normals, local.covariance, cfg.degenerate_ratio) is not None:
        return None
    return LoopClosure(anchor, key, pose, local.covariance, local.score)
