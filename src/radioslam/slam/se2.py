"""SE(2) poses (x, y, θ) as arrays, vectorized over leading axes (DESIGN.md §2: θ counter-clockwise)."""

from __future__ import annotations

import numpy as np


def wrap_angle(theta: np.ndarray) -> np.ndarray:
    """Angles wrapped to (−π, π]."""
    wrapped = np.pi - np.mod(np.pi - np.asarray(theta, dtype=np.float64), 2 * np.pi)
    return wrapped


def rotation(theta: np.ndarray) -> np.ndarray:
    """Rotation matrices (..., 2, 2)."""
    c, s = np.cos(theta), np.sin(theta)
    return np.stack([np.stack([c, -s], axis=-1), np.stack([s, c], axis=-1)], axis=-2)


def compose(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a ⊕ b: the pose b expressed in a's frame, taken to a's parent frame."""
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    c, s = np.cos(a[..., 2]), np.sin(a[..., 2])
    x = a[..., 0] + c * b[..., 0] - s * b[..., 1]
    y = a[..., 1] + s * b[..., 0] + c * b[..., 1]
    return np.stack([x, y, wrap_angle(a[..., 2] + b[..., 2])], axis=-1)


def inverse(a: np.ndarray) -> np.ndarray:
    a = np.asarray(a, dtype=np.float64)
    c, s = np.cos(a[..., 2]), np.sin(a[..., 2])
    return np.stack([-c * a[..., 0] - s * a[..., 1], s * a[..., 0] - c * a[..., 1], wrap_angle(-a[..., 2])], axis=-1)


def between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a⁻¹ ⊕ b: the pose b seen from a."""
    return compose(inverse(a), b)


def transform_points(pose: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Points (P, 2) of a frame at ``pose`` into the parent frame."""
    c, s = np.cos(pose[2]), np.sin(pose[2])
    return points @ np.array([[c, s], [-s, c]]) + np.asarray(pose[:2])


def pose_covariance(sigma_m: float, sigma_deg: float) -> np.ndarray:
    """Diagonal covariance (3, 3) of an (x, y, θ) pose: ``sigma_m`` on each axis, ``sigma_deg`` in θ."""
    return np.diag([sigma_m**2, sigma_m**2, np.radians(sigma_deg) ** 2])
