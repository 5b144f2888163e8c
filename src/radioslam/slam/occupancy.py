"""Occupancy grid by log-odds (Thrun, Burgard, Fox, *Probabilistic Robotics*, §9.2): every
point marks its cell occupied and the cells the ray from the terminal crosses before it
free. Rays are sampled at half a cell, vectorized over all points of all scans.

A radio beam is ~13° wide (issue #12, point 8): its echo at range r came from somewhere
across the beam at that range, not from the centre line, and beams beside it may have seen
an obstacle the centre line passes. So a ray clears free space only up to ``free_stop_m``
short of its echo, and never a cell that holds a point of any scan: what the points show
stays occupied.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from radioslam.slam.se2 import transform_points


@dataclass(frozen=True)
class OccupancyGrid:
    log_odds: np.ndarray  # (NX, NY), ix along x
    origin: np.ndarray  # (2,) world position of cell (0, 0)'s lower-left corner
    resolution: float

    @property
    def probability(self) -> np.ndarray:
        return 1.0 / (1.0 + np.exp(-self.log_odds))


@dataclass(frozen=True)
class RayCounts:
    """How many points lie in each cell, and how many rays cleared it (each ray counts a cell once; a
    cell holding a point of any of these scans is never cleared)."""

    hits: np.ndarray  # (NX, NY) points in each cell
    misses: np.ndarray  # (NX, NY) rays that crossed it
    origin: np.ndarray
    resolution: float

    def log_odds(self, cfg) -> np.ndarray:
        """The log-odds of the counts with the ``map`` settings: a cell hit is never cleared."""
        free = np.where(self.hits > 0, 0.0, cfg.log_odds_miss * self.misses.astype(np.float64))
        return np.clip(cfg.log_odds_hit * self.hits + free, -cfg.log_odds_limit, cfg.log_odds_limit)


def occupancy_grid(poses: np.ndarray, scans_xy: list[np.ndarray], cfg) -> OccupancyGrid:
    """Log-odds grid of terminal-frame scans (P_i, 2) seen from world ``poses`` (P, 3), with the
    settings of the ``map`` config section (:class:`~radioslam.slam.config.MapConfig`)."""
    counts = ray_counts(poses, scans_xy, cfg)
    return OccupancyGrid(counts.log_odds(cfg), counts.origin, counts.resolution)


def ray_counts(poses: np.ndarray, scans_xy: list[np.ndarray], cfg) -> RayCounts:
    """The hits and clearing rays of terminal-frame scans (P_i, 2) seen from ``poses`` (P, 3), on a grid
    of ``cfg.resolution_m`` spanning them with ``cfg.margin_m``."""
    resolution, margin = cfg.resolution_m, cfg.margin_m
    ends = [transform_points(p, xy) for p, xy in zip(poses, scans_xy)]
    starts = [np.broadcast_to(p[:2], e.shape) for p, e in zip(poses, ends)]
    end, start = np.concatenate(ends + [poses[:, :2]]), np.concatenate(starts + [poses[:, :2]])
    origin = np.minimum(end.min(axis=0), start.min(axis=0)) - margin
    shape = tuple(np.ceil((np.maximum(end.max(axis=0), start.max(axis=0)) + margin - origin) / resolution)
                  .astype(int) + 1)
    hits_count, misses_count = np.zeros(int(np.prod(shape)), np.int64), np.zeros(int(np.prod(shape)), np.int64)
    hits, rays = end[: len(end) - len(poses)], start[: len(end) - len(poses)]
    if len(hits):
        distance = np.linalg.norm(hits - rays, axis=1)
        length = np.maximum(distance - cfg.free_stop_m, 0.0)  # cleared up to free_stop_m short of the echo
        samples = np.ceil(length / (resolution / 2)).astype(int)
        ray = np.repeat(np.arange(len(hits)), samples)
        frac = (np.arange(samples.sum()) - np.repeat(np.cumsum(samples) - samples, samples)) / np.maximum(
            samples[ray], 1)
        direction = (hits - rays) / np.maximum(distance, 1e-12)[:, None]
        along = rays[ray] + (frac * length[ray])[:, None] * direction[ray]
        free = np.floor((along - origin) / resolution).astype(int)
        hit = np.ravel_multi_index(np.floor((hits - origin) / resolution).astype(int).T, shape)
        # a cell counts once per ray
        size = hits_count.size
        free_cells = np.unique(ray * size + np.ravel_multi_index(free.T, shape)) % size
        np.add.at(misses_count, free_cells, 1)
        np.add.at(hits_count, hit, 1)
    return RayCounts(hits_count.reshape(shape), misses_count.reshape(shape), origin, resolution)
