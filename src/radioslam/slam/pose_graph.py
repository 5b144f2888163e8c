"""Pose graph over SE(2) with GTSAM (Dellaert & Kaess, "Factor Graphs for Robot Perception",
2017): Pose2 between factors from the scan matcher's covariances, and the batch solve:
Levenberg–Marquardt, with loop factors made robust to false closures by graduated non-convexity
(Yang, Antonante, Tzoumas, Carlone, "Graduated Non-Convexity for Robust Spatial Perception", RA-L
2020): ``GncLMOptimizer`` with the prior, the odometry and the relocalizations as known inliers,
truncated least squares rejecting a loop whose χ² exceeds χ²(3) at ``INLIER_PROBABILITY``. The back
end runs it only when the incremental smoother (:mod:`radioslam.slam.incremental`) doubts a loop.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import gtsam
import numpy as np
from scipy.special import chdtri

from radioslam.slam.se2 import rotation

INLIER_PROBABILITY = 0.99  # GNC's default: an inlier's χ² lies below its threshold with this probability
# the χ²₃ quantile, 11.34 (scipy.special's, not scipy.stats': that import costs 0.3-0.5 s a command):
# a loop beyond it at the solution is rejected
LOOP_INLIER_CHI2 = float(chdtri(3, 1.0 - INLIER_PROBABILITY))


def _pose2(p: np.ndarray) -> gtsam.Pose2:
    return gtsam.Pose2(float(p[0]), float(p[1]), float(p[2]))


def _noise(covariance: np.ndarray) -> gtsam.noiseModel.Gaussian:
    return gtsam.noiseModel.Gaussian.Covariance(np.asarray(covariance, dtype=np.float64))


def local_covariance(world_covariance: np.ndarray, theta: float) -> np.ndarray:
    """A covariance of (x, y, θ) in the world frame, expressed in the frame of a pose at θ."""
    rot = np.eye(3)
    rot[:2, :2] = rotation(theta).T
    return rot @ world_covariance @ rot.T


@dataclass
class PoseGraph:
    graph: gtsam.NonlinearFactorGraph = field(default_factory=gtsam.NonlinearFactorGraph)
    initial: gtsam.Values = field(default_factory=gtsam.Values)
    inliers: list[int] = field(default_factory=list)  # factor indices GNC must keep
    loops: list[tuple[int, int, int]] = field(default_factory=list)  # (i, j, factor index) of each loop
    doubtable: set[int] = field(default_factory=set)  # the loops the robust solve may reject (not relocalizations)
    prior_sigmas: np.ndarray = field(default_factory=lambda: np.array([1e-4, 1e-4, 1e-5]))  # the first pose

    def add_pose(self, key: int, pose: np.ndarray) -> None:
        if not self.initial.exists(key):
            self.initial.insert(key, _pose2(pose))
        if self.graph.size() == 0:
            self.inliers.append(self.graph.size())
            prior = gtsam.noiseModel.Diagonal.Sigmas(self.prior_sigmas)
            self.graph.add(gtsam.PriorFactorPose2(key, _pose2(pose), prior))

    def _between(self, i: int, j: int, relative: np.ndarray, covariance: np.ndarray) -> None:
        self.graph.add(gtsam.BetweenFactorPose2(i, j, _pose2(relative), _noise(covariance)))

    def add_odometry(self, i: int, j: int, relative: np.ndarray, covariance: np.ndarray) -> int:
        """A between factor GNC must keep; its index."""
        self.inliers.append(self.graph.size())
        self._between(i, j, relative, covariance)
        return self.graph.size() - 1

    def loosen(self, index: int, covariance: np.ndarray) -> None:
        """The between factor at ``index`` keeps its measurement with a new covariance."""
        factor = self.graph.at(index)
        self.graph.replace(index, gtsam.BetweenFactorPose2(factor.keys()[0], factor.keys()[1], factor.measured(),
                                                           _noise(covariance)))

    def add_loop(self, i: int, j: int, relative: np.ndarray, covariance: np.ndarray,
                 known_inlier: bool = False) -> None:
        """A loop factor; GNC may reject it unless ``known_inlier`` (a relocalization, the only tie
        of a lost pose to the map)."""
        if known_inlier:
            self.inliers.append(self.graph.size())
        else:
            self.doubtable.add(self.graph.size())
        self.loops.append((i, j, self.graph.size()))
        self._between(i, j, relative, covariance)

    def remeasure(self, index: int, relative: np.ndarray) -> None:
        """The between factor at ``index`` keeps its covariance with a new measurement."""
        factor = self.graph.at(index)
        self.graph.replace(index, gtsam.BetweenFactorPose2(factor.keys()[0], factor.keys()[1], _pose2(relative),
                                                           factor.noiseModel()))

    def move(self, poses: dict[int, np.ndarray]) -> None:
        """New values of the poses given (the latest estimates: the next solve starts there)."""
        for key, pose in poses.items():
            self.initial.update(key, _pose2(pose))

    def optimize(self, robust: bool = True) -> tuple[dict[int, np.ndarray], set[int]]:
        """Optimized poses by key, and the loops (factor indices) the robust solve rejected; loop factors
        robust (GNC, truncated least squares) when asked."""
        rejected: set[int] = set()
        if robust and self.loops:
            params = gtsam.GncLMParams(gtsam.LevenbergMarquardtParams())
            params.setKnownInliers(self.inliers)
            optimizer = gtsam.GncLMOptimizer(self.graph, self.initial, params)
            optimizer.setInlierCostThresholdsAtProbability(INLIER_PROBABILITY)
            result = optimizer.optimize()
            weights = np.asarray(optimizer.getWeights())
            # GNC can drop a consistent loop with a wrong one that pulled both: one whose χ² at the solution
            # is within the threshold is kept
            rejected = {index for _, _, index in self.loops if weights[index] < 0.5
                        and 2.0 * self.graph.at(index).error(result) > LOOP_INLIER_CHI2}
        else:
            result = gtsam.LevenbergMarquardtOptimizer(self.graph, self.initial).optimize()
        self.initial = result
        poses = gtsam.utilities.extractPose2(result)
        return dict(zip((int(k) for k in result.keys()), poses)), rejected

    def factors(self, start: int = 0, excluded: set[int] = frozenset()) -> list[tuple[int, gtsam.NonlinearFactor]]:
        """The factors (index, factor) from index ``start`` on, but those ``excluded``."""
        return [(index, self.graph.at(index)) for index in range(start, self.graph.size()) if index not in excluded]

    def marginal_sigmas(self, gate_chi2: float) -> dict[int, np.ndarray] | None:
        """Each pose's standard deviations (x, y, θ; position in the world frame) at the latest solution
        (Kaess & Dellaert, "Covariance recovery from a square root information matrix", 2009), from the
        prior, the odometry and the loops whose χ² there is within ``gate_chi2`` (GNC's inliers: a loop it
        rejected fixes nothing); None where the graph leaves a pose undetermined."""
        graph = gtsam.NonlinearFactorGraph()
        loops, inliers = {index for _, _, index in self.loops}, set(self.inliers)
        for index in range(self.graph.size()):
            factor = self.graph.at(index)
            if index in inliers or (index in loops and 2.0 * factor.error(self.initial) <= gate_chi2):
                graph.add(factor)
        try:
            marginals = gtsam.Marginals(graph, self.initial)
        except RuntimeError:  # an indeterminant system
            return None
        # Pose2's covariance is in its own frame: expressed in the frame turned back by θ, the world's
        return {int(key): np.sqrt(np.diag(local_covariance(marginals.marginalCovariance(key),
                                                           -self.initial.atPose2(key).theta())))
                for key in self.initial.keys()}
