"""Refinement of a correlative match on the interpolated likelihood field, as Cartographer's
``ceres_scan_matcher_2d`` does (Hess et al. 2016 §IV-B): minimize Σ_p (1 − L(T·p))² over
(x, y, θ) with bilinear interpolation. Each point's residual is 1 − L(T·p)·exp(−Δψ²/2σ_ψ²),
the normal agreement of :mod:`radioslam.slam.grid`, with the nearest map normal held fixed
per step.

The solver is Levenberg–Marquardt on the three pose parameters with the analytic Jacobian
(Madsen, Nielsen & Tingleff, "Methods for non-linear least squares problems", 2004, §3.2,
Nielsen's damping update), the step clipped to the box ±(max_shift, max_turn) around the
start. Three unknowns need a 3 × 3 solve per iteration; a general solver's per-call
overhead (scipy's ``least_squares``: ≈ 6 ms per scan here) costs more than the fit itself.
The front end's candidates are refined side by side (one batched solve per iteration, each
candidate its own damping), so their number costs array length, not Python calls.
"""

from __future__ import annotations

import numpy as np

from radioslam.slam.grid import LikelihoodGrid
from radioslam.slam.se2 import wrap_angle


def fit_terms(grid: LikelihoodGrid, points: np.ndarray, normals: np.ndarray, poses: np.ndarray):
    """Residuals (C, P) and their Jacobians (C, P, 3) at each of ``poses`` (C, 3)."""
    known = ~np.isnan(normals)
    sigma = grid.normal_sigma
    c, s = np.cos(poses[:, 2:3]), np.sin(poses[:, 2:3])
    px, py = points[:, 0], points[:, 1]
    rx, ry = c * px - s * py, s * px + c * py  # (C, P) the points turned; ∂(R p)/∂θ = (−ry, rx)
    value, gx, gy, map_normal = grid.sample(rx + poses[:, 0:1], ry + poses[:, 1:2], known)
    delta = np.where(known, wrap_angle(poses[:, 2:3] + np.nan_to_num(normals) - map_normal), 0.0)
    delta = np.nan_to_num(delta)  # no map normal there
    positive = value > 0  # free space: no normal
    agree = np.where(positive, np.exp(-0.5 * (delta / sigma) ** 2), 1.0)
    dv_theta = gx * -ry + gy * rx
    d_agree = np.where(positive, -agree * delta / sigma**2, 0.0)
    jac = -np.stack([gx * agree, gy * agree, dv_theta * agree + value * d_agree], axis=2)
    return 1.0 - value * agree, jac


def refine_poses(grid: LikelihoodGrid, points: np.ndarray, normals: np.ndarray, starts: np.ndarray,
                 max_shift: float, max_turn: float, iterations: int = 10, tolerance: float = 1e-3) -> np.ndarray:
    """The poses (C, 3), each near its start (within ±max_shift, ±max_turn), that best fit ``points``
    (P, 2) with their terminal-frame ``normals`` (P,): one Levenberg–Marquardt per start, run side
    by side (each its own damping; one stops once a step of its, taken or not, moves it less than
    ``tolerance`` of the box: 50 µm and 0.0005° for a 5 cm cell and 0.5° step, far below what the
    5 cm field resolves)."""
    starts = np.atleast_2d(np.asarray(starts, dtype=np.float64))
    span = np.array([max_shift, max_shift, max_turn])
    poses = starts.copy()
    r, jac = fit_terms(grid, points, normals, poses)
    cost = np.einsum("cp,cp->c", r, r)
    damping, grow = None, np.full(len(poses), 2.0)
    running = np.ones(len(poses), dtype=bool)
    for _ in range(iterations):
        hessian, gradient = np.einsum("cpi,cpj->cij", jac, jac), np.einsum("cpi,cp->ci", jac, r)
        if damping is None:  # Madsen et al. (3.14): τ·max diag, τ = 1e-3
            damping = 1e-3 * np.max(np.diagonal(hessian, axis1=1, axis2=2), axis=1) + 1e-12
        step = -np.linalg.solve(hessian + damping[:, None, None] * np.eye(3), gradient[..., None])[..., 0]
        trial = np.clip(poses + step, starts - span, starts + span)
        r_trial, jac_trial = fit_terms(grid, points, normals, trial)
        cost_trial = np.einsum("cp,cp->c", r_trial, r_trial)
        actual, step = cost - cost_trial, trial - poses
        predicted = np.einsum("ci,ci->c", step, damping[:, None] * step - 2 * gradient) / 2  # gain ratio (3.15)
        better = running & (actual > 0) & (predicted > 0)
        rho = np.divide(actual, predicted, out=np.zeros_like(actual), where=better)
        damping = np.where(better, damping * np.maximum(1 / 3, 1 - (2 * rho - 1) ** 3),
                           np.where(running, damping * grow, damping))
        grow = np.where(better, 2.0, np.where(running, grow * 2, grow))
        poses, cost = np.where(better[:, None], trial, poses), np.where(better, cost_trial, cost)
        r, jac = np.where(better[:, None], r_trial, r), np.where(better[:, None, None], jac_trial, jac)
        running &= ~np.all(np.abs(step) <= tolerance * span, axis=1)  # Madsen et al. (3.16b)
        if not running.any():
            break
    return poses


def refine_pose(grid: LikelihoodGrid, points: np.ndarray, normals: np.ndarray, start: np.ndarray,
                max_shift: float, max_turn: float, iterations: int = 10, tolerance: float = 1e-3) -> np.ndarray:
    """The pose near ``start`` (within ±max_shift, ±max_turn) that best fits ``points`` (P, 2)
    with their terminal-frame ``normals`` (P,) (:func:`refine_poses` of one start)."""
    return refine_poses(grid, points, normals, start, max_shift, max_turn, iterations, tolerance)[0]


def fit_scores(grid: LikelihoodGrid, points: np.ndarray, normals: np.ndarray, poses: np.ndarray) -> np.ndarray:
    """The mean interpolated point likelihood (normal agreement included) at each of ``poses``
    (C, 3): the normalized score off the lattice, 1 − mean residual."""
    residual, _ = fit_terms(grid, points, normals, np.atleast_2d(np.asarray(poses, dtype=np.float64)))
    return 1.0 - residual.mean(axis=1)


def fit_score(grid: LikelihoodGrid, points: np.ndarray, normals: np.ndarray, pose: np.ndarray) -> float:
    """:func:`fit_scores` of one pose."""
    return float(fit_scores(grid, points, normals, pose)[0])
