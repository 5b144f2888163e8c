"""A radio scan as the matchers see it (paper §IV-A): terminal-frame points, the specular normal
of the arc each came from (:mod:`radioslam.slam.normals`), and the free space the scan shows
(:mod:`radioslam.slam.free_space`), computed once per scan for the front end and the loop closer."""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from functools import cached_property

import numpy as np

from radioslam.sensing.pointcloud import Scan
from radioslam.slam.config import GridConfig, ScanConfig
from radioslam.slam.free_space import free_samples, seen_samples
from radioslam.slam.grid import LikelihoodGrid, field_reach
from radioslam.slam.normals import echo_weights, specular_arcs
from radioslam.slam.se2 import between, transform_points

SEEN_SPACING_M = 0.2  # the observed space's samples: a beam is ~13° wide, 0.2 m across at 1 m


@dataclass(frozen=True)
class ScanPoints:
    xy: np.ndarray  # (P, 2)
    normals: np.ndarray  # (P,) NaN: no normal known
    free: np.ndarray  # (F, 2) terminal-frame samples of the space the scan saw through
    sightings: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))  # (A, 2) bearing, range of each arc's wall
    weights: np.ndarray | None = None  # (P,) each point's share of one independent observation; None: 1 each

    @property
    def seen(self) -> np.ndarray:
        """(S, 2) samples of the space the scan observed (derived from its points when asked: only the
        measurement model reads them, and a long walk need not keep them)."""
        return seen_samples(self.xy, SEEN_SPACING_M)

    @cached_property
    def observation_weights(self) -> np.ndarray:
        """(P,) what each point counts for in a log-likelihood (:mod:`radioslam.slam.measurement`)."""
        return np.ones(len(self.xy)) if self.weights is None else self.weights

    def __len__(self) -> int:
        return len(self.xy)

    @cached_property
    def reach(self) -> float:
        """How far from the terminal its points and free samples lie, at most."""
        return float(np.sqrt(max(np.max(np.sum(self.xy**2, axis=1), initial=0.0),
                                 np.max(np.sum(self.free**2, axis=1), initial=0.0))))


def prepare_points(scan: Scan, cfg: ScanConfig, grid: GridConfig) -> ScanPoints:
    """The scan's points with their specular normals, its free-space samples (half a cell apart) and
    the sightings of the walls its specular arcs face."""
    phi, sightings = specular_arcs(scan, cfg.arc_range_m, np.radians(cfg.seam_gap_deg))
    return ScanPoints(scan.xy, phi, free_samples(scan.xy, phi, grid.free_stop_m, grid.free_pose_radius_m,
                                            grid.resolution_m / 2), sightings, echo_weights(scan, cfg.arc_range_m))


def fused_points(keys: list[int], poses: dict[int, np.ndarray], scans: dict[int, ScanPoints],
                 frame: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The scans' points (P, 2) and world-frame normals (P,) in the frame of the pose ``frame``."""
    rel = [between(frame, poses[k]) for k in keys]
    xy = np.concatenate([transform_points(r, scans[k].xy) for r, k in zip(rel, keys)])
    nrm = np.concatenate([scans[k].normals + r[2] for r, k in zip(rel, keys)])
    return xy, nrm


def fused_free(keys: list[int], poses: dict[int, np.ndarray], scans: dict[int, ScanPoints]) -> np.ndarray:
    """The scans' free-space samples (F, 2) in the world frame."""
    return _in_world(keys, poses, [scans[k].free for k in keys])


def fused_seen(keys: list[int], poses: dict[int, np.ndarray], scans: dict[int, ScanPoints]) -> np.ndarray:
    """(S, 2) world samples of the space the scans observed, at ``poses``."""
    return _in_world(keys, poses, [scans[k].seen for k in keys])


def _in_world(keys: list[int], poses: dict[int, np.ndarray], samples: list[np.ndarray]) -> np.ndarray:
    return np.concatenate([transform_points(poses[k], a) for k, a in zip(keys, samples)] or [np.zeros((0, 2))])


def viewpoints(keys: list[int], poses: dict[int, np.ndarray], scans: dict[int, ScanPoints]) -> np.ndarray:
    """(J, 3) each scan's world position and reach (its farthest echo or free sample)."""
    return np.array([[poses[k][0], poses[k][1], scans[k].reach] for k in keys]).reshape(-1, 3)


def map_grid(keys: list[int], poses: dict[int, np.ndarray], scans: dict[int, ScanPoints], g: GridConfig,
             observed: bool = False) -> tuple[LikelihoodGrid, np.ndarray]:
    """The likelihood field of the scans ``keys`` at ``poses`` (world frame), with their free space, and the
    map points' world normals; ``observed``: also the space they observed and their viewpoints (what the
    measurement model, :mod:`radioslam.slam.measurement`, tells unseen space by)."""
    xy, normals = fused_points(keys, poses, scans, np.zeros(3))
    grid = LikelihoodGrid.from_points(xy, g.resolution_m, g.sigma_m, field_reach(g.sigma_m, g.resolution_m,
                                                                                 g.plane_reach_m),
                                      normals, np.radians(g.normal_sigma_deg), g.plane_reach_m,
                                      fused_free(keys, poses, scans), g.free_penalty,
                                      fused_seen(keys, poses, scans) if observed else None)
    if observed:
        grid = replace(grid, viewpoints=viewpoints(keys, poses, scans))
    return grid, normals
