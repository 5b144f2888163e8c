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
SEEN_CELLS = 4  # the observed space is marked on cells this many grid cells wide (0.2 m at 5 cm)


def phasors(angles: np.ndarray) -> np.ndarray:
    """e^{iψ} of bearings (complex64), 0 where unknown (NaN): what :meth:`LikelihoodGrid.likelihood_at`
    compares."""
    return np.where(np.isnan(angles), 0.0, np.exp(1j * np.nan_to_num(angles))).astype(np.complex64)


def phasor_agreement(map_phasor: np.ndarray, map_known: np.ndarray, point_phasor: np.ndarray,
                     sigma: float) -> np.ndarray:
    """exp(−(1 − cos Δψ)/σ²) ≈ exp(−Δψ²/2σ²) of two unit phasors; 1 where either is 0 (unknown):
    the exponent is Re(m·p̄) − |m|²|p|² (``map_known`` = |m|² ∈ {0, 1}), without a wrap or a NaN test
    per lookup; float32 throughout (Δψ resolved to ≈ 0.02°, against σ ≈ 1°), never above 1."""
    p = np.asarray(point_phasor, dtype=np.complex64)
    exponent = np.real(map_phasor * np.conj(p)) - map_known * (p.real**2 + p.imag**2)  # contiguous float32
    exponent *= np.float32(1.0 / sigma**2)
    return np.exp(np.minimum(exponent, 0.0, out=exponent), out=exponent)  # ≤ 1 despite rounding: an admissible bound


@dataclass(frozen=True)
class LikelihoodGrid:
    values: np.ndarray  # (NX, NY) in [0, 1], or −penalty on known free space
    origin: np.ndarray  # (2,) world position of cell (0, 0)'s lower-left corner
    resolution: float
    normals: np.ndarray | None  # (NX, NY) world normal of the nearest map point, NaN: unknown; None: normal_cells
    normal_sigma: float
    plane: np.ndarray | None = None  # (NX, NY) point-to-plane field; None: as ``values``
    phasor: np.ndarray | None = None  # (NX, NY) e^{iψ} of ``normals``, 0 where unknown; None: computed
    # (NX, NY) the cells the map observed (its scans' beams swept them); None: all of them
    seen: np.ndarray | None = None
    # the likelihood a point gets where the map never looked: the field's mean over the cells it observed,
    # the prior of a surface there (the likelihood field marginalized over a map it does not know)
    neutral: float = 0.0
    # (J, 3) where the map's scans were taken (x, y) and how far each saw (its farthest echo): whether the map
    # could have detected a surface of a given orientation (:mod:`radioslam.slam.measurement`); None: unknown
    viewpoints: np.ndarray | None = None
    # ``normals`` held sparse: (ascending flat cells ix·NY + iy, the nearest map point's world normal there), NaN
    # elsewhere (a map normal matters only near the map: a whole-grid array would cost more than the field)
    normal_cells: tuple[np.ndarray, np.ndarray] | None = None

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
                    free_penalty: float = 0.0, seen: np.ndarray | None = None) -> "LikelihoodGrid":
        """The field of map points (P, 2) with their world normals (P,), ``margin`` beyond them (and
        beyond the free samples; :func:`field_reach` is as far as the field reaches);
        cells holding a ``free`` sample (F, 2) (:mod:`radioslam.slam.free_space`) and farther than
        3σ from every map point score −``free_penalty``: a point there contradicts the map. ``seen`` (S, 2):
        samples of the space the map's scans observed (:func:`radioslam.slam.free_space.seen_samples`),
        ``SEEN_CELLS`` cells apart at most, which mark it (None: all of it).
        Whole-grid array operations throughout (float32 fields: the scores need no more)."""
        if len(points) == 0:
            raise SlamError("cannot build a likelihood grid from no points", field="points")
        extent = [points] if free is None or not len(free) else [points, free]
        low = np.min([[p[:, axis].min() for axis in (0, 1)] for p in extent], axis=0)  # per column: an axis-0
        high = np.max([[p[:, axis].max() for axis in (0, 1)] for p in extent], axis=0)  # reduction of (N, 2) is slow
        origin = low - margin
        shape = tuple(np.ceil((high + margin - origin) / resolution).astype(int) + 1)
        cells = np.floor((points - origin) / resolution).astype(np.intp)
        owner = np.full(shape, -1, dtype=np.int32)  # the map point of each hit cell (the last one wins)
        owner[cells[:, 0], cells[:, 1]] = np.arange(len(points), dtype=np.int32)
        # the nearest hit cell of every cell, and the offset (in whole cells) from it
        ix, iy = distance_transform_edt(owner < 0, return_distances=False, return_indices=True)
        offset_x = (np.arange(shape[0], dtype=np.int32)[:, None] - ix).ravel()
        offset_y = (np.arange(shape[1], dtype=np.int32)[None, :] - iy).ravel()
        whole2 = offset_x * offset_x + offset_y * offset_y  # squared distance to the nearest hit cell centre, cells²
        # both fields vanish beyond 6σ and the plane reach: computed only on the cells within (a fraction);
        # a map normal matters only in a cell next to one where a field is positive (a point's bilinear
        # corners hold its own cell), so normals are gathered a diagonal further. The whole-grid test is on
        # integers, a cell wider; the exact one on the few cells it leaves
        reach = max(6 * sigma, plane_reach)
        within = np.flatnonzero(whole2 <= int(np.ceil(((reach + 2 * resolution) / resolution) ** 2)) + 1)
        cells2 = whole2[within].astype(np.float32)  # whole numbers below 2²⁴: exact
        d2_within = cells2 * np.float32(resolution**2)
        is_near = d2_within < reach**2 + resolution**2
        is_beside = d2_within < (reach + 2 * resolution) ** 2
        near, beside = within[is_near], within[is_beside]
        nearest = np.take(owner, ix.ravel()[beside] * shape[1] + iy.ravel()[beside])  # the map point there
        # per map point first (few), then gathered: the nearest map point's normal in those cells
        normal_p = np.full(len(points), np.nan) if normals is None else np.asarray(normals, dtype=np.float64)
        known_p = ~np.isnan(normal_p)
        phasor_p = np.where(known_p, np.exp(1j * np.where(known_p, normal_p, 0.0)), 0.0).astype(np.complex64)
        size = shape[0] * shape[1]
        phasor = np.zeros(size, dtype=np.complex64)
        phasor[beside] = phasor_p[nearest]
        d2_near, phasor_near = d2_within[is_near], phasor[near]
        dx, dy = offset_x[near].astype(np.float32), offset_y[near].astype(np.float32)
        # point-to-plane: the offset along the nearest map point's normal (0 phasor: unknown), within reach
        along = phasor_near.real * dx + phasor_near.imag * dy
        along2 = along * along * np.float32(resolution**2)
        plane2 = np.where((phasor_near != 0) & (d2_near <= plane_reach**2), along2, d2_near)
        fields = np.zeros((2, size), dtype=np.float32)  # point, then plane field
        # the point field of whole cells² by table (the same float32 products as d2's), the plane field in full
        squares = whole2[near].astype(np.intp)
        table = _gaussian(np.arange(squares.max() + 1 if len(squares) else 1, dtype=np.float32)
                          * np.float32(resolution**2), sigma)
        fields[0, near], fields[1, near] = table[squares], _gaussian(plane2, sigma)
        if free is not None and len(free) and free_penalty > 0:
            u = (free - origin) / resolution
            inside = (u[:, 0] >= 0) & (u[:, 0] < shape[0]) & (u[:, 1] >= 0) & (u[:, 1] < shape[1])
            c = u[inside].astype(np.intp)  # non-negative: truncation is the floor
            flat = c[:, 0] * shape[1] + c[:, 1]
            far = whole2[flat].astype(np.float32) * np.float32(resolution**2) > (3 * sigma) ** 2
            fields[:, flat[far]] = -free_penalty  # free, and far from every map point
        fields = fields.reshape(2, *shape)
        fields[:, [0, -1], :] = 0.0  # lookups beyond the grid clip to its border: keep it empty
        fields[:, :, [0, -1]] = 0.0
        observed = None if seen is None else _observed(seen, origin, resolution, shape)
        neutral = 0.0 if observed is None or not observed.any() else float(np.maximum(fields[0][observed], 0).mean())
        grid = cls(fields[0], origin, resolution, None, normal_sigma, fields[1], phasor.reshape(shape), observed,
                   neutral, normal_cells=(beside, normal_p[nearest]))
        grid.__dict__["fields"] = fields  # the cached stack, already built
        return grid

    @property
    def area_m2(self) -> float:
        """The area the grid covers."""
        return float(np.prod(self.values.shape)) * self.resolution ** 2

    def cells(self, points: np.ndarray) -> np.ndarray:
        """Integer cells (..., 2) of points (..., 2), clipped to the grid."""
        c = np.floor((points - self.origin) / self.resolution).astype(np.int64)
        return np.clip(c, 0, np.array(self.values.shape) - 1)

    @cached_property
    def normal_phasors(self) -> np.ndarray:
        """(NX, NY) e^{iψ} of each cell's nearest map normal, 0 where unknown."""
        return phasors(self.normals) if self.phasor is None else self.phasor

    def normals_of_cells(self, cell: np.ndarray) -> np.ndarray:
        """The world normal of the nearest map point (NaN: unknown) in flat cells (ix·NY + iy, within the grid)."""
        if self.normal_cells is None:
            return np.take(self.normals, cell)
        held, normal = self.normal_cells
        at = np.minimum(np.searchsorted(held, cell), len(held) - 1)
        return np.where(held[at] == cell, normal[at], np.nan) if len(held) else np.full(np.shape(cell), np.nan)

    @cached_property
    def normal_known(self) -> np.ndarray:
        """(NX, NY) float32 |e^{iψ}|²: 1 where a cell's nearest map normal is known, else 0."""
        return (np.abs(self.normal_phasors) > 0).astype(np.float32)

    def likelihood_at(self, x: np.ndarray, y: np.ndarray, on_plane: np.ndarray,
                      point_phasor: np.ndarray | None = None,
                      fields: np.ndarray | None = None) -> np.ndarray:
        """The field at integer cells x, y (0 outside the grid: its border cells are 0),
        point-to-plane where ``on_plane`` (broadcast against x), times the normal agreement of
        points whose world normals have phasors ``point_phasor`` (:func:`phasors`; left out when
        None). ``fields`` (2, NX, NY) replaces the point and plane fields (a max-pooled level, for
        branch and bound)."""
        nx, ny = self.values.shape
        cell = np.clip(x, 0, nx - 1) * ny + np.clip(y, 0, ny - 1)  # flat indices: one gather, not three
        return self.likelihood_of_cells(cell, np.asarray(on_plane, dtype=np.intp) * (nx * ny), point_phasor, fields)

    def likelihood_of_cells(self, cell: np.ndarray, plane_offset: np.ndarray, point_phasor: np.ndarray | None = None,
                            fields: np.ndarray | None = None) -> np.ndarray:
        """:meth:`likelihood_at` of flat cell indices (ix·NY + iy, within the grid); ``plane_offset`` is
        NX·NY where a point is scored point-to-plane, else 0 (broadcast against ``cell``)."""
        fields = self.fields if fields is None else fields
        like = np.take(fields, plane_offset + cell)
        if point_phasor is not None:  # free space (negative) contradicts whatever the normal
            agree = phasor_agreement(np.take(self.normal_phasors, cell), np.take(self.normal_known, cell),
                                     point_phasor, self.normal_sigma)
            like = np.where(like > 0, like * agree, like)
        return like

    def interpolate(self, points: np.ndarray, on_plane: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Bilinear likelihood (P,) between cell centres and its gradient (P, 2) in world
        units, point-to-plane where ``on_plane`` (P,)."""
        value, dx, dy, _ = self.sample(points[:, 0], points[:, 1], on_plane)
        return value, np.stack([dx, dy], axis=1)

    def sample(self, x: np.ndarray, y: np.ndarray, on_plane: np.ndarray):
        """At world points (x, y) (any shape, alike): the bilinear likelihood between cell centres, its
        gradient ∂/∂x and ∂/∂y in world units (point-to-plane where ``on_plane``, broadcast against x),
        and the world normal of the nearest map point (in the cell holding the point): one pass for the
        refinement."""
        ox, oy = self.origin
        res, (nx, ny) = self.resolution, self.values.shape
        u, v = (x - ox) / res - 0.5, (y - oy) / res - 0.5
        i0, j0 = np.floor(u).astype(np.intp), np.floor(v).astype(np.intp)
        fx, fy = u - i0, v - j0
        x0, y0 = np.clip(i0, 0, nx - 1) * ny, np.clip(j0, 0, ny - 1)  # flat indices: one gather, not three
        x1, y1 = np.clip(i0 + 1, 0, nx - 1) * ny, np.clip(j0 + 1, 0, ny - 1)
        base = np.asarray(on_plane, dtype=np.intp) * self.values.size
        flat = self.fields.ravel()
        v00, v10 = np.take(flat, base + x0 + y0), np.take(flat, base + x1 + y0)
        v01, v11 = np.take(flat, base + x0 + y1), np.take(flat, base + x1 + y1)
        value = (v00 * (1 - fx) + v10 * fx) * (1 - fy) + (v01 * (1 - fx) + v11 * fx) * fy
        gx = ((v10 - v00) * (1 - fy) + (v11 - v01) * fy) / res
        gy = ((v01 - v00) * (1 - fx) + (v11 - v10) * fx) / res
        cx = np.clip(np.floor((x - ox) / res).astype(np.intp), 0, nx - 1)  # the cell holding the point
        cy = np.clip(np.floor((y - oy) / res).astype(np.intp), 0, ny - 1)
        return value, gx, gy, self.normals_of_cells(cx * ny + cy)

    def pyramid(self, levels: int) -> list[np.ndarray]:
        """Level 0: ``fields`` (2, NX, NY); level h ≥ 1: (1, NX, NY), the max over cells [i, i + 2^h) ×
        [j, j + 2^h) of both fields (the plane field is ≥ the point field anyway, up to rounding): one
        bound for every point, point-to-plane or not, at half the pooling."""
        levels_out = [self.fields, np.maximum(self.fields[:1], self.fields[1:])]
        for h in range(1, levels + 1):
            levels_out.append(_pool_twice(levels_out[-1], 2 ** (h - 1)))
        return levels_out[:1] + levels_out[2:]


def _observed(seen: np.ndarray, origin: np.ndarray, resolution: float, shape: tuple[int, int]) -> np.ndarray:
    """(NX, NY) the cells within a coarse cell (``SEEN_CELLS`` wide) of a ``seen`` sample, or beside one."""
    coarse_shape = (-(-shape[0] // SEEN_CELLS), -(-shape[1] // SEEN_CELLS))
    c = np.floor((seen - origin) / (resolution * SEEN_CELLS)).astype(np.intp)
    inside = (c[:, 0] >= 0) & (c[:, 0] < coarse_shape[0]) & (c[:, 1] >= 0) & (c[:, 1] < coarse_shape[1])
    coarse = np.zeros(coarse_shape, dtype=bool)
    coarse[c[inside, 0], c[inside, 1]] = True
    padded = np.pad(coarse, 1)  # and its 8 neighbours: samples that far apart leave no hole
    coarse = np.any([padded[1 + i:1 + i + coarse_shape[0], 1 + j:1 + j + coarse_shape[1]]
                     for i in (-1, 0, 1) for j in (-1, 0, 1)], axis=0)
    return np.repeat(np.repeat(coarse, SEEN_CELLS, axis=0), SEEN_CELLS, axis=1)[:shape[0], :shape[1]]


def field_reach(sigma: float, resolution: float, plane_reach: float = 0.0) -> float:
    """How far beyond its points a field is nonzero (6σ, :func:`_gaussian`; a wall's plane field as far
    as ``plane_reach`` along it), plus its zeroed border cell: a grid with this margin scores every
    pose exactly as a wider one (lookups beyond clip to the border; points in general position)."""
    return max(6.0 * sigma, plane_reach) + 2.0 * resolution


def _gaussian(distance2: np.ndarray, sigma: float) -> np.ndarray:
    """exp(−d²/2σ²) in float32 of squared distances, exactly 0 beyond 6σ (below 1.6e-8)."""
    g = np.exp(np.float32(-0.5 / sigma**2) * distance2)
    g[distance2 >= (6 * sigma) ** 2] = 0.0
    return g


def _pool_twice(fields: np.ndarray, shift: int) -> np.ndarray:
    """max(F[i, j], F[i + s, j], F[i, j + s], F[i + s, j + s]) over the last two axes, 0 beyond:
    the max over [i, i + 2s) from two windows [i, i + s) and [i + s, i + 2s) of the level below."""
    out = np.empty_like(fields)
    np.maximum(fields[:, :-shift, :], fields[:, shift:, :], out=out[:, :-shift, :])
    out[:, -shift:, :] = fields[:, -shift:, :]
    wider = np.empty_like(fields)
    np.maximum(out[:, :, :-shift], out[:, :, shift:], out=wider[:, :, :-shift])
    wider[:, :, -shift:] = out[:, :, -shift:]
    return wider
