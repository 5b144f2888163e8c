"""Degeneracy of a scan match and solution remapping (Zhang, Kaess & Singh, "On degeneracy
of optimization-based state estimation problems", ICRA 2016).

A surface constrains the terminal only along its normal. For a radio wall this is
literal: its echo is an arc of constant range centred on the specular foot, and the
foot slides along the wall with the terminal. The translation information of a scan
is then (Zhang §III, point-to-plane residuals with unit weight per point)

    J = Σ_p n_p n_pᵀ,   n_p = (cos φ_p, sin φ_p),

with φ_p the specular normal of the point's arc (:mod:`radioslam.slam.normals`) or,
for a point without one, the normal of the line through its neighbours within
``NEIGHBOUR_RADIUS_M`` (an isolated point, e.g. a sidelobe outlier, counts for
nothing). The direction of J's smallest eigenvalue is the one the scan sees least;
in a straight corridor both walls share one normal axis, λ_min = 0, and a correlative
match along it reports zero motion with confidence (the arcs move with the terminal).
Where √(λ_max/λ_min) exceeds ``max_ratio`` — the same bound as for an elongated
covariance, since Σ ∝ J⁻¹ — the match is flagged and remapped (Zhang §IV): its position
along the weak direction is replaced by the prediction, and that direction's variance
by the prediction's.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from radioslam.slam.grid import LikelihoodGrid
from radioslam.slam.se2 import rotation, transform_points

NEIGHBOUR_RADIUS_M = 0.5
NEIGHBOURS = 6  # the point itself and up to five others
INLIER_LIKELIHOOD = float(np.exp(-0.5 * 2.0**2))  # a point within 2σ of the map agrees with it


def line_normals(points: np.ndarray, radius: float = NEIGHBOUR_RADIUS_M) -> np.ndarray:
    """Normal bearing (P,) of the line fitted through each point's neighbours within
    ``radius`` (principal axes of their scatter); NaN with fewer than three points."""
    if len(points) < 3:
        return np.full(len(points), np.nan)
    dist, idx = cKDTree(points).query(points, k=min(NEIGHBOURS, len(points)), distance_upper_bound=radius)
    near = np.isfinite(dist)
    nbr = np.where(near[..., None], points[np.minimum(idx, len(points) - 1)], 0.0)
    count = near.sum(axis=1)
    mean = nbr.sum(axis=1) / count[:, None]
    d = np.where(near[..., None], nbr - mean[:, None], 0.0)
    cxx, cyy, cxy = (d[..., 0] ** 2).sum(1), (d[..., 1] ** 2).sum(1), (d[..., 0] * d[..., 1]).sum(1)
    major = 0.5 * np.arctan2(2 * cxy, cxx - cyy)
    return np.where(count >= 3, major + np.pi / 2, np.nan)


def information(points: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """J (2, 2) = Σ n nᵀ, specular normals where known, neighbour lines elsewhere."""
    unknown = np.isnan(normals)
    phi = np.where(unknown, line_normals(points), normals) if unknown.any() else normals
    phi = phi[~np.isnan(phi)]
    u = np.stack([np.cos(phi), np.sin(phi)], axis=1)
    return u.T @ u


def weak_direction(points: np.ndarray, normals: np.ndarray, heading: float, covariance: np.ndarray,
                   max_ratio: float) -> np.ndarray | None:
    """The world-frame unit direction (2,) a match at ``heading`` cannot observe, or None.

    Flagged when the scan's information J, or the match's own position covariance (the
    response surface sees other ambiguities too), is elongated beyond ``max_ratio``
    standard deviations.
    """
    eig, vec = np.linalg.eigh(information(points, normals))
    if _elongation(eig) > max_ratio:
        return rotation(heading) @ vec[:, 0]  # least information
    eig, vec = np.linalg.eigh(covariance[:2, :2])
    if _elongation(eig) > max_ratio:
        return vec[:, -1]  # most variance
    return None


def matched_weak_direction(grid: LikelihoodGrid, pose: np.ndarray, points: np.ndarray, normals: np.ndarray,
                           covariance: np.ndarray, max_ratio: float) -> np.ndarray | None:
    """:func:`weak_direction` of only the points that agree with ``grid`` at ``pose``: a wall the
    map has not seen yet constrains nothing, so a match on one wall in common slides along it."""
    agree = grid.interpolate(transform_points(pose, points), ~np.isnan(normals))[0] >= INLIER_LIKELIHOOD
    return weak_direction(points[agree], normals[agree], pose[2], covariance, max_ratio)


def _elongation(eigenvalues: np.ndarray) -> float:
    """√(λ_max/λ_min) of ascending eigenvalues: the ratio of the axes' lengths."""
    return float(np.sqrt(eigenvalues[-1] / max(eigenvalues[0], 1e-18)))


def remap(pose: np.ndarray, covariance: np.ndarray, prediction: np.ndarray, weak: np.ndarray,
          prediction_sigma: float) -> tuple[np.ndarray, np.ndarray]:
    """Zhang §IV: the pose along ``weak`` taken from the prediction, and the covariance
    along it widened to the prediction's standard deviation."""
    projector = np.outer(weak, weak)
    pose, covariance = pose.copy(), covariance.copy()
    pose[:2] -= projector @ (pose[:2] - prediction[:2])
    covariance[:2, :2] += prediction_sigma**2 * projector
    return pose, covariance
