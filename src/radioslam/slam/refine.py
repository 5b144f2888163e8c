"""Refinement of a correlative match on the interpolated likelihood field, as Cartographer's
``ceres_scan_matcher_2d`` does (Hess et al. 2016 §IV-B): minimize Σ_p (1 − L(T·p))² over
(x, y, θ) with bilinear interpolation, here by scipy's trust-region least squares with the
analytic Jacobian. Each point's residual is 1 − L(T·p)·exp(−Δψ²/2σ_ψ²), the normal
agreement of :mod:`radioslam.slam.grid`, with the nearest map normal held fixed per step.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import least_squares

from radioslam.slam.grid import LikelihoodGrid
from radioslam.slam.se2 import rotation, wrap_angle


def refine_pose(grid: LikelihoodGrid, points: np.ndarray, normals: np.ndarray, start: np.ndarray,
                max_shift: float, max_turn: float) -> np.ndarray:
    """The pose near ``start`` (within ±max_shift, ±max_turn) that best fits ``points`` (P, 2)
    with their terminal-frame ``normals`` (P,)."""
    known = ~np.isnan(normals)
    sigma = grid.normal_sigma

    def terms(pose):
        placed = points @ rotation(pose[2]).T + pose[:2]
        value, grad = grid.interpolate(placed, known)
        delta = np.where(known, wrap_angle(pose[2] + np.nan_to_num(normals) - grid.normal_at(placed)), 0.0)
        delta = np.nan_to_num(delta)  # no map normal there
        agree = np.where(value > 0, np.exp(-0.5 * (delta / sigma) ** 2), 1.0)  # free space: no normal
        return value, grad, delta, agree

    def residuals(pose):
        value, _, _, agree = terms(pose)
        return 1.0 - value * agree

    def jacobian(pose):
        value, grad, delta, agree = terms(pose)
        c, s = np.cos(pose[2]), np.sin(pose[2])
        d_theta = points @ np.array([[-s, c], [-c, -s]])  # ∂(R p)/∂θ
        dv_theta = np.einsum("pi,pi->p", grad, d_theta)
        d_agree = -agree * delta / sigma**2
        return -np.column_stack([grad[:, 0] * agree, grad[:, 1] * agree, dv_theta * agree + value * d_agree])

    span = np.array([max_shift, max_shift, max_turn])
    fit = least_squares(residuals, start, jac=jacobian, bounds=(start - span, start + span), x_scale=span,
                        xtol=1e-6, max_nfev=30)
    return fit.x
