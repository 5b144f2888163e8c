"""Vectorized 2D ray caster with transmission through walls.

Every ray from the terminal is intersected with every wall segment at once
(rays × segments arrays, in blocks of rays of at most ``TABLE_CELLS`` cells, so that a scene of
thousands of segments needs bounded memory). Hits are sorted by distance; a ray goes on through a
wall with transmission T > 0 (glass, drywall) and stops at an opaque one. Each
hit carries the two-way amplitude factor Π T_j² of the walls crossed before it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from radioslam.scene.geometry import ray_segment_intersections

TABLE_CELLS = 2**22  # rays × segments per block: a few float64 tables of 32 MiB


@dataclass(frozen=True)
class RayHits:
    """Up to ``max_hits`` hits per ray; unused entries have distance = inf, segment = −1."""

    angle: np.ndarray  # (R,) world angle of each ray
    distance: np.ndarray  # (R, H) metres
    segment: np.ndarray  # (R, H) index of the wall segment hit
    cos_incidence: np.ndarray  # (R, H) |cos ψ|
    transmission: np.ndarray  # (R, H) two-way amplitude through the walls before the hit

    @property
    def valid(self) -> np.ndarray:
        return np.isfinite(self.distance)


def cast_rays(origin: np.ndarray, angles: np.ndarray, segments: np.ndarray,
              segment_transmission: np.ndarray, max_hits: int, max_range: float) -> RayHits:
    """Cast rays from ``origin`` at world ``angles`` (R,) against ``segments`` (S, 2, 2)."""
    angles = np.asarray(angles, dtype=np.float64)
    block = max(1, TABLE_CELLS // max(len(segments), 1))
    if len(angles) > block:  # the same hits, block by block
        parts = [cast_rays(origin, angles[i:i + block], segments, segment_transmission, max_hits, max_range)
                 for i in range(0, len(angles), block)]
        return RayHits(angles, *(np.concatenate([getattr(h, f) for h in parts])
                                 for f in ("distance", "segment", "cos_incidence", "transmission")))
    directions = np.stack([np.cos(angles), np.sin(angles)], axis=-1)
    t, cos_inc = ray_segment_intersections(np.asarray(origin, float), directions, segments)
    h = min(max_hits, segments.shape[0])
    order = np.argsort(t, axis=1)[:, :h]
    dist = np.take_along_axis(t, order, axis=1)
    cos_h = np.take_along_axis(cos_inc, order, axis=1)
    seg = np.where(np.isfinite(dist), order, -1)
    # a ray through a shared polyline vertex meets both segments at the same distance
    repeat = np.zeros_like(dist, dtype=bool)
    with np.errstate(invalid="ignore"):  # inf − inf where a ray has fewer hits
        repeat[:, 1:] = np.abs(np.diff(dist, axis=1)) < 1e-9
    t_two_way = np.where(seg >= 0, segment_transmission[np.maximum(seg, 0)] ** 2, 0.0)
    before = np.ones_like(dist)
    before[:, 1:] = np.cumprod(t_two_way[:, :-1], axis=1)
    keep = np.isfinite(dist) & ~repeat & (before > 0.0) & (dist <= max_range)
    return RayHits(angles, np.where(keep, dist, np.inf), np.where(keep, seg, -1), cos_h,
                   np.where(keep, before, 0.0))


def cast_fan(origin: np.ndarray, heading: float, spacing_rad: float, segments: np.ndarray,
             segment_transmission: np.ndarray, max_hits: int, max_range: float) -> tuple[np.ndarray, RayHits]:
    """A full circle of rays about ``spacing_rad`` apart (a whole number of them), centred in their cells:
    their angles (R,) relative to ``heading`` and their hits."""
    n = int(round(2 * np.pi / spacing_rad))
    local = -np.pi + (np.arange(n) + 0.5) * (2 * np.pi / n)
    return local, cast_rays(origin, heading + local, segments, segment_transmission, max_hits, max_range)
