"""Occupancy grid by log-odds (Thrun, Burgard, Fox, *Probabilistic Robotics*, §9.2): every
point marks its cell occupied and the cells the ray from the terminal crosses before it
free. Rays are sampled at half a cell, vectorized over all points of all scans.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from radioslam.slam.se2 import transform_points

LOG_ODDS_HIT = 0.85  # p = 0.7
LOG_ODDS_MISS = -0.4  # p = 0.4
LOG_ODDS_LIMIT = 5.0


@dataclass(frozen=True)
class OccupancyGrid:
    log_odds: np.ndarray  # (NX, NY), ix along x
    origin: np.ndarray  # (2,) world position of cell (0, 0)'s lower-left corner
    resolution: float

    @property
    def probability(self) -> np.ndarray:
        return 1.0 / (1.0 + np.exp(-self.log_odds))


def occupancy_grid(poses: np.ndarray, scans_xy: list[np.ndarray], resolution: float,
                   margin: float = 0.5) -> OccupancyGrid:
    """Log-odds grid of terminal-frame scans (P_i, 2) seen from world ``poses`` (P, 3)."""
    ends = [transform_points(p, xy) for p, xy in zip(poses, scans_xy)]
    starts = [np.broadcast_to(p[:2], e.shape) for p, e in zip(poses, ends)]
    end, start = np.concatenate(ends + [poses[:, :2]]), np.concatenate(starts + [poses[:, :2]])
    origin = np.minimum(end.min(axis=0), start.min(axis=0)) - margin
    shape = np.ceil((np.maximum(end.max(axis=0), start.max(axis=0)) + margin - origin) / resolution).astype(int) + 1
    log_odds = np.zeros(shape)
    hits, rays = end[: len(end) - len(poses)], start[: len(end) - len(poses)]
    if len(hits):
        length = np.linalg.norm(hits - rays, axis=1)
        samples = np.ceil(length / (resolution / 2)).astype(int)
        ray = np.repeat(np.arange(len(hits)), samples)
        frac = (np.arange(samples.sum()) - np.repeat(np.cumsum(samples) - samples, samples)) / samples[ray]
        along = rays[ray] + frac[:, None] * (hits[ray] - rays[ray])
        free = np.floor((along - origin) / resolution).astype(int)
        hit = np.floor((hits - origin) / resolution).astype(int)
        # a cell counts once per ray, and the hit cell is never also free on its own ray
        free_flat = np.unique(ray * log_odds.size + np.ravel_multi_index(free.T, shape))
        hit_flat = np.arange(len(hits)) * log_odds.size + np.ravel_multi_index(hit.T, shape)
        free_flat = np.setdiff1d(free_flat, hit_flat, assume_unique=True)
        np.add.at(log_odds.reshape(-1), free_flat % log_odds.size, LOG_ODDS_MISS)
        np.add.at(log_odds.reshape(-1), hit_flat % log_odds.size, LOG_ODDS_HIT)
    return OccupancyGrid(np.clip(log_odds, -LOG_ODDS_LIMIT, LOG_ODDS_LIMIT), origin, resolution)
