"""Submaps: N consecutive scans fused in the frame of the first (MATLAB lidarSLAM and
Cartographer both close loops against such submaps rather than single scans)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from radioslam.slam.se2 import between, transform_points


@dataclass
class Submap:
    keys: list[int] = field(default_factory=list)  # scan indices, the first is the anchor

    @property
    def anchor(self) -> int:
        return self.keys[0]


def fused_points(keys: list[int], poses: dict[int, np.ndarray], points: dict[int, np.ndarray],
                 normals: dict[int, np.ndarray], frame: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The scans' points (P, 2) and world-frame normals (P,) in the frame of the pose ``frame``."""
    rel = [between(frame, poses[k]) for k in keys]
    xy = np.concatenate([transform_points(r, points[k]) for r, k in zip(rel, keys)])
    nrm = np.concatenate([normals[k] + r[2] for r, k in zip(rel, keys)])
    return xy, nrm
