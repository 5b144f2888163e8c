"""Incremental smoothing of the pose graph (Kaess, Johannsson, Roberts, Ila, Leonard, Dellaert,
"iSAM2: Incremental smoothing and mapping using the Bayes tree", IJRR 2012): ``gtsam.ISAM2``
takes each scan's pose and factors as they come and re-solves only the part of the Bayes tree a
new factor touches, so a scan costs the same after a thousand poses as after ten.

It holds the factors the back end trusts (the prior, the steps, the relocalizations and the loops
the last robust solve kept); :meth:`doubtful` names the new loops whose residual at the smoother's
solution lies beyond the inlier threshold of the robust batch solve
(:meth:`radioslam.slam.pose_graph.PoseGraph.optimize`), which then decides.
"""

from __future__ import annotations

import gtsam
import numpy as np


class IncrementalSmoother:
    def __init__(self, relinearize_threshold: float = 1e-3, iterations: int = 4):
        params = gtsam.ISAM2Params()
        params.setRelinearizeThreshold(relinearize_threshold)
        params.relinearizeSkip = 1
        # QR, not Cholesky: a relocalized scan's step carries next to no information (100 m, 180°) beside
        # steps of centimetres, and a loop across it made the normal equations indeterminate for Cholesky
        # (a generated office, issue #47); QR factors the Jacobian itself, its condition number not squared
        params.setFactorization("QR")
        self.isam = gtsam.ISAM2(params)
        self.iterations = iterations  # at most this many extra Gauss–Newton steps after a loop
        self.pending = gtsam.NonlinearFactorGraph()
        self.pending_values = gtsam.Values()
        self.loops: dict[int, gtsam.NonlinearFactor] = {}  # the pose graph's index → a loop not yet judged
        self.solution = gtsam.Values()  # the last solve's

    def add_pose(self, key: int, pose: gtsam.Pose2) -> None:
        self.pending_values.insert(key, pose)

    def add_factor(self, factor: gtsam.NonlinearFactor, loop_index: int | None = None) -> None:
        """A factor for the next update; ``loop_index``: the pose graph's index of a loop it may doubt."""
        self.pending.add(factor)
        if loop_index is not None:
            self.loops[loop_index] = factor

    def update(self) -> None:
        """The pending poses and factors into the Bayes tree (one Gauss–Newton step)."""
        if self.pending.size() or self.pending_values.size():
            self.isam.update(self.pending, self.pending_values)
            self.pending, self.pending_values = gtsam.NonlinearFactorGraph(), gtsam.Values()

    def solve(self) -> np.ndarray:
        """(P, 3) poses by key (0 … P − 1) once the pending factors are in and the relinearized steps
        have settled: at most ``iterations`` more steps, until one relinearizes no pose (every pose's
        step from its linearization point within the threshold: a loop can move poses far from where
        they were linearized). The estimate is read once, at the end: reading it costs O(P)."""
        self.update()
        for _ in range(self.iterations):
            if not self.isam.update().getVariablesRelinearized():
                break
        self.solution = self.isam.calculateEstimate()
        return gtsam.utilities.extractPose2(self.solution)

    def doubtful(self, threshold_chi2: float) -> list[int]:
        """The loops added since the last call (pose-graph indices) whose χ² at the last :meth:`solve`'s
        solution exceeds ``threshold_chi2``: a wrong loop shows its residual when it comes (the loops before
        it held), and an older loop it pulls out of place is judged again by the robust solve it calls for."""
        if not self.loops:
            return []
        doubtful = [index for index, factor in self.loops.items()
                    if 2.0 * factor.error(self.solution) > threshold_chi2]
        self.loops = {}
        return doubtful
