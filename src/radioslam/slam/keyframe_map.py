"""The SLAM's map of keyframes (issue #47, point 5; Cartographer's scans grouped into submaps, Hess, Kohler, Rapp,
Andor, "Real-time loop closure in 2D LIDAR SLAM", ICRA 2016, §IV): every scan that was not skipped, with its
matchable points (:class:`~radioslam.slam.scan_points.ScanPoints`), in the order it came, and the submaps of
``submap_scans`` consecutive keyframes that loop closure matches against. It is updated by insertion alone, and
held by the front end, the loop closer and the session alike (one store of the scans, not one per component).
The poses are the pose graph's latest solution, passed to its views: the keyframes before a scan, and the
likelihood field of any of them at those poses (:func:`radioslam.slam.scan_points.map_grid`)."""

from __future__ import annotations

import numpy as np

from radioslam.slam.config import GridConfig
from radioslam.slam.grid import LikelihoodGrid
from radioslam.slam.scan_points import ScanPoints, map_grid
from radioslam.slam.submap import Submap


class KeyframeMap:
    """Built from the number of keyframes per submap."""

    def __init__(self, submap_scans: int):
        self.submap_scans = submap_scans
        self.points: dict[int, ScanPoints] = {}  # keyframe → its points, normals, free space and sightings
        self.keys: list[int] = []  # the keyframes, oldest first
        self.submaps: list[Submap] = []

    @classmethod
    def from_config(cls, cfg) -> "KeyframeMap":
        return cls(cfg.loop_closure.submap_scans)

    def insert(self, k: int, points: ScanPoints) -> None:
        """Scan k becomes a keyframe and joins the current submap (a new one every ``submap_scans`` keyframes)."""
        if not self.submaps or len(self.submaps[-1].keys) >= self.submap_scans:
            self.submaps.append(Submap())
        self.submaps[-1].keys.append(k)
        self.keys.append(k)
        self.points[k] = points

    def __len__(self) -> int:
        return len(self.keys)

    def before(self, k: int, before: int | None = None) -> list[int]:
        """Every keyframe other than k (and before ``before``), oldest first."""
        return [m for m in self.keys if m != k and (before is None or m < before)]

    def grid(self, keys: list[int], poses: dict[int, np.ndarray], cfg: GridConfig,
             observed: bool = False) -> tuple[LikelihoodGrid, np.ndarray]:
        """The likelihood field of the keyframes ``keys`` at ``poses`` with the free space they saw, and their points'
        world normals (``observed``: also the space they observed, for the measurement model)."""
        return map_grid(keys, poses, self.points, cfg, observed)
