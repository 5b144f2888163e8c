"""Loop closure and relocalization against submaps (Cartographer's ``ConstraintBuilder2D``:
Hess, Kohler, Rapp, Andor, "Real-time loop closure in 2D LIDAR SLAM", ICRA 2016, §V).

The loop closer matches against the map's submaps (N consecutive keyframes fused in the frame of the first:
:class:`~radioslam.slam.keyframe_map.KeyframeMap`), one branch-and-bound pyramid per submap (kept while its
scans stay put relative to its first one, as Cartographer keeps a finished submap's grid: rebuilt only once one
has moved by ``submap_rebuild_m`` or ``submap_rebuild_deg``, not at every pose-graph solution; at most
``cached_matchers`` of them, the least recently used dropped, and a dropped one matched again only
when no kept or new one is near) and the acceptance tests of a loop:

- the normalized score (mean point likelihood, in [0, 1], independent of the number of points);
- geometric consistency with the graph: the match must agree with the pose the odometry
  predicts, within their joint covariance (a χ²(3) gate);
- the information of the points that agree with the submap must fix every direction
  (:mod:`radioslam.slam.degeneracy`): one wall in common lets the match slide along it.

Score and χ² weigh a loop smoothly instead of flipping it (issue #12): its covariance is
divided by a weight that rises from 0 at ``min_score`` to 1 at ``min_score + score_ramp``
and falls from 1 at half the gate to 0 at the gate, so a loop on the edge of acceptance
carries almost no weight either way.

Relocalization (the global constraint search of Cartographer): a lost scan is matched
against the whole map (every earlier scan with the free space it saw, one grid; small
submaps, each seen from a few poses, let a wrong place outscore the right one), over its
whole extent and every heading the normals suggest (:mod:`radioslam.slam.rotation_search`);
a match that scores ``relocalize_min_score``, is not degenerate and has no rival place within
the ambiguity margin places the scan again.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np

from radioslam.slam.branch_bound import BranchAndBound
from radioslam.slam.config import GridConfig, LoopClosureConfig
from radioslam.slam.grid import LikelihoodGrid
from radioslam.slam.keyframe_map import KeyframeMap
from radioslam.slam.pose_graph import local_covariance
from radioslam.slam.refine import fit_score
from radioslam.slam.scan_matcher import ScanMatcher, loop_matcher, relocalization_matcher
from radioslam.slam.scan_points import ScanPoints, fused_free, fused_points
from radioslam.slam.se2 import between, compose, wrap_angle
from radioslam.slam.submap import Submap


@dataclass(frozen=True)
class LoopClosure:
    anchor: int  # the submap's first scan
    key: int  # the current scan
    relative: np.ndarray  # the current pose in the anchor's frame
    covariance: np.ndarray  # already divided by the weight
    score: float
    weight: float = 1.0  # in (0, 1]: how far inside the acceptance tests it lies
    relocalization: bool = False  # places a lost scan: the graph must keep it
    searched_m2: float = 0.0  # a relocalization's: the area its search covered (any pose there was possible)


def mahalanobis2(measured: np.ndarray, predicted: np.ndarray, covariance: np.ndarray) -> float:
    d = measured - predicted
    d[2] = wrap_angle(d[2])
    return float(d @ np.linalg.solve(covariance, d))


def smooth_step(x: float) -> float:
    """0 below 0, 1 above 1, 3x² − 2x³ between: continuous with its slope."""
    x = float(np.clip(x, 0.0, 1.0))
    return x * x * (3 - 2 * x)


@dataclass
class LoopCloser:
    grid_cfg: GridConfig
    cfg: LoopClosureConfig
    matcher: ScanMatcher  # a loop's, within its window of the pose the graph predicts
    relocalizer: ScanMatcher  # relocalization's, over the whole map
    keyframes: KeyframeMap  # the map's scans and their submaps (the session inserts them)
    pyramids: dict[int, tuple[np.ndarray, BranchAndBound]] = field(default_factory=dict)  # anchor → (its scans'
    # poses in the anchor's frame when its pyramid was built, the pyramid)
    tried: dict[int, int] = field(default_factory=dict)  # anchor → the last scan matched against it

    @property
    def floor(self) -> np.ndarray:
        """The covariance floor: a loop's response surface is as over-confident as the front end's."""
        return self.matcher.floor

    @classmethod
    def from_config(cls, cfg, keyframes: KeyframeMap | None = None) -> "LoopCloser":
        return cls(cfg.grid, cfg.loop_closure, loop_matcher(cfg), relocalization_matcher(cfg),
                   KeyframeMap.from_config(cfg) if keyframes is None else keyframes)

    def _grid(self, submap: Submap, estimates, margin: float) -> LikelihoodGrid:
        g = self.grid_cfg
        xy, nrm = fused_points(submap.keys, estimates, self.keyframes.points, estimates[submap.anchor])
        return LikelihoodGrid.from_points(xy, g.resolution_m, g.sigma_m, margin, nrm, np.radians(g.normal_sigma_deg),
                                          self.cfg.plane_reach_m)

    def _pyramid(self, submap: Submap, estimates, margin: float) -> BranchAndBound:
        """The submap's branch-and-bound pyramid, built again only once its scans have moved relative to its first one
        (by ``submap_rebuild_m`` or ``submap_rebuild_deg``) since it was built."""
        relative = np.array([between(estimates[submap.anchor], estimates[m]) for m in submap.keys])
        built = self.pyramids.pop(submap.anchor, None)  # put back last: the dict's order is the use order
        if built is None or len(built[0]) != len(relative) or self._moved(built[0], relative):
            built = (relative, self.matcher.pyramid(self._grid(submap, estimates, margin)))
        self.pyramids[submap.anchor] = built
        while len(self.pyramids) > self.cfg.cached_matchers:  # the least recently used goes
            del self.pyramids[next(iter(self.pyramids))]
        return built[1]

    def _moved(self, before: np.ndarray, now: np.ndarray) -> bool:
        """Whether a submap's scan poses (S, 3) in its first scan's frame moved by the rebuild tolerance."""
        shift = np.linalg.norm(now[:, :2] - before[:, :2], axis=1).max()
        turn = np.abs(wrap_angle(now[:, 2] - before[:, 2])).max()
        return shift > self.cfg.submap_rebuild_m or turn > np.radians(self.cfg.submap_rebuild_deg)

    def budget(self, k: int, last_tied: int | None) -> int:
        """How many submaps scan k matches: ``loop_matches_per_scan``, but while a scan of the last
        ``tied_search_every`` closed a loop (``last_tied``: the latest that did) only every
        ``tied_search_every``-th scan searches (the others match none)."""
        every = self.cfg.tied_search_every
        tied = last_tied is not None and k - last_tied <= every
        return self.cfg.loop_matches_per_scan if not tied or k % every == 0 else 0

    def close(self, k: int, estimates: dict[int, np.ndarray],
              drift: Callable[[int, int, float], np.ndarray], budget: int) -> list[LoopClosure]:
        """Verified loop closures of scan k against at most ``budget`` older submaps near its pose;
        ``drift(anchor, k, distance)`` is the covariance the odometry accumulated between the two poses."""
        current = estimates[k]
        margin = max(self.matcher.options.response_m, self.cfg.window_m) + 3 * self.grid_cfg.sigma_m
        found = []
        for s in self._candidates(current, estimates, budget):
            self.tried[s.anchor] = k
            pyramid = self._pyramid(s, estimates, margin)
            predicted = between(estimates[s.anchor], current)
            loop = self._match(pyramid, self.keyframes.points[k], predicted,
                               drift(s.anchor, k, np.linalg.norm(predicted[:2])), s.anchor, k)
            if loop is not None:
                found.append(loop)
        return found

    def _candidates(self, current: np.ndarray, estimates: dict[int, np.ndarray], budget: int) -> list[Submap]:
        """The older submaps (not the ``skip_submaps`` latest) with a scan within ``radius_m`` of the pose
        ``current``: at most ``budget`` of them, never tried ones first, then those whose pyramids are kept,
        each group the one tried longest ago first, then the nearest."""
        submaps = self.keyframes.submaps
        older = submaps[:max(0, len(submaps) - 1 - self.cfg.skip_submaps)]
        if not older or budget <= 0:
            return []
        keys = [m for s in older for m in s.keys]
        starts = np.cumsum([0] + [len(s.keys) for s in older[:-1]])
        distance = np.linalg.norm(np.array([estimates[m][:2] for m in keys]) - current[:2], axis=1)
        nearest = np.minimum.reduceat(distance, starts)  # each submap's scan nearest the pose
        near = []
        for s, d in zip(older, nearest):
            if d <= self.cfg.radius_m:
                tried = self.tried.get(s.anchor, -1)
                near.append((tried >= 0 and s.anchor not in self.pyramids, tried, float(d), s.anchor, s))
        near.sort(key=lambda c: c[:4])
        return [c[4] for c in near[:budget]]

    def _match(self, pyramid: BranchAndBound, points: ScanPoints, predicted: np.ndarray, drift: np.ndarray,
               anchor: int, key: int) -> LoopClosure | None:
        """A verified, weighted loop closure of the scan against a submap's pyramid (anchor frame)."""
        fit = self._window_fit(pyramid, points, predicted)
        if fit is None:
            return None
        local, pose, score_weight = fit
        chi2 = mahalanobis2(pose, predicted, drift + local.covariance + self.floor)
        weight = score_weight * smooth_step(2.0 * (self.cfg.gate_chi2 - chi2) / self.cfg.gate_chi2)
        if weight <= 0.0 or self._degenerate(pyramid.grid, points, pose, local.covariance):
            return None
        return LoopClosure(anchor, key, pose, (local.covariance + self.floor) / weight, local.score, weight)

    def matched_in(self, pyramid: BranchAndBound, k: int, pose: np.ndarray, keys: list[int] | tuple[int, ...],
                   estimates: dict[int, np.ndarray]) -> LoopClosure | None:
        """Scan k matched against a whole map (``pyramid`` over the world-frame grid of the scans
        ``keys``) within the loop window of ``pose``: a loop tied to the map scan nearest the place,
        weighted by its score alone (no chain to gate it against), or None (weak, degenerate)."""
        points = self.keyframes.points[k]
        fit = self._window_fit(pyramid, points, pose)
        if fit is None:
            return None
        local, fitted, weight = fit
        if weight <= 0.0 or self._degenerate(pyramid.grid, points, fitted, local.covariance):
            return None
        loop = self.placed(k, fitted, local.score, (local.covariance + self.floor) / weight, keys, estimates)
        return replace(loop, weight=weight, relocalization=False)

    def _window_fit(self, pyramid: BranchAndBound, points: ScanPoints, around: np.ndarray):
        """The scan's best pose within the loop window of ``around`` (None: nothing scores ``min_score``),
        refined, with the response surface around it (its covariance, Olson 2009 §IV) and its score's
        weight: 0 at ``min_score``, 1 from ``min_score + score_ramp`` on."""
        c = self.cfg
        found = self.matcher.around(pyramid, points.xy, points.normals, around, c.window_m, np.radians(c.window_deg),
                                    c.min_score)
        if found.pose is None:
            return None
        local, pose = self.matcher.fit(pyramid.grid, points.xy, points.normals, found.pose)
        return local, pose, smooth_step((local.score - c.min_score) / c.score_ramp)

    def _degenerate(self, grid: LikelihoodGrid, points: ScanPoints, pose: np.ndarray, covariance: np.ndarray) -> bool:
        """Whether the points that agree with the map leave a direction unfixed (Zhang et al. 2016)."""
        return self.matcher.weak(grid, pose, points.xy, points.normals, covariance) is not None

    def whole_map(self, keys: list[int], estimates: dict[int, np.ndarray]) -> tuple[LikelihoodGrid, np.ndarray]:
        """The likelihood field of the scans ``keys`` (oldest first) at their latest poses with the free space
        they saw (one grid: small submaps, each seen from a few poses, let a wrong place outscore the right
        one), and the map points' world normals. Only what lies within ``relocalize_radius_m`` of the
        latest scan's pose (a square) enters, and all of that scan: a grid of bounded size however long
        the walk (a map smaller than that square is whole)."""
        g, radius = self.grid_cfg, self.cfg.relocalize_radius_m
        centre = estimates[keys[-1]][:2]
        # the scans that can reach the square (a far one's points cannot), in their order: memory bounded too
        reach = np.array([self.keyframes.points[m].reach for m in keys])
        poses = np.array([estimates[m][:2] for m in keys])
        keys = [m for m, inside in zip(keys, np.max(np.abs(poses - centre), axis=1) <= radius + reach) if inside]
        xy, normals = fused_points(keys, estimates, self.keyframes.points, np.zeros(3))
        free = fused_free(keys, estimates, self.keyframes.points)
        near = np.max(np.abs(xy - centre), axis=1) <= radius
        if not near.all():
            # the latest scan's own points: never an empty map
            near[len(xy) - len(self.keyframes.points[keys[-1]]):] = True
            xy, normals = xy[near], normals[near]
            free = free[np.max(np.abs(free - centre), axis=1) <= radius]
        grid = LikelihoodGrid.from_points(xy, g.resolution_m, g.sigma_m, self.cfg.relocalize_margin_m, normals,
                                          np.radians(g.normal_sigma_deg), g.plane_reach_m, free, g.free_penalty)
        return grid, normals

    def looks_alike(self, jump: np.ndarray, pose: np.ndarray, keys: list[int], grid: LikelihoodGrid,
                    estimates: dict[int, np.ndarray]) -> bool:
        """Whether the map ``grid`` of the scans ``keys`` looks the same after the world transform
        ``jump``: its scans within ``radius_m`` of ``pose``, carried by the jump, land on its walls again
        (score at least ``self_similar`` of their score in place). Then the room looks the same from
        both places (a symmetric room, a row of aisles) and no scan can tell them apart; carried
        anywhere else the points fall on free space or nothing."""
        near = [m for m in keys if np.linalg.norm(estimates[m][:2] - pose[:2]) <= self.cfg.radius_m]
        if not near:
            return False
        xy, normals = fused_points(near, estimates, self.keyframes.points, np.zeros(3))
        in_place = fit_score(grid, xy, normals, np.zeros(3))
        return fit_score(grid, xy, normals, jump) >= self.cfg.self_similar * in_place

    def follow(self, grid: LikelihoodGrid, map_normals: np.ndarray, points: ScanPoints, guesses: np.ndarray,
               radius_m: float) -> tuple[np.ndarray, float, np.ndarray]:
        """The scan's best pose against ``grid`` within ``radius_m`` of the first of ``guesses`` (G, 3), at
        every heading its normals or the guesses suggest (one step of any motion, as the front end searches
        its local map): its pose, score and covariance there (score 0 where nothing matches)."""
        headings = self.matcher.headings(points.normals, map_normals, guesses[:, 2])
        found = self.matcher.search(grid, points.xy, points.normals, guesses[0, :2], headings, radius_m, 0.0,
                                    seeds=guesses)
        if found.pose is None:
            return guesses[0], 0.0, self.floor
        local, pose = self.matcher.fit(grid, points.xy, points.normals, found.pose)
        return pose, fit_score(grid, points.xy, points.normals, pose), local.covariance

    def relocalize(self, k: int, points: ScanPoints, estimates: dict[int, np.ndarray],
                   before: int | None = None,
                   whole: tuple[LikelihoodGrid, np.ndarray] | None = None) -> LoopClosure | None:
        """Scan k placed where it matches best in the whole map (every scan before ``before``, at the
        latest poses, with the free space they saw; or the ``whole`` map given), over the map's extent
        and every heading the normals suggest; None when no place holds it unambiguously (a rival place
        within the ambiguity margin: a symmetric room), or the match is weak or degenerate. The
        constraint ties it to the map scan nearest the place found."""
        c, matcher = self.cfg, self.relocalizer
        keys = self.keyframes.before(k, before)
        if not keys:
            return None
        grid, normals = whole or self.whole_map(keys, estimates)
        lo, hi = grid.origin, grid.origin + np.array(grid.values.shape) * grid.resolution
        headings = matcher.headings(points.normals, normals)
        found = matcher.search(grid, points.xy, points.normals, 0.5 * (lo + hi), headings,
                               0.5 * float(np.max(hi - lo)), c.relocalize_min_score, matcher.keep_ratio)
        if found.pose is None:
            return None
        places, _ = matcher.distinct(found.candidates, found.scores)
        fits = [matcher.fit(grid, points.xy, points.normals, place) for place in places]
        scores = np.array([fit_score(grid, points.xy, points.normals, pose) for _, pose in fits])
        best = int(np.argmax(scores))
        (local, pose), score = fits[best], float(scores[best])
        rivals = np.delete(scores, best)
        if np.any(rivals >= (1.0 - matcher.options.ambiguity_margin) * score) or score < c.relocalize_min_score:
            return None
        if matcher.weak(grid, pose, points.xy, points.normals, local.covariance) is not None:
            return None
        return replace(self.placed(k, pose, score, local.covariance, keys, estimates), searched_m2=grid.area_m2)

    @staticmethod
    def placed_pose(loop: LoopClosure, estimates: dict[int, np.ndarray]) -> np.ndarray:
        """The world pose a relocalization places its scan at (latest estimates)."""
        return compose(estimates[loop.anchor], loop.relative)

    @staticmethod
    def placed(k: int, pose: np.ndarray, score: float, covariance: np.ndarray, keys: list[int] | tuple[int, ...],
               estimates: dict[int, np.ndarray]) -> LoopClosure:
        """The relocalization of scan k at world ``pose``: tied to the map scan nearest it."""
        anchor = keys[int(np.argmin([np.linalg.norm(estimates[m][:2] - pose[:2]) for m in keys]))]
        return LoopClosure(anchor, k, between(estimates[anchor], pose), local_covariance(covariance,
                           estimates[anchor][2]), score, 1.0, relocalization=True)
