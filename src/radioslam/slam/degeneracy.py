"""Degeneracy of a scan match and solution remapping (Zhang, Kaess & Singh, "On degeneracy
of optimization-based state estimation problems", ICRA 2016).

A surface constrains the terminal only along its normal. For a radio wall this is
literal: its echo is an arc of constant range centred on the specular foot, and the
foot slides along the wall with the terminal. The translation information of a scan
is then (Zhang §III, point-to-plane residuals with unit weight per point)

    J = Σ_p n_p n_pᵀ,   n_p = (cos φ_p, sin φ_p),

with φ_p the specular normal of the point's arc (:mod:`radioslam.slam.normals`) or,
for a point without one, the normal of the line through its neighbours within
``radius`` (an isolated point, e.g. a sidelobe outlier, counts for
nothing). The direction of J's smallest eigenvalue is the one the scan sees least;
in a straight corridor both walls share one normal axis, λ_min = 0, and a correlative
match along it reports zero motion with confidence (the arcs move with the terminal).
Where √(λ_max/λ_min) exceeds ``max_ratio`` — the same bound as for an elongated
covariance, since Σ ∝ J⁻¹ — the match is flagged and remapped (Zhang §IV): its position
along the weak direction is replaced by the prediction, and that direction's variance
by the prediction's.

J counts the points that agree with the map at the match, so a match misplaced along a
direction makes that direction weak by itself: the walls facing along it (an end wall ahead)
disagree and drop out, while the points on the walls parallel to it, scored point to point,
land on the previous scan's at a zero step. Before remapping, :meth:`DegeneracyTest.settled`
slides the match along the weak direction to the slide of highest posterior (the walls facing
along it, one observation per echo, against the motion's prior of the step): where the match
there is no longer degenerate, the direction was never weak. Weighed by likelihood alone, one
echo of a surface facing along the slide could carry the match a metre off a step the motion
predicted well.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from radioslam.slam.grid import LikelihoodGrid
from radioslam.slam.measurement import scan_log_likelihoods
from radioslam.slam.refine import fit_scores
from radioslam.slam.se2 import rotation, transform_points, wrap_angle


@dataclass(frozen=True)
class DegeneracyTest:
    """The settings of the tests below, from the ``scan`` and ``front_end`` config sections."""

    max_ratio: float  # elongation (ratio of standard deviations) beyond which a direction is weak
    neighbour_radius: float  # line fits through neighbours within this radius where no normal is known
    neighbours: int  # the point itself and up to neighbours − 1 others
    inlier_sigmas: float  # a point within this many σ of the map agrees with it

    @classmethod
    def from_config(cls, cfg) -> "DegeneracyTest":
        """From a :class:`~radioslam.slam.config.SlamConfig`."""
        return cls(cfg.front_end.degenerate_ratio, cfg.scan.neighbour_radius_m, cfg.scan.neighbours,
                   cfg.scan.inlier_sigmas)

    def weak(self, points: np.ndarray, normals: np.ndarray, heading: float,
             covariance: np.ndarray) -> np.ndarray | None:
        return weak_direction(points, normals, heading, covariance, self.max_ratio, self.neighbour_radius,
                              self.neighbours)

    def matched_weak(self, grid: LikelihoodGrid, pose: np.ndarray, points: np.ndarray, normals: np.ndarray,
                     covariance: np.ndarray) -> np.ndarray | None:
        agree = agreeing(grid, pose, points, normals, self.inlier_sigmas)
        return self.weak(points[agree], normals[agree], pose[2], covariance)

    def settled(self, grid: LikelihoodGrid, pose: np.ndarray, points: np.ndarray, normals: np.ndarray,
                weights: np.ndarray, weak: np.ndarray, span: float, log_prior) -> np.ndarray | None:
        """``pose`` slid along the world direction ``weak`` (unit, 2) within ±``span`` to the slide of highest
        posterior: the log-likelihood of the points whose specular normals face along it (within 45°: they
        measure the offset along it, point to plane; :func:`radioslam.slam.measurement.scan_log_likelihoods`,
        each point at its ``weights``) plus ``log_prior`` (a callable: poses (N, 3) → (N,), the motion's log
        prior of the step to each), on the grid's cells; None without such points, or when the match is
        already the most probable slide."""
        facing = facing_along(normals, pose[2], weak)
        if not facing.any():
            return None
        slide = grid.resolution * np.arange(-np.ceil(span / grid.resolution), np.ceil(span / grid.resolution) + 1)
        trials = pose + slide[:, None] * np.array([weak[0], weak[1], 0.0])
        posterior = scan_log_likelihoods(grid, points[facing], normals[facing], weights[facing], trials) + \
            log_prior(trials)
        best = int(np.argmax(posterior))
        return None if posterior[best] <= posterior[len(slide) // 2] else trials[best]  # the middle trial: ``pose``

    def told_apart(self, grid: LikelihoodGrid, pose: np.ndarray, points: np.ndarray, normals: np.ndarray,
                   rivals: np.ndarray, margin: float, turn: float) -> np.ndarray:
        """Mask (R,) of the ``rivals`` (R, 3) slid from ``pose`` (turned less than ``turn``) that the points
        facing along the slide tell apart: they fit there less than (1 − ``margin``) as well as at
        ``pose`` (the whole scan's ambiguity margin, applied to the points that see the slide). A step
        along walls whose other points land on the previous scan's at a zero step is no rival."""
        apart = np.zeros(len(rivals), dtype=bool)
        for r, rival in enumerate(rivals):  # a handful
            slide = rival[:2] - pose[:2]
            facing = facing_along(normals, pose[2], slide)
            if abs(wrap_angle(rival[2] - pose[2])) < turn and facing.any():
                fit = fit_scores(grid, points[facing], normals[facing], np.array([pose, rival]))
                apart[r] = fit[1] < (1.0 - margin) * fit[0]
        return apart


def facing_along(normals: np.ndarray, heading: float, direction: np.ndarray) -> np.ndarray:
    """Mask (P,) of the points whose specular normals (terminal frame, NaN: none) at ``heading`` lie
    within 45° of ±``direction`` (world): they measure an offset along it, point to plane."""
    return np.abs(np.cos(normals + heading - np.arctan2(direction[1], direction[0]))) >= np.sqrt(0.5)


def agreeing(grid: LikelihoodGrid, pose: np.ndarray, points: np.ndarray, normals: np.ndarray,
             inlier_sigmas: float) -> np.ndarray:
    """Mask (P,) of the points whose likelihood at ``pose`` is that of a point within
    ``inlier_sigmas`` σ of the map: the points that agree with it."""
    threshold = np.exp(-0.5 * inlier_sigmas**2)
    return grid.interpolate(transform_points(pose, points), ~np.isnan(normals))[0] >= threshold


def line_normals(points: np.ndarray, radius: float, neighbours: int) -> np.ndarray:
    """Normal bearing (P,) of the line fitted through each point's neighbours within
    ``radius`` (principal axes of their scatter); NaN with fewer than three points."""
    if len(points) < 3:
        return np.full(len(points), np.nan)
    dist, idx = cKDTree(points).query(points, k=min(neighbours, len(points)), distance_upper_bound=radius)
    near = np.isfinite(dist)
    nbr = np.where(near[..., None], points[np.minimum(idx, len(points) - 1)], 0.0)
    count = near.sum(axis=1)
    mean = nbr.sum(axis=1) / count[:, None]
    d = np.where(near[..., None], nbr - mean[:, None], 0.0)
    cxx, cyy, cxy = (d[..., 0] ** 2).sum(1), (d[..., 1] ** 2).sum(1), (d[..., 0] * d[..., 1]).sum(1)
    major = 0.5 * np.arctan2(2 * cxy, cxx - cyy)
    return np.where(count >= 3, major + np.pi / 2, np.nan)


def information(points: np.ndarray, normals: np.ndarray, radius: float, neighbours: int) -> np.ndarray:
    """J (2, 2) = Σ n nᵀ, specular normals where known, neighbour lines elsewhere."""
    unknown = np.isnan(normals)
    phi = np.where(unknown, line_normals(points, radius, neighbours), normals) if unknown.any() else normals
    phi = phi[~np.isnan(phi)]
    u = np.stack([np.cos(phi), np.sin(phi)], axis=1)
    return u.T @ u


def weak_direction(points: np.ndarray, normals: np.ndarray, heading: float, covariance: np.ndarray,
                   max_ratio: float, radius: float, neighbours: int) -> np.ndarray | None:
    """The world-frame unit direction (2,) a match at ``heading`` cannot observe, or None.

    Flagged when the scan's information J, or the match's own position covariance (the
    response surface sees other ambiguities too), is elongated beyond ``max_ratio``
    standard deviations.
    """
    eig, vec = np.linalg.eigh(information(points, normals, radius, neighbours))
    if _elongation(eig) > max_ratio:
        return rotation(heading) @ vec[:, 0]  # least information
    eig, vec = np.linalg.eigh(covariance[:2, :2])
    if _elongation(eig) > max_ratio:
        return vec[:, -1]  # most variance
    return None


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
