"""Radio point cloud of one pose (paper §IV-A).

The 4 orientations are already stitched: every beam carries its terminal-frame
angle (orientation k·π/2 plus arcsin(2ϑ_i)). Detections are normalized by the
scan's peak energy and those below the threshold (−13 dB by default) are dropped as
sidelobe returns (the paper's rule), and (angle, range) becomes terminal-frame x, y.

The paper's rule compares every detection with the scan's strongest, which in a
corridor is a side wall 2 m away: a wall 8 m away echoes 12 dB less (spreading
alone, 20·log10(8/2)), so the walls that fix the position along the corridor drop
out. A beam sidelobe of an echo arrives at that echo's range, though, so
:func:`same_range_points` applies the threshold per range: a detection is dropped
when a detection within one range cell of it is more than |threshold| stronger, or
when it is below the floor (the two-way beam sidelobe level, −25.6 dB for 8
elements) relative to the scan's peak.
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


def same_range_points(range_m: np.ndarray, rel_db: np.ndarray, valid: np.ndarray, threshold_db: float,
                      floor_db: float, cell_m: float) -> np.ndarray:
    """Mask (B, M) of the valid detections within ``threshold_db`` of the strongest valid detection
    within ``cell_m`` of their range, and within ``floor_db`` of the scan's peak (``rel_db`` is
    relative to it)."""
    r, p = range_m[valid], rel_db[valid]
    near = np.abs(r[:, None] - r[None, :]) <= cell_m  # (N, N), N ≤ beams × peaks
    strongest_near = np.where(near, p[None, :], -np.inf).max(axis=1)
    keep = np.zeros_like(valid)
    keep[valid] = (p - strongest_near >= threshold_db) & (p >= floor_db)
    return keep


def build_scan(range_m: np.ndarray, power: np.ndarray, valid: np.ndarray, beam_angle: np.ndarray,
               beam_index: np.ndarray, orientation: np.ndarray, threshold_db: float,
               floor_db: float | None = None, cell_m: float = 0.0) -> Scan:
    """Points from detections (B, M): keep valid ones within ``threshold_db`` of the scan's peak or,
    with a ``floor_db``, of the strongest detection at their range (:func:`same_range_points`)."""
    if not valid.any():
        return Scan.empty()
    peak = power[valid].max()
    rel = 10.0 * np.log10(np.maximum(power, 1e-300) / peak)
    keep = (valid & (rel >= threshold_db) if floor_db is None else
            same_range_points(range_m, rel, valid, threshold_db, floor_db, cell_m))
    rows, _ = np.nonzero(keep)
    return Scan(range_m[keep], beam_angle[rows], rel[keep], beam_index[rows].astype(np.int64),
                orientation[rows].astype(np.int64))
