"""2D geometry of wall segments: vectorized point–segment distances and ray intersections."""

from __future__ import annotations

import numpy as np


def cross2(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """z-component of the 2D cross product, broadcasting over leading axes."""
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def point_segment_distance(points: np.ndarray, segments: np.ndarray) -> np.ndarray:
    """Euclidean distance (P, S) from points (P, 2) to segments (S, 2, 2)."""
    a, e = segments[:, 0], segments[:, 1] - segments[:, 0]
    rel = points[:, None, :] - a[None]
    t = np.clip(np.einsum("psk,sk->ps", rel, e) / np.einsum("sk,sk->s", e, e), 0.0, 1.0)
    closest = a[None] + t[..., None] * e[None]
    return np.linalg.norm(points[:, None, :] - closest, axis=-1)


def ray_segment_intersections(origin: np.ndarray, directions: np.ndarray,
                              segments: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Distance along each ray (R, S) to each segment (inf where missed) and |cos ψ| (R, S).

    origin + t·d = a + u·e with t > 0 and 0 ≤ u ≤ 1; ψ is the incidence angle
    between the ray and the segment normal, so |cos ψ| = |d × ê|.
    """
    a, e = segments[:, 0], segments[:, 1] - segments[:, 0]
    denom = cross2(directions[:, None, :], e[None])  # (R, S)
    rel = a - origin  # (S, 2)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        t = cross2(rel[None], e[None]) / denom
        u = cross2(rel[None], directions[:, None, :]) / denom
    hit = (np.abs(denom) > 1e-12) & (t > 1e-9) & (u >= 0.0) & (u <= 1.0)
    cos_incidence = np.abs(denom) / np.linalg.norm(e, axis=-1)[None]
    return np.where(hit, t, np.inf), cos_incidence
