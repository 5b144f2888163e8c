"""Likelihood field of a point map, smeared to the radio point errors, with the max-pooled
pyramid that branch and bound needs (Olson 2009 §III; Hess et al. 2016, "Real-time loop
closure in 2D LIDAR SLAM", §V-C "precomputed grids").

Each cell holds L = exp(−d²/2σ²), d the distance to the nearest map point: the
likelihood of a new point falling there under a Gaussian error of σ. ``values[ix, iy]``
covers the cell whose lower-left corner is origin + (ix, iy)·resolution.

Radio points also carry the specular normal of the surface they came from
(:mod:`radioslam.slam.normals`); each cell then also holds the world normal of its
nearest map point, and a point whose normal disagrees by Δψ is scored
L·exp(−Δψ²/2σ_ψ²). Where either normal is unknown the factor is 1. This term is what
makes rotation observable: a wall's arc of points is blind to it.

A point with a normal is scored point-to-plane, as in point-to-plane ICP (Chen &
Medioni 1992): d is then the offset along the nearest map point's normal,
|n·(c − q)|, for cells within ``plane_reach`` of that point (beyond, the plain
distance). A wall seen from two poses is two stretches of one line, and the offset
along it must not count: it is what the terminal's motion along the wall changes.
Both fields are kept (``values``: point-to-point, ``plane``: point-to-plane).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from scipy.ndimage import distance_transform_edt

from radioslam.slam.errors import SlamError

# a point farther than 3σ from the map counts as this likely (log-likelihood floor)
LIKELIHOOD_FLOOR = float(np.exp(-4.5))


def phasors(angles: np.ndarray) -> np.ndarray:
    """e^{iψ} of bearings, 0 where unknown (NaN): what :meth:`LikelihoodGrid.likelihood_at` compares."""
    return np.where(np.isnan(angles), 0.0, np.exp(1j * np.nan_to_num(angles)))


def phasor_agreement(map_phasor: np.ndarray, point_phasor: np.ndarray, sigma: float) -> np.ndarray:
    """exp(−(1 − cos Δψ)/σ²) ≈ exp(−Δψ²/2σ²) of two unit phasors; 1 where either is 0 (unknown):
    the exponent is Re(m·p̄) − |m|²|p|², without a wrap or a NaN test per lookup."""
    m, p = map_phasor, point_phasor
    dot = m.real * p.real + m.imag * p.imag
    both = (m.real**2 + m.imag**2) * (p.real**2 + p.imag**2)
    return np.exp((dot - both) / sigma**2)


@dataclass(frozen=True)
class LikelihoodGrid:
    values: np.ndarray  # (NX, NY) in [0, 1], or −penalty on known free space
    origin: np.ndarray  # (2,) world position of cell (0, 0)'s lower-left corner
    resolution: float
    normals: np.ndarray  # (NX, NY) world normal of the nearest map point, NaN: unknown
    normal_sigma: float
    plane: np.ndarray | None = None  # (NX, NY) point-to-plane field; None: as ``values``
    phasor: np.ndarray | None = None  # (NX, NY) e^{iψ} of ``normals``, 0 where unknown; None: computed

    @property
    def plane_values(self) -> np.ndarray:
        return self.values if self.plane is None else self.plane

    @cached_property
    def fields(self) -> np.ndarray:
        """(2, NX, NY): the point field, then the plane field (one gather picks either)."""
        return np.stack([self.values, self.plane_values])

    @classmethod
    def from_points(cls, points: np.ndarray, resolution: float, sigma: float, margin: float,
                    normals: np.ndarray | None = None, normal_sigma: float = np.inf,
                    plane_reach: float = 0.0, free: np.ndarray | None = None,
                    free_penalty: float = 0.0) -> "LikelihoodGrid":
        """The field of map points (P, 2) with their world normals (P,), ``margin`` beyond them;
        cells holding a ``free`` sample (F, 2) (:mod:`radioslam.slam.free_space`) and farther than
        3σ from every map point score −``free_penalty``: a point there contradicts the map.
        Whole-grid array operations throughout (float32 fields: the scores need no more)."""
        if len(points) == 0:
            raise SlamError("cannot build a likelihood grid from no points", field="points")
        origin = points.min(axis=0) - margin
        shape = tuple(np.ceil((points.max(axis=0) + margin - origin) / resolution).astype(int) + 1)
        cells = np.floor((points - origin) / resolution).astype(int)
        owner = np.full(shape, -1, dtype=np.int64)  # the map point of each hit cell (the last one wins)
        owner[cells[:, 0], cells[:, 1]] = np.arange(len(points))
        # distance from each cell centre to the nearest hit cell centre, and which cell that is
        d, (ix, iy) = distance_transform_edt(owner < 0, return_indices=True)
        d = (d * resolution).astype(np.float32)
        nearest = owner[ix, iy]
        # per map point first (few), then gathered: the nearest map point's normal in every cell
        normal_p = np.full(len(points), np.nan) if normals is None else np.asarray(normals, dtype=np.float64)
        known_p = ~np.isnan(normal_p)
        angle_p = np.where(known_p, normal_p, 0.0)
        nearest_normal, known = normal_p[nearest], known_p[nearest]
        # point-to-plane: the offset along the nearest map point's normal, within reach of it
        dx = (np.arange(shape[0])[:, None] - ix).astype(np.float32)
        dy = (np.arange(shape[1])[None, :] - iy).astype(np.float32)
        cos_p, sin_p = np.cos(angle_p).astype(np.float32), np.sin(angle_p).astype(np.float32)
        along = np.abs(cos_p[nearest] * dx + sin_p[nearest] * dy) * np.float32(resolution)
        plane = np.where(known & (d <= plane_reach), along, d)
        values, plane = _gaussian(d, sigma), _gaussian(plane, sigma)
        if free is not None and len(free) and free_penalty > 0:
            c = np.floor((free - origin) / resolution).astype(np.int64)
            c = c[np.all((c >= 0) & (c < np.array(shape)), axis=1)]
            contradicted = np.zeros(shape, dtype=bool)
            contradicted[c[:, 0], c[:, 1]] = True
            contradicted &= d > 3 * sigma
            values[contradicted] = plane[contradicted] = -free_penalty
        for field in (values, plane):  # lookups beyond the grid clip to its border: keep it empty
            field[[0, -1], :] = 0.0
            field[:, [0, -1]] = 0.0
        phasor = np.where(known_p, np.exp(1j * angle_p), 0.0).astype(np.complex64)[nearest]
        return cls(values, origin, resolution, nearest_normal, normal_sigma, plane, phasor)

    def cells(self, points: np.ndarray) -> np.ndarray:
        """Integer cells (..., 2) of points (..., 2), clipped to the grid."""
        c = np.floor((points - self.origin) / self.resolution).astype(np.int64)
        return np.clip(c, 0, np.array(self.values.shape) - 1)

    @cached_property
    def normal_phasors(self) -> np.ndarray:
        """(NX, NY) e^{iψ} of each cell's nearest map normal, 0 where unknown."""
        return phasors(self.normals) if self.phasor is None else self.phasor

    def likelihood_at(self, x: np.ndarray, y: np.ndarray, on_plane: np.ndarray,
                      point_phasor: np.ndarray | None = None,
                      fields: np.ndarray | None = None) -> np.ndarray:
        """The field at integer cells x, y (0 outside the grid: its border cells are 0),
        point-to-plane where ``on_plane`` (broadcast against x), times the normal agreement of
        points whose world normals have phasors ``point_phasor`` (:func:`phasors`; left out when
        None). ``fields`` (2, NX, NY) replaces the point and plane fields (a max-pooled level, for
        branch and bound)."""
        fields = self.fields if fields is None else fields
        nx, ny = fields.shape[1:]
        cell = np.clip(x, 0, nx - 1) * ny + np.clip(y, 0, ny - 1)  # flat indices: one gather, not three
        like = np.take(fields, np.asarray(on_plane, dtype=np.intp) * (nx * ny) + cell)
        if point_phasor is not None:  # free space (negative) contradicts whatever the normal
            agree = phasor_agreement(np.take(self.normal_phasors, cell), point_phasor, self.normal_sigma)
            like = np.where(like > 0, like * agree, like)
        return like

    def normal_at(self, points: np.ndarray) -> np.ndarray:
        """World normal of the nearest map point to each point (..., 2)."""
        c = self.cells(points)
        return self.normals[c[..., 0], c[..., 1]]

    def interpolate(self, points: np.ndarray, on_plane: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Bilinear likelihood (P,) between cell centres and its gradient (P, 2) in world
        units, point-to-plane where ``on_plane`` (P,)."""
        u = (points - self.origin) / self.resolution - 0.5
        i0 = np.floor(u).astype(np.int64)
        f = u - i0
        hi = np.array(self.values.shape) - 1
        x0, y0 = np.clip(i0[:, 0], 0, hi[0]), np.clip(i0[:, 1], 0, hi[1])
        x1, y1 = np.clip(i0[:, 0] + 1, 0, hi[0]), np.clip(i0[:, 1] + 1, 0, hi[1])

        plane = np.asarray(on_plane, dtype=np.intp) * self.values.size
        flat, ny = self.fields.ravel(), self.values.shape[1]

        def corner(x, y):  # flat indices: one gather, not three
            return np.take(flat, plane + x * ny + y)

        v00, v10, v01, v11 = corner(x0, y0), corner(x1, y0), corner(x0, y1), corner(x1, y1)
        fx, fy = f[:, 0], f[:, 1]
        value = (v00 * (1 - fx) + v10 * fx) * (1 - fy) + (v01 * (1 - fx) + v11 * fx) * fy
        dx = ((v10 - v00) * (1 - fy) + (v11 - v01) * fy) / self.resolution
        dy = ((v01 - v00) * (1 - fx) + (v11 - v10) * fx) / self.resolution
        return value, np.stack([dx, dy], axis=1)

    def pyramid(self, levels: int) -> list[np.ndarray]:
        """Max-pooled fields (2, NX, NY) as in ``fields``: level h holds the max over cells
        [i, i + 2^h) × [j, j + 2^h)."""
        levels_out = [self.fields]
        for h in range(1, levels + 1):
            levels_out.append(_pool_twice(levels_out[-1], 2 ** (h - 1)))
        return levels_out


def _gaussian(distance: np.ndarray, sigma: float) -> np.ndarray:
    """exp(−d²/2σ²) in float32, exactly 0 beyond 6σ (below 1.6e-8)."""
    g = np.exp(np.float32(-0.5 / sigma**2) * np.square(distance, dtype=np.float32))
    g[distance >= 6 * sigma] = 0.0
    return g


def _pool_twice(fields: np.ndarray, shift: int) -> np.ndarray:
    """max(F[i, j], F[i + s, j], F[i, j + s], F[i + s, j + s]) over the last two axes, 0 beyond:
    the max over [i, i + 2s) from two windows [i, i + s) and [i + s, i + 2s) of the level below."""
    out = fields.copy()
    out[:, :-shift, :] = np.maximum(out[:, :-shift, :], fields[:, shift:, :])
    wider = out.copy()
    wider[:, :, :-shift] = np.maximum(wider[:, :, :-shift], out[:, :, shift:])
    return wider
