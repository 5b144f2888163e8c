"""The back end (issue #12): owns the pose graph (:mod:`radioslam.slam.pose_graph`), the latest
pose estimates, and how to solve (issue #14): every scan's factors go into the incremental smoother
(:mod:`radioslam.slam.incremental`, iSAM2), which gives the solution whenever loop closures were
added; the robust batch solve of the whole graph (GNC) runs only when a loop's residual there is
beyond the inlier threshold, or after a factor already in the graph was changed (a kidnap's step cut,
a fork's branch switched), and the smoother is then built again from the loops it kept.

Each front-end step becomes a between factor from the previous pose with the step's
covariance expressed in that pose's frame; external odometry adds its own between factor
per step (an independent measurement of the same motion); loop closures and relocalizations
come from the loop closer.
"""

from __future__ import annotations

import numpy as np

from radioslam.slam.config import MotionConfig, PoseGraphConfig
from radioslam.slam.front_end import Step
from radioslam.slam.incremental import IncrementalSmoother
from radioslam.slam.loop_closer import LoopCloser, LoopClosure
from radioslam.slam.motion import jump_covariance
from radioslam.slam.pose_graph import LOOP_INLIER_CHI2, PoseGraph, local_covariance
from radioslam.slam.se2 import between, compose, inverse, pose_covariance


class BackEnd:
    def __init__(self, cfg: PoseGraphConfig, motion: MotionConfig):
        self.cfg = cfg
        self.graph = PoseGraph(prior_sigmas=np.array([cfg.prior_sigma_m, cfg.prior_sigma_m,
                                                      np.radians(cfg.prior_sigma_deg)]))
        self.odometry_noise = pose_covariance(motion.odometry_sigma_m, motion.odometry_sigma_deg)
        # a gyro's step: its turn at the odometry's heading noise, its translation unmeasured (a kilometre)
        self.gyro_noise = pose_covariance(1e3, motion.odometry_sigma_deg)
        self.jump_covariance = jump_covariance(motion)  # a step the front end did not see (a kidnap, a branch left)
        self.step_factor: dict[int, int] = {}  # the front-end between factor into each pose
        self.estimates: dict[int, np.ndarray] = {}  # the latest solution, every pose so far
        self.chain: dict[int, np.ndarray] = {}  # the front end's steps composed: no loops, no optimization
        self.step_covariance: dict[int, np.ndarray] = {}  # each step's covariance in its previous pose's frame
        self.summed: list[np.ndarray] = []  # [k]: the step covariances into poses 1 … k summed (drift in O(1))
        self.loops: list[LoopClosure] = []
        self.smoother = IncrementalSmoother()
        self.stale = False  # a factor changed since the smoother was built: the next solve is the batch one
        self.batch_solves = 0

    @classmethod
    def from_config(cls, cfg) -> "BackEnd":
        return cls(cfg.pose_graph, cfg.motion)

    def add(self, k: int, step: Step, odometry_step: np.ndarray | None = None) -> None:
        """Pose k and the factors tying it to pose k − 1."""
        previous, since = self.estimates.get(k - 1), self.graph.graph.size()
        self.graph.add_pose(k, step.pose)
        if previous is None:
            self.chain[k] = step.pose
        else:
            relative = between(previous, step.pose)
            self.step_covariance[k] = local_covariance(step.covariance, previous[2])
            self.step_factor[k] = self.graph.add_odometry(k - 1, k, relative, self.step_covariance[k])
            if odometry_step is not None and np.isnan(odometry_step[:2]).any():  # a gyro: the turn alone
                self.graph.add_odometry(k - 1, k, np.array([0.0, 0.0, odometry_step[2]]), self.gyro_noise)
            elif odometry_step is not None:
                self.graph.add_odometry(k - 1, k, odometry_step, self.odometry_noise)
            self.chain[k] = compose(self.chain[k - 1], relative)
        self.estimates[k] = step.pose
        self._sum_steps(k)
        self.smoother.add_pose(k, self.graph.initial.atPose2(k))
        self._forward(since)

    def add_loops(self, loops: list[LoopClosure]) -> None:
        """Loop closures (and relocalizations) into the graph, then a new solution."""
        since = self.graph.graph.size()
        for loop in loops:
            self.graph.add_loop(loop.anchor, loop.key, loop.relative, loop.covariance, known_inlier=loop.relocalization)
            self.loops.append(loop)
        if loops:
            self._forward(since)
            self._solve()

    def _forward(self, since: int) -> None:
        """The pose graph's factors from index ``since`` on into the smoother (not while it is stale)."""
        if not self.stale:
            self._feed(self.graph.factors(since))

    def _solve(self) -> None:
        """The smoother's solution; the batch one when it is stale or doubts a loop."""
        if not self.stale:
            self.estimates.update(enumerate(self.smoother.solve()))
        if self.stale or (self.cfg.gnc and self.smoother.doubtful(LOOP_INLIER_CHI2)):
            self._batch()

    def _batch(self) -> None:
        """The robust batch solve from the latest estimates; the smoother built again from its solution
        and every factor but the loops it rejected."""
        self.graph.move(self.estimates)
        solution, rejected = self.graph.optimize(self.cfg.gnc)
        self.batch_solves += 1
        self.smoother, self.stale = IncrementalSmoother(), False
        for key in sorted(solution):
            self.smoother.add_pose(key, self.graph.initial.atPose2(key))
        self._feed(self.graph.factors(excluded=rejected), judged=True)
        self.estimates.update(enumerate(self.smoother.solve()))  # with the loops GNC dropped but the solution keeps

    def _feed(self, factors, judged: bool = False) -> None:
        """Pose-graph factors (index, factor) into the smoother, new loops marked as ones it may doubt
        (not those the robust solve has ``judged``)."""
        for index, factor in factors:
            self.smoother.add_factor(factor, index if index in self.graph.doubtable and not judged else None)
        self.smoother.update()

    def cut(self, k: int) -> None:
        """The front end's step into pose k was a jump it did not see (a kidnapped terminal): it
        keeps only the relocalized-jump covariance (isotropic in position, so the same in every frame)."""
        if k in self.step_factor:
            self.step_covariance[k] = self.jump_covariance
            self._sum_steps(k)
            self.graph.loosen(self.step_factor[k], self.jump_covariance)
            self.stale = True

    def _sum_steps(self, since: int) -> None:
        """The running sums of the step covariances from pose ``since`` on (a new pose, or a step changed)."""
        del self.summed[since:]
        for m in range(since, len(self.estimates)):
            self.summed.append((self.summed[-1] if self.summed else np.zeros((3, 3)))
                               + self.step_covariance.get(m, np.zeros((3, 3))))

    def switch(self, switches: list[tuple[int, np.ndarray]]) -> None:
        """The front end's steps into the poses k of ``switches`` (k, jump) were rivals'
        (:mod:`radioslam.slam.forks`), latest first: pose k and every later one are carried by the
        world transform ``jump``, the step into k measures the rival's, the loops tying those poses to
        older ones (made in the branch left) lose their weight; then the graph is solved again."""
        for k, jump in switches:
            self._carry(k, jump)
        self._batch()

    def _carry(self, k: int, jump: np.ndarray) -> None:
        self.estimates.update({m: compose(jump, pose) for m, pose in self.estimates.items() if m >= k})
        if k in self.step_factor:
            self.graph.remeasure(self.step_factor[k], between(self.estimates[k - 1], self.estimates[k]))
            carried = compose(self.chain[k - 1], between(self.estimates[k - 1], self.estimates[k]))
            correction = compose(carried, inverse(self.chain[k]))
            self.chain.update({m: compose(correction, pose) for m, pose in self.chain.items() if m >= k})
        for index in [index for anchor, key, index in self.graph.loops if anchor < k <= key]:
            self.graph.loosen(index, self.jump_covariance)
        self.stale = True
        self.loops = [loop for loop in self.loops if not loop.anchor < k <= loop.key]

    def odometry_covariance(self, motion) -> np.ndarray | None:
        """The noise of the external odometry's steps (a gyro's: its turn alone), None without one."""
        if motion.odometry is None:
            return None
        return self.gyro_noise if motion.gyro_only else self.odometry_noise

    def relocalized_pose(self, loop: LoopClosure) -> np.ndarray:
        """The world pose a relocalization places its scan at."""
        return LoopCloser.placed_pose(loop, self.estimates)

    def drift(self, anchor: int, key: int, distance: float) -> np.ndarray:
        """First-order drift between two poses: the step covariances summed, the heading's variance
        also spreading the position by the distance between them."""
        total = self.summed[key] - self.summed[anchor]
        return total + np.diag([total[2, 2] * distance**2] * 2 + [0.0])

    def pose_sigmas(self, count: int) -> np.ndarray | None:
        """(count, 3) standard deviations of poses 0 … count − 1 at the latest solution (None: undetermined)."""
        self.graph.move(self.estimates)
        sigmas = self.graph.marginal_sigmas(self.cfg.inlier_chi2)
        return None if sigmas is None else np.array([sigmas[k] for k in range(count)])

    def finish(self) -> None:
        """A last solution when any loop was closed."""
        if self.loops:
            self._solve()
