"""The SLAM driver (paper §IV-B): radio scans in, trajectory, statuses and loop closures out, by
feeding a :class:`~radioslam.slam.session.SlamSession` every scan of a recorded walk."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from radioslam.progress import SILENT, Progress
from radioslam.sensing.pointcloud import Scan
from radioslam.slam.config import SlamConfig
from radioslam.slam.errors import SlamError
from radioslam.slam.loop_closer import LoopClosure
from radioslam.slam.result import SlamResult
from radioslam.slam.session import SlamSession


class RadioSlam:
    """Built from plain settings; ``loop_hook`` lets a test replace accepted loop closures;
    ``odometry`` (P, 3) are external odometry poses (their steps become between factors)."""

    def __init__(self, cfg: SlamConfig | None = None,
                 loop_hook: Callable[[LoopClosure], LoopClosure] | None = None):
        self.cfg = cfg or SlamConfig()
        self.loop_hook = loop_hook

    def run(self, scans: list[Scan], odometry: np.ndarray | None = None, progress: Progress = SILENT) -> SlamResult:
        cfg = self.cfg
        if not any(len(s) >= cfg.scan.min_points for s in scans):
            raise SlamError(f"none of the {len(scans)} scans has {cfg.scan.min_points} points or more: "
                            "nothing to map", field="(points)")
        if odometry is not None and len(odometry) != len(scans):
            raise SlamError(f"{len(odometry)} odometry poses for {len(scans)} scans", field="(odometry)")
        session = SlamSession(cfg, self.loop_hook, odometry)
        progress.start("SLAM", len(scans))
        for scan in scans:
            session.add(scan)
            progress.advance()
        return session.finish()
