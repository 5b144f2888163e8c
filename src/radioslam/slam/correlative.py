"""Exhaustive correlative scan matching and its covariance from the response surface
(Olson, "Real-time correlative scan matching", ICRA 2009, §III–IV).

Every candidate (θ, x, y) on a grid around a prediction is scored at once: rotate
the scan by each θ, then shift its cells by every integer offset. The scan's
log-likelihood ℓ = Σ_p log max(L(p), L_floor) picks the best candidate and, read as
a posterior over the candidates, gives the covariance (Olson §IV): with
w_i ∝ exp(ℓ_i − ℓ_max), Σ = Σ_i w_i (x_i − μ)(x_i − μ)ᵀ / Σ_i w_i. The score
reported is the mean likelihood of the points, normalized to [0, 1].
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from radioslam.slam.grid import LIKELIHOOD_FLOOR, LikelihoodGrid, phasors
from radioslam.slam.se2 import rotation


@dataclass(frozen=True)
class Match:
    """A scan's pose in the grid's frame, its normalized score and covariance (x, y, θ)."""

    pose: np.ndarray
    score: float
    covariance: np.ndarray
    at_edge: bool = False  # the best candidate lies on the window's border


def heading_cells(grid: LikelihoodGrid, points: np.ndarray, xy: np.ndarray, headings: np.ndarray) -> np.ndarray:
    """Cells (A, P, 2) of the scan points rotated to each heading (A,) and placed at ``xy``."""
    rotated = np.einsum("aij,pj->api", rotation(headings), points)
    return np.floor((rotated + np.asarray(xy)[:2] - grid.origin) / grid.resolution).astype(np.int32)


def candidate_cells(grid: LikelihoodGrid, points: np.ndarray, pose: np.ndarray,
                    angles: np.ndarray) -> np.ndarray:
    """Cells (A, P, 2) of the scan points rotated by pose θ + each angle and placed at pose x, y."""
    return heading_cells(grid, points, pose[:2], pose[2] + angles)


def candidate_likelihoods(grid: LikelihoodGrid, points: np.ndarray, normals: np.ndarray, pose: np.ndarray,
                          angles: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """Point likelihoods (A, X, Y, P) of every candidate: distance field × normal agreement,
    the scan rotated by each angle and its cells shifted by every x and y offset."""
    cells = candidate_cells(grid, points, pose, angles)
    x = cells[:, None, None, :, 0] + offsets[None, :, None, None]
    y = cells[:, None, None, :, 1] + offsets[None, None, :, None]
    world_normal = phasors((pose[2] + angles)[:, None, None, None] + normals[None, None, None, :])
    return grid.likelihood_at(x, y, ~np.isnan(normals), world_normal)


def point_log_likelihood(like: np.ndarray) -> np.ndarray:
    """log max(L, L_floor) per point; a point on known free space (L < 0) scores the floor times
    e^(−4.5) again: contradicted, not merely unexplained."""
    return np.where(like < 0, 2 * np.log(LIKELIHOOD_FLOOR), np.log(np.maximum(like, LIKELIHOOD_FLOOR)))


def correlative_match(grid: LikelihoodGrid, points: np.ndarray, normals: np.ndarray, prediction: np.ndarray,
                      window_m: float, window_rad: float, angle_step: float) -> Match:
    """Best pose of ``points`` (P, 2) with specular ``normals`` (P,) in ``grid`` within ±window of
    ``prediction`` (x, y, θ)."""
    angles = angle_step * np.arange(-np.floor(window_rad / angle_step + 1e-9),
                                    np.floor(window_rad / angle_step + 1e-9) + 1)
    reach = int(np.ceil(window_m / grid.resolution))
    offsets = np.arange(-reach, reach + 1)
    like = candidate_likelihoods(grid, points, normals, prediction, angles, offsets)
    loglik = point_log_likelihood(like).sum(axis=-1)  # (A, X, Y)
    a, i, j = np.unravel_index(np.argmax(loglik), loglik.shape)
    best = prediction + np.array([offsets[i] * grid.resolution, offsets[j] * grid.resolution, angles[a]])
    # Olson §IV: the candidates' likelihoods as a posterior → mean and covariance
    w = np.exp(loglik - loglik.max())
    grid_a, grid_x, grid_y = np.meshgrid(angles, offsets * grid.resolution, offsets * grid.resolution, indexing="ij")
    cand = np.stack([grid_x.ravel(), grid_y.ravel(), grid_a.ravel()], axis=1)
    w = w.ravel() / w.sum()
    mean = w @ cand
    centred = cand - mean
    cov = (centred * w[:, None]).T @ centred
    # the grid cannot resolve below its own step: a uniform error within one cell / angle step
    cov += np.diag([grid.resolution**2 / 12, grid.resolution**2 / 12, angle_step**2 / 12])
    edge = a in (0, len(angles) - 1) or i in (0, len(offsets) - 1) or j in (0, len(offsets) - 1)
    return Match(best, float(like[a, i, j].mean()), cov, bool(edge))
