"""Branch-and-bound correlative scan matching over a wide window (Hess, Kohler, Rapp,
Andor, "Real-time loop closure in 2D LIDAR SLAM", ICRA 2016, §V: "fast_correlative_scan_matcher").

A node (θ, h, ox, oy) stands for the 2^h × 2^h translations [ox, ox + 2^h) × [oy, oy + 2^h)
at one rotation; the mean over the points of the level-h max-pooled grid bounds the
score of every translation in it. Level by level, nodes whose bound is below the
threshold are pruned and the rest split into four; a greedy descent from the best node
first raises the threshold to a score that is actually reached. At level 0 the bound
is the score, so the result is the exhaustive search's best (an exact search, not a
heuristic), at a fraction of the lookups. The leaf score includes the normal agreement;
the coarser bounds leave it out (it is ≤ 1), so they stay admissible.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from radioslam.slam.correlative import candidate_cells
from radioslam.slam.grid import LikelihoodGrid


@dataclass(frozen=True)
class BranchBoundResult:
    pose: np.ndarray | None  # None: no candidate reached the minimum score
    score: float
    evaluated: int  # candidate nodes scored (against the exhaustive search's count)
    exhaustive: int


class BranchAndBound:
    """Built once per map grid: the max-pooled pyramid up to ``levels``."""

    def __init__(self, grid: LikelihoodGrid, levels: int):
        self.grid, self.levels = grid, levels
        self.pyramid = grid.pyramid(levels)

    def _scores(self, cells, normals, theta, nodes, level):
        """Mean bound (N,) of nodes (angle index, ox, oy) at ``level``; exact with normals at 0."""
        a, ox, oy = nodes[:, 0], nodes[:, 1], nodes[:, 2]
        x, y = cells[a, :, 0] + ox[:, None], cells[a, :, 1] + oy[:, None]  # (N, P)
        world_normal = theta[a][:, None] + normals[None, :] if level == 0 else None
        return self.grid.likelihood_at(x, y, ~np.isnan(normals), world_normal, self.pyramid[level]).mean(axis=1)

    def _children(self, nodes, level, reach):
        half = 2 ** (level - 1)
        steps = np.array([[0, 0, 0], [0, half, 0], [0, 0, half], [0, half, half]])
        kids = (nodes[:, None, :] + steps[None]).reshape(-1, 3)
        return kids[(kids[:, 1] <= reach) & (kids[:, 2] <= reach)]

    def match(self, points: np.ndarray, normals: np.ndarray, prediction: np.ndarray, window_m: float,
              window_rad: float, angle_step: float, min_score: float) -> BranchBoundResult:
        res = self.grid.resolution
        angles = angle_step * np.arange(-np.floor(window_rad / angle_step), np.floor(window_rad / angle_step) + 1)
        reach = int(np.ceil(window_m / res))
        cells = candidate_cells(self.grid, points, prediction, angles)
        theta = prediction[2] + angles
        top = 2**self.levels
        starts = np.arange(-reach, reach + 1, top)
        ga, gx, gy = np.meshgrid(np.arange(len(angles)), starts, starts, indexing="ij")
        nodes = np.stack([ga.ravel(), gx.ravel(), gy.ravel()], axis=1)
        threshold, evaluated = min_score, 0
        for level in range(self.levels, -1, -1):
            bound = self._scores(cells, normals, theta, nodes, level)
            evaluated += len(nodes)
            if level > 0:
                threshold = max(threshold, self._greedy(cells, normals, theta, nodes[np.argmax(bound)], level, reach))
            nodes = nodes[bound >= threshold]
            if len(nodes) == 0:
                return BranchBoundResult(None, 0.0, evaluated, len(angles) * (2 * reach + 1) ** 2)
            if level > 0:
                nodes = self._children(nodes, level, reach)
        best = np.argmax(bound[bound >= threshold])
        a, ox, oy = nodes[best]
        pose = prediction + np.array([ox * res, oy * res, angles[a]])
        return BranchBoundResult(pose, float(bound[bound >= threshold][best]), evaluated,
                                 len(angles) * (2 * reach + 1) ** 2)

    def _greedy(self, cells, normals, theta, node, level, reach) -> float:
        """Score of the leaf reached by always taking the best child: a reachable lower bound."""
        nodes = node[None]
        for h in range(level, 0, -1):
            nodes = self._children(nodes, h, reach)
            if len(nodes) == 0:
                return 0.0
            nodes = nodes[[np.argmax(self._scores(cells, normals, theta, nodes, h - 1))]]
        return float(self._scores(cells, normals, theta, nodes, 0)[0])
