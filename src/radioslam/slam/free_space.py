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
    """Terminal-frame sample points (F, 2), ``spacing`` apart, of the free space one scan shows:
    each arc's normal line from the terminal to ``stop`` short of its foot, and a disc of
    ``pose_radius`` around the terminal."""
    known = ~np.isnan(normals)
    phi, index = np.unique(normals[known], return_index=True)  # one line per arc (its points share φ)
    reach = np.linalg.norm(xy[known][index], axis=1) - stop
    phi, reach = phi[reach > 0], reach[reach > 0]
    count = np.ceil(reach / spacing).astype(np.int64)
    line = np.repeat(np.arange(len(phi)), count)
    along = (np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count)) * spacing
    samples = [np.stack([along * np.cos(phi[line]), along * np.sin(phi[line])], axis=1)]
    if pose_radius > 0:
        g = np.arange(-pose_radius, pose_radius + 1e-9, spacing)
        gx, gy = np.meshgrid(g, g, indexing="ij")
        disc = np.stack([gx.ravel(), gy.ravel()], axis=1)
        samples.append(disc[np.linalg.norm(disc, axis=1) <= pose_radius])
    return np.concatenate(samples)
