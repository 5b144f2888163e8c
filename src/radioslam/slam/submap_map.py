"""The map kept up to date scan by scan (issue #14), as Cartographer keeps it (Hess, Kohler, Rapp,
Andor, "Real-time loop closure in 2D LIDAR SLAM", ICRA 2016, §IV): each scan joins its submap in the
frame of the submap's first scan, with its pose relative to that scan when it came; a submap is fixed
once full, and its hits and clearing rays (:func:`radioslam.slam.occupancy.ray_counts`) counted once,
the first time the map is asked for. A scan therefore costs the same whatever the map's
size (and nothing more where nobody asks); the world map is composed on request from the submaps at
their first scans' latest poses, so it follows every pose-graph solution without rebuilding a submap.

The composition sums the submaps' counts into the world cells (nearest cell) and applies the same rule
as the map written after a run (a cell any scan hit is never cleared); that map (``map.pgm``, one grid
from every scan at its final pose) stays the exact one: this is the live view, its cells placed with
each submap's scans where they were relative to its first when they came.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from radioslam.slam.config import MapConfig
from radioslam.slam.occupancy import OccupancyGrid, RayCounts, ray_counts
from radioslam.slam.se2 import between, inverse, transform_points


@dataclass
class _Part:
    anchor: int
    poses: list[np.ndarray] = field(default_factory=list)  # each scan's pose in the anchor's frame, when it came
    scans: list[np.ndarray] = field(default_factory=list)  # each scan's points (terminal frame)
    counts: RayCounts | None = None  # once full (a later submap begun) and asked for

    def ray_counts(self, cfg: MapConfig, full: bool) -> RayCounts:
        if self.counts is not None:
            return self.counts
        counts = ray_counts(np.array(self.poses), self.scans, cfg)
        counts = RayCounts(counts.hits.astype(np.uint16), counts.misses.astype(np.uint16), counts.origin,
                           counts.resolution)  # a submap's few scans count far below 65,535 a cell
        if full:
            self.counts = counts
        return counts


class SubmapMap:
    def __init__(self, cfg: MapConfig):
        self.cfg = cfg
        self.parts: list[_Part] = []

    def add(self, k: int, xy: np.ndarray, anchor: int, estimates: dict[int, np.ndarray]) -> None:
        """Scan k (its points ``xy``, terminal frame) at its pose in ``estimates`` joins the submap whose
        first scan is ``anchor`` (the loop closer's: one grouping of the scans); a new anchor starts a
        submap and leaves the one before full."""
        if not self.parts or self.parts[-1].anchor != anchor:
            self.parts.append(_Part(anchor))
        part = self.parts[-1]
        part.poses.append(between(estimates[anchor], estimates[k]))
        part.scans.append(np.asarray(xy, dtype=np.float64).reshape(-1, 2))

    def grid(self, estimates: dict[int, np.ndarray]) -> OccupancyGrid | None:
        """The world occupancy grid: every submap's hits and clearing rays placed at its first scan's latest
        pose (nearest cell), summed, then their log-odds; None before the first scan."""
        if not self.parts:
            return None
        grids = [(part.ray_counts(self.cfg, full=part is not self.parts[-1]), estimates[part.anchor])
                 for part in self.parts]
        corners = np.concatenate([transform_points(pose, _corners(g)) for g, pose in grids])
        resolution = self.cfg.resolution_m
        origin = corners.min(axis=0)
        shape = tuple(np.ceil((corners.max(axis=0) - origin) / resolution).astype(int) + 1)
        centres = origin + (np.stack(np.meshgrid(np.arange(shape[0]), np.arange(shape[1]), indexing="ij"), -1)
                            + 0.5) * resolution
        hits, misses = np.zeros(int(np.prod(shape)), np.int64), np.zeros(int(np.prod(shape)), np.int64)
        for g, pose in grids:  # one vectorized resampling per submap (a submap holds many scans)
            local = transform_points(inverse(pose), centres.reshape(-1, 2))
            cells = np.floor((local - g.origin) / g.resolution).astype(np.int64)
            inside = np.flatnonzero(np.all((cells >= 0) & (cells < g.hits.shape), axis=1))
            hits[inside] += g.hits[cells[inside, 0], cells[inside, 1]]
            misses[inside] += g.misses[cells[inside, 0], cells[inside, 1]]
        total = RayCounts(hits.reshape(shape), misses.reshape(shape), origin, resolution)
        return OccupancyGrid(total.log_odds(self.cfg), origin, resolution)


def _corners(grid: RayCounts) -> np.ndarray:
    size = np.array(grid.hits.shape) * grid.resolution
    return grid.origin + np.array([[0.0, 0.0], [size[0], 0.0], [0.0, size[1]], size])

