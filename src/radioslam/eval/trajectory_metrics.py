"""Trajectory error after SE(2) alignment (Umeyama, "Least-squares estimation of transformation
parameters between two point patterns", PAMI 1991, without scale), as evo's ``evo_ape -a`` and
``evo_rpe`` compute them (Grupp, evo, 2017; Sturm et al. 2012 for ATE/RPE).
"""

from __future__ import annotations

import numpy as np

from radioslam.slam.se2 import between, compose


def umeyama_se2(estimate_xy: np.ndarray, truth_xy: np.ndarray) -> np.ndarray:
    """The SE(2) transform (x, y, θ) that best maps estimated positions (P, 2) onto true ones."""
    mu_e, mu_t = estimate_xy.mean(axis=0), truth_xy.mean(axis=0)
    cov = (truth_xy - mu_t).T @ (estimate_xy - mu_e) / len(estimate_xy)
    u, _, vt = np.linalg.svd(cov)
    s = np.diag([1.0, np.sign(np.linalg.det(u @ vt))])
    rot = u @ s @ vt
    t = mu_t - rot @ mu_e
    return np.array([t[0], t[1], np.arctan2(rot[1, 0], rot[0, 0])])


def align(estimate: np.ndarray, truth: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Estimated poses (P, 3) aligned onto the truth, and the transform used."""
    transform = umeyama_se2(estimate[:, :2], truth[:, :2])
    return compose(transform, estimate), transform


def pose_errors(estimate: np.ndarray, truth: np.ndarray) -> np.ndarray:
    """Each pose's position error (P,) after the SE(2) alignment (the ATE's terms)."""
    aligned, _ = align(estimate, truth)
    return np.linalg.norm(aligned[:, :2] - np.asarray(truth)[:, :2], axis=1)


def ate_rmse(estimate: np.ndarray, truth: np.ndarray) -> float:
    """Absolute trajectory error: RMSE of the aligned positions (m)."""
    return float(np.sqrt(np.mean(pose_errors(estimate, truth) ** 2)))


def relative_errors(estimate: np.ndarray, truth: np.ndarray, delta: int = 1) -> np.ndarray:
    """Each relative pose error (P − delta, 3) over ``delta`` steps: the estimated step seen from the true
    one (the RPE's terms)."""
    return between(between(truth[:-delta], truth[delta:]), between(estimate[:-delta], estimate[delta:]))


def rpe_rmse(estimate: np.ndarray, truth: np.ndarray, delta: int = 1) -> float:
    """Relative pose error over ``delta`` steps: RMSE of the translation error (m)."""
    error = relative_errors(estimate, truth, delta)
    return float(np.sqrt(np.mean(np.sum(error[:, :2] ** 2, axis=1))))
