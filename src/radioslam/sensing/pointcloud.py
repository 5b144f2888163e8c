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

With elevation beams (issue #16) each elevation row j of the codebook is a flat
scan of its own: the rule runs per row, relative to that row's strongest
detection (so the floor's strong near returns on the low rows do not drop the
walls of the horizontal one), and a point's elevation is its beam's. The
horizontal row (j = 0) is :meth:`Scan.horizontal`, the slice the SE(2) SLAM reads:
exactly the flat scan's points.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np


@dataclass(frozen=True)
class Scan:
    """Points (P,) in the terminal frame of one pose."""

    range_m: np.ndarray  # slant range from the arrays' centre
    angle_rad: np.ndarray  # azimuth
    power_db: np.ndarray  # relative to the strongest detection of the point's elevation row
    beam: np.ndarray  # codebook index i of the beam that saw the point
    orientation: np.ndarray  # array orientation k
    elevation_rad: np.ndarray | None = None  # elevation of the beam that saw it; None: 0 (a flat scan)
    elevation_beam: np.ndarray | None = None  # elevation codebook index j of that beam; None: 0

    def __post_init__(self) -> None:
        for name, dtype in (("elevation_rad", np.float64), ("elevation_beam", np.int64)):
            if getattr(self, name) is None:
                object.__setattr__(self, name, np.zeros(len(self.range_m), dtype))

    def __len__(self) -> int:
        return len(self.range_m)

    @property
    def xy(self) -> np.ndarray:
        """Terminal-frame x, y: the points projected on the horizontal plane."""
        ground = self.range_m * np.cos(self.elevation_rad)
        return np.stack([ground * np.cos(self.angle_rad), ground * np.sin(self.angle_rad)], axis=1)

    @property
    def z(self) -> np.ndarray:
        """Height above the arrays' centre."""
        return self.range_m * np.sin(self.elevation_rad)

    @property
    def xyz(self) -> np.ndarray:
        return np.column_stack([self.xy, self.z])

    def select(self, rows: np.ndarray) -> "Scan":
        """The points of ``rows`` (a mask or indices)."""
        return Scan(*(getattr(self, f.name)[rows] for f in fields(self)))

    def horizontal(self) -> "Scan":
        """The horizontal elevation row's points (j = 0): what the SE(2) SLAM reads."""
        return self if not self.elevation_beam.any() else self.select(self.elevation_beam == 0)

    @classmethod
    def concatenate(cls, scans: list["Scan"]) -> "Scan":
        if not scans:
            return cls.empty()
        return cls(*(np.concatenate([getattr(s, f.name) for s in scans]) for f in fields(cls)))

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
               floor_db: float | None = None, cell_m: float = 0.0, beam_elevation: np.ndarray | None = None,
               elevation_index: np.ndarray | None = None) -> Scan:
    """Points from detections (B, M): keep valid ones within ``threshold_db`` of the scan's peak or,
    with a ``floor_db``, of the strongest detection at their range (:func:`same_range_points`); with
    elevation beams (``elevation_index`` (B,) not all 0), row by row. ``beam_angle`` and
    ``beam_elevation`` are per beam (B,) or per detection (B, M) (estimated between the rows)."""
    if elevation_index is not None and np.any(elevation_index != 0):
        rows = [np.flatnonzero(elevation_index == j) for j in np.unique(elevation_index)]  # a few rows
        return Scan.concatenate([_row_scan(range_m[r], power[r], valid[r], beam_angle[r], beam_index[r],
                                           orientation[r], threshold_db, floor_db, cell_m, beam_elevation[r],
                                           elevation_index[r]) for r in rows])
    return _row_scan(range_m, power, valid, beam_angle, beam_index, orientation, threshold_db, floor_db, cell_m)


def _row_scan(range_m, power, valid, beam_angle, beam_index, orientation, threshold_db, floor_db, cell_m,
              beam_elevation=None, elevation_index=None) -> Scan:
    if not valid.any():
        return Scan.empty()
    peak = power[valid].max()
    rel = 10.0 * np.log10(np.maximum(power, 1e-300) / peak)
    keep = (valid & (rel >= threshold_db) if floor_db is None else
            same_range_points(range_m, rel, valid, threshold_db, floor_db, cell_m))
    rows, _ = np.nonzero(keep)

    def per_point(a):  # a per-beam (B,) or a per-detection (B, M) array at the kept points
        return None if a is None else (a[keep] if a.ndim == 2 else a[rows])

    return Scan(range_m[keep], per_point(beam_angle), rel[keep], beam_index[rows].astype(np.int64),
                orientation[rows].astype(np.int64), per_point(beam_elevation),
                None if elevation_index is None else elevation_index[rows].astype(np.int64))
