"""Radio point cloud of one pose (paper §IV-A).

The 4 orientations are already stitched: every beam carries its terminal-frame
angle (orientation k·π/2 plus arcsin(2ϑ_i)). Detections are normalized by the
scan's peak energy, those below the threshold (−13 dB by default) are dropped as
sidelobe returns, and (angle, range) becomes terminal-frame x, y.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Scan:
    """Points (P,) in the terminal frame of one pose."""

    range_m: np.ndarray
    angle_rad: np.ndarray
    power_db: np.ndarray  # relative to the scan's strongest detection
    beam: np.ndarray  # codebook index i of the beam that saw the point
    orientation: np.ndarray  # array orientation k

    def __len__(self) -> int:
        return len(self.range_m)

    @property
    def xy(self) -> np.ndarray:
        return np.stack([self.range_m * np.cos(self.angle_rad), self.range_m * np.sin(self.angle_rad)], axis=1)

    @classmethod
    def empty(cls) -> "Scan":
        z = np.zeros(0)
        return cls(z, z, z, z.astype(np.int64), z.astype(np.int64))


def build_scan(range_m: np.ndarray, power: np.ndarray, valid: np.ndarray, beam_angle: np.ndarray,
               beam_index: np.ndarray, orientation: np.ndarray, threshold_db: float) -> Scan:
    """Points from detections (B, M): keep valid ones within ``threshold_db`` of the scan's peak."""
    if not valid.any():
        return Scan.empty()
    peak = power[valid].max()
    rel = 10.0 * np.log10(np.maximum(power, 1e-300) / peak)
    keep = valid & (rel >= threshold_db)
    rows, _ = np.nonzero(keep)
    return Scan(range_m[keep], beam_angle[rows], rel[keep], beam_index[rows].astype(np.int64),
                orientation[rows].astype(np.int64))
