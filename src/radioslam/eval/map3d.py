"""3D map metrics (issue #16): a radio point cloud with heights against the scene's true surfaces, a
triangle mesh (the extruded walls, floor and ceiling, or a Mitsuba scene's furniture).

Each point's nearest face is found through a k-d tree of points sampled on the faces (scipy's
``cKDTree``, at most ``spacing_m`` apart), then its distance is the exact distance to that face's
plane, clipped to the face by the sample's offset. Points whose nearest face is horizontal (a floor,
a ceiling, a table or shelf top: |n_z| > cos 10°) give the height error z − z_face, signed (up > 0):
the error distribution of the elevation beams' heights.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from radioslam.scene.mesh import Mesh

HORIZONTAL_NZ = np.cos(np.radians(10.0))


@dataclass(frozen=True)
class SurfaceMatch:
    """Each point's nearest face, its distance to it and, for horizontal faces, its signed height error."""

    face: np.ndarray  # (P,) index into the mesh's faces
    distance_m: np.ndarray  # (P,)
    horizontal: np.ndarray  # (P,) bool: the nearest face is horizontal
    height_error_m: np.ndarray  # (P,) z − z_face where horizontal, NaN elsewhere
    surface_height_m: np.ndarray  # (P,) z of the nearest horizontal face, NaN elsewhere


def face_samples(mesh: Mesh, spacing_m: float) -> tuple[np.ndarray, np.ndarray]:
    """Points (S, 3) on every face, a barycentric grid at most ``spacing_m`` apart, and their face (S,)."""
    a, b, c = (mesh.vertices[mesh.faces[:, k]] for k in range(3))
    longest = np.max([np.linalg.norm(b - a, axis=1), np.linalg.norm(c - b, axis=1), np.linalg.norm(a - c, axis=1)],
                     axis=0)
    steps = np.maximum(1, np.ceil(longest / spacing_m)).astype(int)
    points, owners = [], []
    for n in np.unique(steps):  # faces grouped by grid size: a few groups
        faces = np.flatnonzero(steps == n)
        i, j = np.meshgrid(np.arange(n + 1), np.arange(n + 1), indexing="ij")
        keep = i + j <= n
        u, v = i[keep] / n, j[keep] / n  # (G,)
        grid = (a[faces, None] + u[:, None] * (b[faces, None] - a[faces, None])
                + v[:, None] * (c[faces, None] - a[faces, None]))  # (F', G, 3)
        points.append(grid.reshape(-1, 3))
        owners.append(np.repeat(faces, len(u)))
    return np.concatenate(points), np.concatenate(owners)


def face_planes(mesh: Mesh, faces: np.ndarray | slice = slice(None)) -> tuple[np.ndarray, np.ndarray]:
    """A vertex (F, 3) and the unit normal (F, 3) of each of ``faces`` (default: every face)."""
    a, b, c = (mesh.vertices[mesh.faces[faces, k]] for k in range(3))
    normal = np.cross(b - a, c - a)
    return a, normal / np.linalg.norm(normal, axis=1, keepdims=True)


def horizontal_surface_heights(mesh: Mesh) -> np.ndarray:
    """The heights (m) of the mesh's horizontal faces (floor, ceiling, table tops), each once, to the mm."""
    a, normal = face_planes(mesh)
    return np.unique(np.round(a[np.abs(normal[:, 2]) > HORIZONTAL_NZ, 2], 3))


def match_surfaces(points: np.ndarray, mesh: Mesh, spacing_m: float = 0.05) -> SurfaceMatch:
    """Each point (P, 3) against the mesh (world frame, z up)."""
    samples, owner = face_samples(mesh, spacing_m)
    _, nearest = cKDTree(samples).query(points)
    face = owner[nearest]
    a, normal = face_planes(mesh, face)
    off_plane = np.einsum("pk,pk->p", points - a, normal)
    in_plane = np.linalg.norm((points - off_plane[:, None] * normal) - samples[nearest], axis=1)
    # exact off the face's plane; along it, the distance beyond the nearest sample (within spacing/√2 of exact)
    distance = np.hypot(off_plane, np.maximum(in_plane - spacing_m / np.sqrt(2), 0.0))
    horizontal = np.abs(normal[:, 2]) > HORIZONTAL_NZ
    surface = np.where(horizontal, a[:, 2], np.nan)
    return SurfaceMatch(face, distance, horizontal, points[:, 2] - surface, surface)


def height_error_summary(match: SurfaceMatch) -> dict:
    """The height errors' distribution over the points nearest a horizontal face: count, median |e|,
    90th percentile |e|, mean (bias) and the 3D distance median over every point."""
    e = match.height_error_m[match.horizontal]
    if not len(e):
        return {"points": 0, "distance_median_m": float(np.median(match.distance_m))}
    surfaces = np.round(match.surface_height_m[match.horizontal], 2)
    return {**_spread(e), "distance_median_m": float(np.median(match.distance_m)),
            "by_surface_height_m": {f"{z:g}": _spread(e[surfaces == z]) for z in np.unique(surfaces)}}


def _spread(e: np.ndarray) -> dict:
    return {"points": int(len(e)), "median_abs_m": float(np.median(np.abs(e))),
            "p90_abs_m": float(np.percentile(np.abs(e), 90)), "bias_m": float(np.mean(e))}
