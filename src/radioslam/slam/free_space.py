"""Space a radio scan shows to be empty (issue #12): negative evidence for scan matching.

A wall's specular echo travels along the wall's normal from the terminal to the foot
and back; a strong specular echo at range r along bearing φ means that nothing opaque
stands on that line closer than r (the ray caster, like the world, stops at opaque walls).
So each arc's normal line, from the terminal to ``stop`` short of its foot, is free, and so
is a disc of ``pose_radius`` around the terminal itself. This is narrower than carving along
every beam's centre line: a beam is ~13° wide, and what it saw may lie anywhere across it
(the occupancy grid's trouble, issue #12 point 8); the specular line is where the echo was.

A candidate pose that puts scan points on known free space is contradicted by the map,
not merely unsupported: in a room of right angles, the 180° twin of the true pose explains
the walls about as well, but puts some of them across lines the terminal saw through.
"""

from __future__ import annotations

import numpy as np


def free_samples(xy: np.ndarray, normals: np.ndarray, stop: float, pose_radius: float, spacing: float) -> np.ndarray:
    """Terminal-frame sample points (F, 2) of the free space one scan shows: a disc of
    ``pose_radius`` around the terminal, then each arc's normal line from the disc's edge to
    ``stop`` short of its foot, ``spacing`` apart. The disc's samples lie on a square lattice
    √2 × ``spacing`` apart: a cell of side 2 × ``spacing`` (the grid's, at half-cell spacing) holds
    one of them however the scan is turned (the lattice's covering radius is half that side)."""
    samples = []
    start = 0.0
    if pose_radius > 0:
        g = np.arange(-pose_radius, pose_radius + 1e-9, np.sqrt(2) * spacing)
        gx, gy = np.meshgrid(g - g.mean(), g - g.mean(), indexing="ij")
        disc = np.stack([gx.ravel(), gy.ravel()], axis=1)
        samples.append(disc[np.linalg.norm(disc, axis=1) <= pose_radius])
        start = pose_radius
    known = ~np.isnan(normals)
    phi, index = np.unique(normals[known], return_index=True)  # one line per arc (its points share φ)
    reach = np.linalg.norm(xy[known][index], axis=1) - stop - start
    phi, reach = phi[reach > 0], reach[reach > 0]
    line, step = ragged_steps(np.ceil(reach / spacing).astype(np.int64))
    along = start + step * spacing
    samples.append(np.stack([along * np.cos(phi[line]), along * np.sin(phi[line])], axis=1))
    return np.concatenate(samples)


def seen_samples(xy: np.ndarray, spacing: float) -> np.ndarray:
    """Terminal-frame samples (S, 2) of the space one scan observed: along each point's ray from the
    terminal to its echo, ``spacing`` apart (the space its beams swept up to what they saw). Coarse by
    design: it tells space the map has observed from space it never saw (:mod:`radioslam.slam.measurement`),
    not where the surfaces are."""
    reach = np.linalg.norm(xy, axis=1)
    ray, step = ragged_steps(np.ceil(reach / spacing).astype(np.int64))
    along = step * spacing
    return xy[ray] * (along / np.maximum(reach[ray], 1e-12))[:, None]


def ragged_steps(count: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Lines of ``count`` (L,) samples each, flattened: each sample's line (N,) and its index along it (N,)."""
    line = np.repeat(np.arange(len(count)), count)
    return line, np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count)
