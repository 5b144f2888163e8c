"""The posterior of a scan's placement (issue #47): one number that relocalization, the lost-and-found trials
and the honest ending compare as log odds,

    log p(T_k | scan k, the map before k, step) = log p(scan k | T_k, map)        (the measurement model)
                                                + log p(T_{k−1} → T_k | motion)   (the motion prior)
                                                + const,

- the scan's term from :mod:`radioslam.slam.measurement` against the scans before it whose poses lie within
  the scan's own reach of T_k (its farthest echo; at most ``max_scans``, nearest first), with the
  space they observed, so a pose in space the map never saw scores neutral, not zero;
- the step's term from :mod:`radioslam.slam.motion_prior`: the platform's step (the odometry's at its noise
  when given), or, beyond a step's reach, the kidnap's share ε_J of steps spread uniformly over the area
  searched. A relocalization (a pose found anywhere within that area, :meth:`LoopCloser.relocalize`) is such a
  step: its prior is ε_J / (area · 2π), which it must overcome by what the scan explains better there. Against
  odometry's step a jump costs about 23–30 nats (the odometry's stated σ, the area searched), more than one
  scan's evidence usually brings: a kidnap is confirmed by the scans after it (:mod:`radioslam.slam.lost_found`).

Two placements of one scan (or two trajectories) compare by the difference of these: a likelihood ratio times
a prior ratio, the posterior odds.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from radioslam.slam.config import GridConfig
from radioslam.slam.measurement import scan_log_likelihoods
from radioslam.slam.motion import MotionModel
from radioslam.slam.scan_points import ScanPoints, map_grid
from radioslam.slam.se2 import between

KEEP = object()  # step_term's default: the motion model's own last step


class Posterior:
    """Built from the likelihood grid's settings, the most scans a scan's map holds and the walk's motion model."""

    def __init__(self, grid: GridConfig, max_scans: int, motion: MotionModel):
        self.grid, self.max_scans, self.motion = grid, max_scans, motion

    @classmethod
    def from_config(cls, cfg, motion: MotionModel) -> "Posterior":
        return cls(cfg.grid, cfg.posterior.max_scans, motion)

    def nearby(self, pose: np.ndarray, earlier: list[int], poses, reach: float) -> list[int]:
        """The scans of ``earlier`` whose ``poses`` (indexable by key) lie within ``reach`` of ``pose`` (the scan's
        own: its farthest echo), at most ``max_scans`` of them, nearest first; returned in key order. A surface the
        scan sees may have been seen from any viewpoint that far: a map cut shorter holds fewer of the scan's
        surfaces where the walk explores than where it revisits, and a place folded onto a well-walked part of
        the map would gain for that alone."""
        if not earlier:
            return []
        keys = np.asarray(earlier)
        distance = np.linalg.norm(np.array([poses[m][:2] for m in earlier]) - pose[:2], axis=1)
        order = np.argsort(distance, kind="stable")[: self.max_scans]
        return sorted(keys[order[distance[order] <= reach]].tolist())

    def scan_term(self, points: ScanPoints, pose: np.ndarray, earlier: list[int], poses,
                  scans: dict[int, ScanPoints], near: list[int] | None = None) -> float:
        """log p(scan | ``pose``, the scans of ``earlier`` near it at ``poses``) (0 where none is near: no map,
        no evidence); ``near``: those scans, where already known (:meth:`nearby`)."""
        near = self.nearby(pose, earlier, poses, points.reach) if near is None else near
        if not near:
            return 0.0
        grid, _ = map_grid(near, {m: poses[m] for m in near}, scans, self.grid, observed=True)
        return float(scan_log_likelihoods(grid, points.xy, points.normals, points.observation_weights, pose,
                                          points.sightings, self.grid.free_stop_m)[0])

    def step_term(self, k: int, last: np.ndarray, pose: np.ndarray, area_m2: float | None = None,
                  velocity=KEEP) -> float:
        """log p(step k from ``last`` to ``pose``): the motion prior given the odometry's step k and ``velocity``
        (the branch's own last step; by default the walk's), its unexpected share uniform over ``area_m2``
        (a relocalization's search) or else over the front end's window."""
        motion = self.motion if velocity is KEEP else replace(self.motion, velocity=velocity, speeds=[])
        return float(motion.log_prob(k, last, pose, area_m2)[0])

    def placement(self, k: int, points: ScanPoints, pose: np.ndarray, last: np.ndarray, earlier: list[int], poses,
                  scans: dict[int, ScanPoints], area_m2: float | None = None, velocity=KEEP) -> float:
        """log p(T_k = ``pose`` | scan k, the map of ``earlier`` at ``poses``, a step from ``last``) + const: the
        scan's term and the step's."""
        return self.scan_term(points, pose, earlier, poses, scans) + \
            self.step_term(k, last, pose, area_m2, velocity)

    def log_odds(self, k: int, points: ScanPoints, place: np.ndarray, rivals: np.ndarray, last: np.ndarray,
                 earlier: list[int], poses, scans: dict[int, ScanPoints], area_m2: float | None = None) -> float:
        """log p(T_k = ``place``) − max_r log p(T_k = rival r) for scan k under one map (``earlier`` at ``poses``)
        and one step's prior from ``last``: the posterior odds of a far placement (a relocalization, a trial's
        first scan) against the no-jump hypothesis' placements ``rivals`` (R, 3), the jump's unexpected share
        spread over ``area_m2``."""
        return self.placement(k, points, place, last, earlier, poses, scans, area_m2) - \
            max(self.placement(k, points, rival, last, earlier, poses, scans, area_m2) for rival in rivals)

    def trajectory_prior(self, poses: np.ndarray) -> float:
        """Σ_k log p(step k) of a whole trajectory (:meth:`step_terms`)."""
        return sum(self.step_terms(poses), 0.0)

    def step_terms(self, poses: np.ndarray) -> list[float]:
        """log p(step k) for k = 1 … P − 1 of a trajectory, each step's hypotheses those of its own last step
        (and the odometry's step k); a jump (a relocalization's) anywhere within the trajectory's extent."""
        area = extent_m2(poses)
        velocity = [None] + list(between(poses[:-2], poses[1:-1]))
        return [self.step_term(k, poses[k - 1], poses[k], area, velocity[k - 1]) for k in range(1, len(poses))]


def extent_m2(poses: np.ndarray) -> float:
    """The area of the poses' bounding box (where a jump may land)."""
    return float(np.prod(np.ptp(np.asarray(poses)[:, :2], axis=0)))
