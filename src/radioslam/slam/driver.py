"""The SLAM driver (paper §IV-B): radio scans in, trajectory and loop closures out.

Main loop per scan, one step per comment. There is no odometry input: a
constant-velocity prediction seeds the front end's correlative search.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from radioslam.sensing.pointcloud import Scan
from radioslam.slam.branch_bound import BranchAndBound
from radioslam.slam.config import SlamConfig
from radioslam.slam.correlative import correlative_match
from radioslam.slam.degeneracy import matched_weak_direction, remap
from radioslam.slam.errors import SlamError
from radioslam.slam.grid import LikelihoodGrid
from radioslam.slam.loop_closure import BRANCH_LEVELS, LoopClosure, match_loop
from radioslam.slam.normals import specular_normals, wall_points
from radioslam.slam.pose_graph import PoseGraph, local_covariance
from radioslam.slam.refine import refine_pose
from radioslam.slam.se2 import between, compose
from radioslam.slam.submap import Submap, fused_points, submap_grid

# a skipped scan is tied to its neighbours by the constant-velocity model only, this loosely
SKIPPED_SIGMA = np.array([0.5, 0.5, np.radians(10.0)])
STRAIGHT_RAD = np.radians(2.0)  # a step turning less than this walks straight: the pace applies
FIRST_WINDOW_M, FIRST_WINDOW_DEG = 1.0, 20.0  # no velocity yet before the second scan


@dataclass
class SlamResult:
    poses: np.ndarray  # (P, 3) with loop closure and pose graph optimization
    odometry: np.ndarray  # (P, 3) front end only
    skipped: np.ndarray  # (P,) scans with too few points
    degenerate: np.ndarray  # (P,) matches that leave a direction unobserved (e.g. a featureless corridor)
    match_score: np.ndarray  # (P,) normalized front-end score, NaN where not matched
    untrusted: np.ndarray  # (P,) matches scored below min_match_score: the pose was predicted
    loops: list[LoopClosure] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    seconds_per_scan: np.ndarray = field(default_factory=lambda: np.zeros(0))


class RadioSlam:
    """Built from plain settings; ``loop_hook`` lets a test replace accepted loop closures."""

    def __init__(self, cfg: SlamConfig | None = None,
                 loop_hook: Callable[[LoopClosure], LoopClosure] | None = None):
        self.cfg = cfg or SlamConfig()
        self.loop_hook = loop_hook

    def run(self, scans: list[Scan]) -> SlamResult:
        cfg, n = self.cfg, len(scans)
        if not any(len(s) >= cfg.min_points for s in scans):
            raise SlamError(f"none of the {n} scans has {cfg.min_points} points or more: nothing to map",
                            field="(points)")
        res, sigma, nsig = cfg.resolution_m, cfg.sigma_m, np.radians(cfg.normal_sigma_deg)
        margin = max(cfg.window_m, cfg.loop_window_m) + 3 * sigma
        graph = PoseGraph()
        estimates: dict[int, np.ndarray] = {}
        points: dict[int, np.ndarray] = {}
        normals: dict[int, np.ndarray] = {}
        odometry = np.zeros((n, 3))
        odo_cov: dict[int, np.ndarray] = {}
        out = SlamResult(poses=np.zeros((n, 3)), odometry=odometry, skipped=np.zeros(n, bool),
                         degenerate=np.zeros(n, bool), match_score=np.full(n, np.nan), untrusted=np.zeros(n, bool))
        # the response surface is over-confident: the measured step errors are added to it
        step_floor = np.diag([cfg.odometry_sigma_m**2] * 2 + [np.radians(cfg.odometry_sigma_deg) ** 2])
        kept: list[int] = []
        submaps: list[Submap] = []
        matchers: dict[int, tuple[int, BranchAndBound]] = {}  # submap anchor → (graph version, matcher)
        velocity, last = None, None
        speeds: list[float] = []  # lengths of the straight steps whose matches observed every direction
        seconds = []
        for k, scan in enumerate(scans):
            tick = time.perf_counter()
            step = np.zeros(3) if velocity is None else velocity  # the constant-velocity motion
            # 1. a scan with too few points is skipped: the pose follows the constant-velocity model
            if len(scan) < cfg.min_points:
                out.skipped[k] = True
                out.warnings.append(f"scan {k}: {len(scan)} points (< {cfg.min_points}), skipped")
                estimates[k] = np.zeros(3) if last is None else compose(estimates[last], step)
                odometry[k] = np.zeros(3) if last is None else compose(odometry[last], step)
                graph.add_pose(k, estimates[k])
                if last is not None:
                    graph.add_odometry(last, k, step, np.diag(SKIPPED_SIGMA**2))
                last = k
                seconds.append(time.perf_counter() - tick)
                continue
            phi = specular_normals(scan)
            xy = wall_points(scan, phi) if cfg.project_arcs else scan.xy
            if not kept:
                # the first scan defines the map frame
                estimates[k] = np.zeros(3) if last is None else estimates[last]
                odometry[k] = estimates[k]
                graph.add_pose(k, estimates[k])
                if last is not None:
                    graph.add_odometry(last, k, np.zeros(3), np.diag(SKIPPED_SIGMA**2))
            else:
                # 2. predict with constant velocity
                prediction = compose(estimates[last], step)
                # 3. match against the local map of the latest scans: coarse correlative search, then refine
                local_keys = kept[-cfg.local_map_scans:]
                map_xy, map_n = fused_points(local_keys, estimates, points, normals, np.zeros(3))
                grid = LikelihoodGrid.from_points(map_xy, res, sigma, margin + FIRST_WINDOW_M, map_n, nsig,
                                                  cfg.plane_reach_m)
                pose, cov, score = self._front_end(grid, xy, phi, prediction, first=velocity is None)
                cov = cov + step_floor
                out.match_score[k] = score
                if score < cfg.min_match_score:
                    # 3b. a match the map barely supports (a new view, most points unmapped) is not trusted
                    out.untrusted[k] = True
                    pose, cov = prediction, np.diag(SKIPPED_SIGMA**2)
                    out.warnings.append(f"scan {k}: match score {score:.2f} < {cfg.min_match_score:.2f}, "
                                        "pose predicted instead")
                # 4. a direction the walls cannot fix keeps the prediction there (Zhang et al. 2016)
                weak = None if out.untrusted[k] else matched_weak_direction(grid, pose, xy, phi, cov,
                                                                             cfg.degenerate_ratio)
                if weak is not None:
                    out.degenerate[k] = True
                    paced = pace_prediction(prediction, estimates[last], speeds if abs(step[2]) < STRAIGHT_RAD else [],
                                            cfg.pace_scans)
                    pose, cov = remap(pose, cov, paced, weak, SKIPPED_SIGMA[0])
                    out.warnings.append(f"scan {k}: degenerate match, nothing fixes the position along "
                                        f"{np.degrees(np.arctan2(weak[1], weak[0])):.0f}° (predicted instead)")
                # 5. odometry factor from the previous pose
                rel = between(estimates[last], pose)
                odo_cov[k] = local_covariance(cov, estimates[last][2])
                graph.add_pose(k, pose)
                graph.add_odometry(last, k, rel, odo_cov[k])
                odometry[k] = compose(odometry[last], rel)
                velocity = rel if not out.skipped[last] else None
                if not (out.degenerate[k] or out.untrusted[k]) and abs(rel[2]) < STRAIGHT_RAD:
                    speeds.append(float(np.linalg.norm(rel[:2])))
                estimates[k] = pose
            points[k], normals[k] = xy, phi
            kept.append(k)
            # 6. submaps of N consecutive scans
            if not submaps or len(submaps[-1].keys) >= cfg.submap_scans:
                submaps.append(Submap())
            submaps[-1].keys.append(k)
            # 7. loop closure against older submaps near the current pose (a degenerate scan cannot close one)
            found = [] if out.degenerate[k] else self._close_loops(k, submaps, estimates, points, normals, odo_cov,
                                                                   kept, margin, matchers, graph.version)
            for loop in found:
                loop = self.loop_hook(loop) if self.loop_hook else loop
                graph.add_loop(loop.anchor, loop.key, loop.relative, loop.covariance)
                out.loops.append(loop)
            # 8. optimize the pose graph whenever loops were added
            if found:
                estimates.update(graph.optimize(cfg.gnc))
            last = k
            seconds.append(time.perf_counter() - tick)
        if out.loops:
            estimates.update(graph.optimize(cfg.gnc))
        out.poses = np.array([estimates[k] for k in range(n)])
        out.seconds_per_scan = np.array(seconds)
        return out

    def _front_end(self, grid, xy, phi, prediction, first: bool):
        cfg = self.cfg
        step = np.radians(cfg.angle_step_deg)
        window, turn = cfg.window_m, np.radians(cfg.window_deg)
        match = None if first else correlative_match(grid, xy, phi, prediction, window, turn, step)
        if match is None or match.at_edge:
            # no velocity yet, or the motion left the window (a turn begins): a wide exact search first
            found = BranchAndBound(grid, BRANCH_LEVELS).match(xy, phi, prediction, FIRST_WINDOW_M,
                                                               np.radians(FIRST_WINDOW_DEG), step, 0.0)
            start = found.pose if found.pose is not None else prediction
            match = correlative_match(grid, xy, phi, start, window, turn, step)
        pose = refine_pose(grid, xy, phi, match.pose, cfg.resolution_m, step)
        return pose, match.covariance, match.score

    def _close_loops(self, k, submaps, estimates, points, normals, odo_cov, kept, margin, matchers,
                     version) -> list[LoopClosure]:
        cfg = self.cfg
        current = estimates[k]
        found = []
        for s in submaps[:max(0, len(submaps) - 1 - cfg.loop_skip_submaps)]:
            members = np.array([estimates[m][:2] for m in s.keys])
            if np.min(np.linalg.norm(members - current[:2], axis=1)) > cfg.loop_radius_m:
                continue
            if matchers.get(s.anchor, (None,))[0] != version:  # built once per pose graph solution
                grid = submap_grid(s, estimates, points, normals, cfg.resolution_m, cfg.sigma_m, margin,
                                   np.radians(cfg.normal_sigma_deg), cfg.plane_reach_m)
                matchers[s.anchor] = (version, BranchAndBound(grid, BRANCH_LEVELS))
            predicted = between(estimates[s.anchor], current)
            drift = drift_covariance(odo_cov, [m for m in kept if s.anchor < m <= k],
                                     np.linalg.norm(predicted[:2]))
            loop = match_loop(matchers[s.anchor][1], points[k], normals[k], predicted, drift, cfg, s.anchor, k)
            if loop is not None:
                found.append(loop)
        return found


def pace_prediction(prediction: np.ndarray, last: np.ndarray, speeds: list[float], scans: int) -> np.ndarray:
    """``prediction`` moved along its own direction of travel from ``last`` so that the step is
    the median of the last ``scans`` observed step lengths ``speeds``: the walker's pace."""
    travel = prediction[:2] - last[:2]
    length = float(np.linalg.norm(travel))
    if not speeds or length < 1e-9:
        return prediction
    paced = prediction.copy()
    paced[:2] = last[:2] + travel * (float(np.median(speeds[-scans:])) / length)
    return paced


def drift_covariance(odo_cov: dict[int, np.ndarray], keys: list[int], distance: float) -> np.ndarray:
    """First-order drift between two poses: the odometry covariances summed, the heading's
    variance also spreading the position by the distance between them."""
    total = sum((odo_cov[m] for m in keys if m in odo_cov), np.zeros((3, 3)))
    total = total + np.diag([total[2, 2] * distance**2] * 2 + [0.0])
    return total

