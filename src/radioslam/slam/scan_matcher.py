"""One scan matcher (issue #47, point 5), Cartographer's ``mapping/internal/2d/scan_matching/`` in one object: branch
and bound over a window (Hess, Kohler, Rapp, Andor, "Real-time loop closure in 2D LIDAR SLAM", ICRA 2016, §V:
:mod:`radioslam.slam.branch_bound`) → the distinct candidates (non-maximum suppression) → each refined off the
lattice (Levenberg–Marquardt on the likelihood field: :mod:`radioslam.slam.refine`, Cartographer's Ceres matcher) →
the response surface around the pose taken and its covariance (Olson, "Real-time correlative scan matching", ICRA
2009, §IV: :mod:`radioslam.slam.correlative`) → the directions its agreeing points leave unfixed (Zhang, Kaess,
Singh, "On degeneracy of optimization-based state estimation problems", ICRA 2016: :mod:`radioslam.slam.degeneracy`).

The front end, the loop closer and relocalization each hold one, built by :func:`front_end_matcher`,
:func:`loop_matcher` and :func:`relocalization_matcher` from their own settings (:class:`MatcherOptions`): a
component reads its matching settings through its matcher, not from another component's config section.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from radioslam.slam.branch_bound import BranchAndBound, BranchBoundResult, distinct
from radioslam.slam.correlative import Match, correlative_match
from radioslam.slam.degeneracy import DegeneracyTest
from radioslam.slam.grid import LikelihoodGrid
from radioslam.slam.refine import fit_scores, refine_poses
from radioslam.slam.rotation_search import HeadingSearch
from radioslam.slam.se2 import pose_covariance


@dataclass(frozen=True)
class MatcherOptions:
    """One matcher's settings (angles in radians, but the floor's in degrees as configured)."""

    levels: int  # branch and bound's pyramid levels (a wider search wants more)
    angle_step_rad: float  # the rotation lattice of the searches and the response surface
    response_m: float  # the response surface's half window around the pose taken (its covariance)
    response_rad: float
    distinct_m: float  # candidates nearer than this in position and heading are one (non-maximum suppression)
    distinct_rad: float
    refined: int  # distinct candidates refined at most
    # two distinct places whose scores differ by less than this fraction are ambiguous; branch and bound keeps
    # candidates this much further below the best (a lattice pose may sit a cell off its wall), for refining
    ambiguity_margin: float
    lattice_allowance: float
    floor_sigma_m: float  # the covariance floor: the response surface is over-confident by this much
    floor_sigma_deg: float


class ScanMatcher:
    """Built from a :class:`MatcherOptions`, the degeneracy test and the heading search (the rotation candidates of
    a search over every heading the scan's normals suggest)."""

    def __init__(self, options: MatcherOptions, degeneracy: DegeneracyTest, headings: HeadingSearch):
        self.options, self.degeneracy, self.heading_search = options, degeneracy, headings
        self.floor = pose_covariance(options.floor_sigma_m, options.floor_sigma_deg)

    @property
    def keep_ratio(self) -> float:
        """The share of the best score a candidate must reach to be kept for refining and comparing."""
        return 1.0 - self.options.ambiguity_margin - self.options.lattice_allowance

    def pyramid(self, grid: LikelihoodGrid) -> BranchAndBound:
        """Branch and bound's max-pooled pyramid of ``grid`` (kept by a caller that matches against it often)."""
        return BranchAndBound(grid, self.options.levels)

    def search(self, grid: LikelihoodGrid, xy: np.ndarray, normals: np.ndarray, centre: np.ndarray,
               headings: np.ndarray, window_m: float, min_score: float, keep_ratio: float = 1.0,
               discount: Callable[[np.ndarray], np.ndarray] | None = None,
               seeds: np.ndarray | None = None) -> BranchBoundResult:
        """Branch and bound (:meth:`BranchAndBound.search`) over ``grid``, its pyramid built for this search."""
        return self.pyramid(grid).search(xy, normals, centre, headings, window_m, min_score, keep_ratio, discount,
                                         seeds)

    def around(self, pyramid: BranchAndBound, xy: np.ndarray, normals: np.ndarray, pose: np.ndarray,
               window_m: float, window_rad: float, min_score: float) -> BranchBoundResult:
        """The best pose within ±``window_m`` and ±``window_rad`` of ``pose`` (x, y, θ), on the angle lattice."""
        return pyramid.match(xy, normals, pose, window_m, window_rad, self.options.angle_step_rad, min_score)

    def headings(self, normals: np.ndarray, map_normals: np.ndarray, guesses=()) -> np.ndarray:
        """Every heading the scan's normals (against the map's) or the ``guesses`` suggest."""
        return self.heading_search.headings(normals, map_normals, guesses)

    def distinct(self, candidates: np.ndarray, scores: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The best ``refined`` candidates (C, 3, best first, with their scores) none of which lies within
        ``distinct_m`` and ``distinct_rad`` of a better one."""
        o = self.options
        return distinct(candidates, scores, o.distinct_m, o.distinct_rad, o.refined)

    def refine(self, grid: LikelihoodGrid, xy: np.ndarray, normals: np.ndarray, starts: np.ndarray) -> np.ndarray:
        """Each start (C, 3) refined off the lattice, within a cell and an angle step of it."""
        return refine_poses(grid, xy, normals, starts, grid.resolution, self.options.angle_step_rad)

    @staticmethod
    def scores(grid: LikelihoodGrid, xy: np.ndarray, normals: np.ndarray, poses: np.ndarray) -> np.ndarray:
        """The normalized scores (C,) of ``poses`` (C, 3) on the interpolated field."""
        return fit_scores(grid, xy, normals, poses)

    def response(self, grid: LikelihoodGrid, xy: np.ndarray, normals: np.ndarray, pose: np.ndarray,
                 window_m: float | None = None, window_rad: float | None = None) -> Match:
        """The response surface within the response window of ``pose`` (or the one given): its best pose, score
        and covariance (Olson 2009 §IV; the floor not included)."""
        o = self.options
        return correlative_match(grid, xy, normals, pose, o.response_m if window_m is None else window_m,
                                 o.response_rad if window_rad is None else window_rad, o.angle_step_rad)

    def fit(self, grid: LikelihoodGrid, xy: np.ndarray, normals: np.ndarray, start: np.ndarray) -> tuple[Match,
                                                                                                        np.ndarray]:
        """The response surface around a lattice pose ``start``, and its best pose refined off the lattice."""
        local = self.response(grid, xy, normals, start)
        return local, self.refine(grid, xy, normals, local.pose[None])[0]

    def weak(self, grid: LikelihoodGrid, pose: np.ndarray, xy: np.ndarray, normals: np.ndarray,
             covariance: np.ndarray) -> np.ndarray | None:
        """The world direction (2,) the points agreeing with the map at ``pose`` leave unfixed, or None."""
        return self.degeneracy.matched_weak(grid, pose, xy, normals, covariance)


def _options(cfg, levels: int, response_scale: float) -> MatcherOptions:
    f = cfg.front_end
    return MatcherOptions(levels, np.radians(f.angle_step_deg), response_scale * f.window_m,
                          np.radians(response_scale * f.window_deg), f.distinct_m, np.radians(f.distinct_deg),
                          f.refined_candidates, f.ambiguity_margin, f.lattice_allowance, f.floor_sigma_m,
                          f.floor_sigma_deg)


def front_end_matcher(cfg) -> ScanMatcher:
    """The front end's: a step's window, the response surface over ``front_end.window_m`` and ``window_deg``."""
    return ScanMatcher(_options(cfg, cfg.grid.branch_levels, 1.0), DegeneracyTest.from_config(cfg),
                       HeadingSearch.from_config(cfg.front_end))


def loop_matcher(cfg) -> ScanMatcher:
    """The loop closer's: its response surface twice the front end's window (a loop's drift is wider than a
    step's)."""
    return ScanMatcher(_options(cfg, cfg.grid.branch_levels, 2.0), DegeneracyTest.from_config(cfg),
                       HeadingSearch.from_config(cfg.front_end))


def relocalization_matcher(cfg) -> ScanMatcher:
    """Relocalization's: the loop closer's over the whole map, with ``relocalize_levels`` (a search that wide)."""
    return ScanMatcher(_options(cfg, cfg.loop_closure.relocalize_levels, 2.0), DegeneracyTest.from_config(cfg),
                       HeadingSearch.from_config(cfg.front_end))
