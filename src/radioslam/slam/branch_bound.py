"""Branch-and-bound correlative scan matching over a wide window (Hess, Kohler, Rapp,
Andor, "Real-time loop closure in 2D LIDAR SLAM", ICRA 2016, §V: "fast_correlative_scan_matcher").

A node (a, h, ox, oy) stands for the 2^h × 2^h translations [ox, ox + 2^h) × [oy, oy + 2^h)
at heading a; the mean over the points of the level-h max-pooled grid bounds the
score of every translation in it. Level by level, nodes whose bound is below the
threshold are pruned and the rest split into four; a greedy descent from the best node
first raises the threshold to a score that is actually reached (and, before the top level, the
best of the leaves nearest the seeds given: a motion model's predictions). At level 0 the bound
is the score, so the result is the exhaustive search's best (an exact search, not a
heuristic), at a fraction of the lookups. The leaf score includes the normal agreement;
the coarser bounds leave it out (it is ≤ 1), so they stay admissible.

The headings are any set (a window around a prediction, or the candidates of the global
rotation search, :mod:`radioslam.slam.rotation_search`). With ``keep_ratio`` < 1 the search
returns every leaf within that fraction of the best, not only the best: the threshold is
then ``keep_ratio`` times the greedy score, which still never prunes such a leaf. Those
leaves, grouped by non-maximum suppression, are the distinct hypotheses an ambiguity test
compares.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from radioslam.slam.correlative import heading_cells
from radioslam.slam.grid import LikelihoodGrid, phasors
from radioslam.slam.se2 import wrap_angle


@dataclass(frozen=True)
class BranchBoundResult:
    pose: np.ndarray | None  # None: no candidate reached the minimum score
    score: float
    evaluated: int  # candidate nodes scored (against the exhaustive search's count)
    exhaustive: int
    # (C, 3) leaves within keep_ratio of the best, best first, and their scores
    candidates: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    scores: np.ndarray = field(default_factory=lambda: np.zeros(0))
    judged: np.ndarray = field(default_factory=lambda: np.zeros(0))  # their discounted scores (= scores: none)


def window_angles(window_rad: float, step: float) -> np.ndarray:
    """Offsets −window … window in ``step`` (symmetric, 0 included)."""
    half = np.floor(window_rad / step + 1e-9)
    return step * np.arange(-half, half + 1)


class BranchAndBound:
    """Built once per map grid: the max-pooled pyramid up to ``levels``."""

    def __init__(self, grid: LikelihoodGrid, levels: int):
        self.grid, self.levels = grid, levels
        self.pyramid = grid.pyramid(levels)

    def _scores(self, cells, plane_offset, phasor, nodes, level):
        """Mean bound (N,) of nodes (angle index, ox, oy) at ``level``; exact with normals at 0.
        ``cells`` (2, A, P) holds the points' cells at each heading, ``phasor`` their world-normal
        phasors (A, P) (None: left out, a bound of the score with them)."""
        nx, ny = self.grid.values.shape
        a = nodes[:, 0]
        cell = cells[0, a]  # (N, P) flat indices, built in place (int32: the hottest loop of the search)
        cell += nodes[:, 1:2]
        np.clip(cell, 0, nx - 1, out=cell)
        cell *= ny
        y = cells[1, a]
        y += nodes[:, 2:3]
        cell += np.clip(y, 0, ny - 1, out=y)
        world_normal = phasor[a] if level == 0 and phasor is not None else None
        offset = plane_offset if level == 0 else 0  # the coarse levels hold one field, the max of both
        return self.grid.likelihood_of_cells(cell, offset, world_normal, self.pyramid[level]).mean(axis=1)

    def _children(self, nodes, level, reach):
        half = 2 ** (level - 1)
        steps = np.array([[0, 0, 0], [0, half, 0], [0, 0, half], [0, half, half]], dtype=np.int32)
        kids = (nodes[:, None, :] + steps[None]).reshape(-1, 3)
        return kids[(kids[:, 1] <= reach) & (kids[:, 2] <= reach)]

    def match(self, points: np.ndarray, normals: np.ndarray, prediction: np.ndarray, window_m: float,
              window_rad: float, angle_step: float, min_score: float) -> BranchBoundResult:
        """The best pose within ±window of ``prediction`` (x, y, θ)."""
        headings = prediction[2] + window_angles(window_rad, angle_step)
        return self.search(points, normals, prediction[:2], headings, window_m, min_score, seeds=prediction[None])

    def search(self, points: np.ndarray, normals: np.ndarray, centre: np.ndarray, headings: np.ndarray,
               window_m: float, min_score: float, keep_ratio: float = 1.0,
               discount: Callable[[np.ndarray], np.ndarray] | None = None,
               seeds: np.ndarray | None = None) -> BranchBoundResult:
        """Poses (x, y) within ±window_m of ``centre`` at each of ``headings`` (A,): the best, and
        every leaf scoring at least ``keep_ratio`` times the best. With a prior ``discount`` (a
        fraction of the score per pose (C, 3)), the best is the best discounted score, and every
        leaf whose own score reaches ``keep_ratio`` times it is kept (the candidates a decision
        on discounted scores can pick, and no more). ``seeds`` (S, 3), poses likely near the best
        (a motion model's predictions), only speed it up: the leaves nearest them are scored first,
        and the best of those, a score actually reached, prunes from the top level on (the same
        result: the threshold never exceeds ``keep_ratio`` times the best)."""
        res = self.grid.resolution
        reach = int(np.ceil(window_m / res))
        cells = np.ascontiguousarray(np.moveaxis(heading_cells(self.grid, points, centre, headings), 2, 0))
        plane_offset = np.where(np.isnan(normals), 0, self.grid.values.size).astype(np.int32)
        phasor = phasors(headings[:, None] + normals[None, :])  # (A, P) world normals, once per heading
        top = 2**self.levels
        starts = np.arange(-reach, reach + 1, top)
        ga, gx, gy = np.meshgrid(np.arange(len(headings)), starts, starts, indexing="ij")
        nodes = np.stack([ga.ravel(), gx.ravel(), gy.ravel()], axis=1).astype(np.int32)
        exhaustive = len(headings) * (2 * reach + 1) ** 2

        def poses_of(leaves):  # (N, 3) world poses of leaf nodes (angle index, ox, oy)
            return np.stack([centre[0] + leaves[:, 1] * res, centre[1] + leaves[:, 2] * res,
                             wrap_angle(headings[leaves[:, 0]])], axis=1)

        threshold, evaluated = min_score, 0
        leaves = self._near(np.atleast_2d(seeds), centre, headings, reach) if seeds is not None else np.zeros((0, 3))
        if len(leaves):
            reached = self._scores(cells, plane_offset, phasor, leaves, 0)
            if discount is not None:
                reached = reached * (1.0 - discount(poses_of(leaves)))
            threshold, evaluated = max(threshold, keep_ratio * float(reached.max())), len(leaves)
        for level in range(self.levels, -1, -1):
            if level == 0:  # the leaves' scores without the normal agreement bound theirs with it: only
                # the leaves that bound keeps are scored with it (a sixth of them, at a fifth of the cost each)
                nodes = nodes[self._scores(cells, plane_offset, None, nodes, 0) >= threshold]
            bound = self._scores(cells, plane_offset, phasor, nodes, level)
            evaluated += len(nodes)
            if level > 0:
                leaf, greedy = self._greedy(cells, plane_offset, phasor, nodes[np.argmax(bound)], level, reach)
                if discount is not None and leaf is not None:
                    greedy *= 1.0 - float(discount(poses_of(leaf[None]))[0])
                threshold = max(threshold, keep_ratio * greedy)
            kept = bound >= threshold
            nodes, bound = nodes[kept], bound[kept]
            if len(nodes) == 0:
                return BranchBoundResult(None, 0.0, evaluated, exhaustive)
            if level > 0:
                nodes = self._children(nodes, level, reach)
        poses = poses_of(nodes)
        judged = bound if discount is None else bound * (1.0 - discount(poses))
        order = np.argsort(-judged, kind="stable")
        order = order[bound[order] >= keep_ratio * judged[order[0]]]
        return BranchBoundResult(poses[order[0]], float(bound[order[0]]), evaluated, exhaustive, poses[order],
                                 bound[order], judged[order])

    def _near(self, seeds: np.ndarray, centre: np.ndarray, headings: np.ndarray, reach: int) -> np.ndarray:
        """The leaves (angle index, ox, oy) nearest the seed poses (S, 3) and their neighbours within a
        cell and a heading index, inside the search."""
        a = np.argmin(np.abs(wrap_angle(headings[None, :] - seeds[:, 2:3])), axis=1)
        offset = np.round((seeds[:, :2] - centre[:2]) / self.grid.resolution)
        step = np.stack(np.meshgrid([-1, 0, 1], [-1, 0, 1], [-1, 0, 1], indexing="ij"), axis=-1).reshape(-1, 3)
        leaves = (np.column_stack([a, offset]).astype(np.int32)[:, None, :] + step[None]).reshape(-1, 3)
        inside = (leaves[:, 0] >= 0) & (leaves[:, 0] < len(headings)) & np.all(np.abs(leaves[:, 1:]) <= reach, axis=1)
        return np.unique(leaves[inside], axis=0)

    def _greedy(self, cells, plane_offset, phasor, node, level, reach) -> tuple[np.ndarray | None, float]:
        """The leaf reached by always taking the best child, and its score: a reachable lower bound."""
        nodes = node[None]
        for h in range(level, 0, -1):
            nodes = self._children(nodes, h, reach)
            if len(nodes) == 0:
                return None, 0.0
            nodes = nodes[[np.argmax(self._scores(cells, plane_offset, phasor, nodes, h - 1))]]
        return nodes[0], float(self._scores(cells, plane_offset, phasor, nodes, 0)[0])


def distinct(poses: np.ndarray, scores: np.ndarray, radius_m: float, radius_rad: float,
             count: int) -> tuple[np.ndarray, np.ndarray]:
    """Non-maximum suppression of candidates (C, 3) sorted best first: up to ``count`` poses
    none of which lies within ``radius_m`` and ``radius_rad`` of a better one."""
    left = np.arange(len(poses))
    keep = []
    while len(left) and len(keep) < count:
        best = left[0]
        keep.append(best)
        near = (np.linalg.norm(poses[left, :2] - poses[best, :2], axis=1) <= radius_m) & \
               (np.abs(wrap_angle(poses[left, 2] - poses[best, 2])) <= radius_rad)
        left = left[~near]
    return poses[keep], scores[keep]
