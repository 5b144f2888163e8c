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


def occupancy_grid(poses: np.ndarray, scans_xy: list[np.ndarray], cfg) -> OccupancyGrid:
    """Log-odds grid of terminal-frame scans (P_i, 2) seen from world ``poses`` (P, 3), with the
    settings of the ``map`` config section (:class:`~radioslam.slam.config.MapConfig`)."""
    resolution, margin = cfg.resolution_m, cfg.margin_m
    ends = [transform_points(p, xy) for p, xy in zip(poses, scans_xy)]
    starts = [np.broadcast_to(p[:2], e.shape) for p, e in zip(poses, ends)]
    end, start = np.concatenate(ends + [poses[:, :2]]), np.concatenate(starts + [poses[:, :2]])
    origin = np.minimum(end.min(axis=0), start.min(axis=0)) - margin
    shape = np.ceil((np.maximum(end.max(axis=0), start.max(axis=0)) + margin - origin) / resolution).astype(int) + 1
    log_odds = np.zeros(shape)
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
        # a cell counts once per ray; a cell holding any scan's point is never cleared
        free_flat = np.unique(ray * log_odds.size + np.ravel_multi_index(free.T, shape))
        free_cells = free_flat % log_odds.size
        free_cells = free_cells[~np.isin(free_cells, hit)]
        np.add.at(log_odds.reshape(-1), free_cells, cfg.log_odds_miss)
        np.add.at(log_odds.reshape(-1), hit, cfg.log_odds_hit)
    return OccupancyGrid(np.clip(log_odds, -cfg.log_odds_limit, cfg.log_odds_limit), origin, resolution)
