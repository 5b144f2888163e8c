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
"""

from __future__ import annotations

import numpy as np

from radioslam.slam.grid import LikelihoodGrid
from radioslam.slam.se2 import rotation, wrap_angle


def fit_terms(grid: LikelihoodGrid, points: np.ndarray, normals: np.ndarray, pose: np.ndarray):
    """Residuals (P,) and their Jacobian (P, 3) at ``pose``."""
    known = ~np.isnan(normals)
    sigma = grid.normal_sigma
    placed = points @ rotation(pose[2]).T + pose[:2]
    value, grad = grid.interpolate(placed, known)
    delta = np.where(known, wrap_angle(pose[2] + np.nan_to_num(normals) - grid.normal_at(placed)), 0.0)
    delta = np.nan_to_num(delta)  # no map normal there
    agree = np.where(value > 0, np.exp(-0.5 * (delta / sigma) ** 2), 1.0)  # free space: no normal
    c, s = np.cos(pose[2]), np.sin(pose[2])
    d_theta = points @ np.array([[-s, c], [-c, -s]])  # ∂(R p)/∂θ
    dv_theta = np.einsum("pi,pi->p", grad, d_theta)
    d_agree = np.where(value > 0, -agree * delta / sigma**2, 0.0)
    jac = -np.column_stack([grad[:, 0] * agree, grad[:, 1] * agree, dv_theta * agree + value * d_agree])
    return 1.0 - value * agree, jac


def refine_pose(grid: LikelihoodGrid, points: np.ndarray, normals: np.ndarray, start: np.ndarray,
                max_shift: float, max_turn: float, iterations: int = 10) -> np.ndarray:
    """The pose near ``start`` (within ±max_shift, ±max_turn) that best fits ``points`` (P, 2)
    with their terminal-frame ``normals`` (P,)."""
    start = np.asarray(start, dtype=np.float64)
    span = np.array([max_shift, max_shift, max_turn])
    pose = start.copy()
    r, jac = fit_terms(grid, points, normals, pose)
    cost, damping, grow = float(r @ r), None, 2.0
    for _ in range(iterations):
        hessian, gradient = jac.T @ jac, jac.T @ r
        if damping is None:  # Madsen et al. (3.14): τ·max diag, τ = 1e-3
            damping = 1e-3 * float(np.max(np.diag(hessian))) + 1e-12
        step = -np.linalg.solve(hessian + damping * np.eye(3), gradient)
        trial = np.clip(pose + step, start - span, start + span)
        r_trial, jac_trial = fit_terms(grid, points, normals, trial)
        cost_trial = float(r_trial @ r_trial)
        actual, step = cost - cost_trial, trial - pose
        predicted = float(step @ (damping * step - 2 * gradient)) / 2  # gain ratio denominator (3.15)
        if actual > 0 and predicted > 0:
            rho = actual / predicted
            damping *= max(1 / 3, 1 - (2 * rho - 1) ** 3)
            grow = 2.0
            pose, r, jac, cost = trial, r_trial, jac_trial, cost_trial
            if np.all(np.abs(step) <= 1e-6 * span):
                break
        else:
            damping *= grow
            grow *= 2
    return pose


def fit_score(grid: LikelihoodGrid, points: np.ndarray, normals: np.ndarray, pose: np.ndarray) -> float:
    """The mean interpolated point likelihood (normal agreement included) at ``pose``: the
    normalized score off the lattice, 1 − mean residual."""
    residual, _ = fit_terms(grid, points, normals, pose)
    return float(1.0 - residual.mean())
