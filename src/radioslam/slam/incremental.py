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
        self.params = params
        self.isam = gtsam.ISAM2(params)
        self.factors, self.values = gtsam.NonlinearFactorGraph(), gtsam.Values()  # all it was given, for a refactoring
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
        """The pending poses and factors into the Bayes tree (one Gauss–Newton step). Should Cholesky find the
        normal equations indeterminate (a relocalized scan's step carries next to no information, 100 m and
        180°, beside steps of centimetres, and a loop across it squares that condition number: a generated
        office, issue #47), the tree is built again from everything given so far by QR, which factors the
        Jacobian itself; the smoother stays on QR."""
        if self.pending.size() or self.pending_values.size():
            try:
                self.isam.update(self.pending, self.pending_values)
            except RuntimeError:
                self._refactor(self.pending, self.pending_values)
            else:
                self.factors.push_back(self.pending)
                self.values.insert(self.pending_values)
            self.pending, self.pending_values = gtsam.NonlinearFactorGraph(), gtsam.Values()

    def _step(self) -> gtsam.ISAM2Result:
        """One more Gauss–Newton step of the tree (refactored by QR should Cholesky fail)."""
        try:
            return self.isam.update()
        except RuntimeError:
            self._refactor(gtsam.NonlinearFactorGraph(), gtsam.Values())
            return self.isam.update()

    def _refactor(self, factors: gtsam.NonlinearFactorGraph, values: gtsam.Values) -> None:
        """The tree built again by QR from everything given, with ``factors`` and ``values`` added."""
        self.params.setFactorization("QR")
        self.isam = gtsam.ISAM2(self.params)
        self.factors.push_back(factors)
        self.values.insert(values)
        self.isam.update(self.factors, self.values)

    def solve(self) -> np.ndarray:
        """(P, 3) poses by key (0 … P − 1) once the pending factors are in and the relinearized steps
        have settled: at most ``iterations`` more steps, until one relinearizes no pose (every pose's
        step from its linearization point within the threshold: a loop can move poses far from where
        they were linearized). The estimate is read once, at the end: reading it costs O(P)."""
        self.update()
        for _ in range(self.iterations):
            if not self._step().getVariablesRelinearized():
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
