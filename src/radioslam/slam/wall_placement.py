"""A scan the front end could not place (its pose is the motion model's), placed on the walls the
other scans sighted: a two-line registration (RANSAC, Fischler & Bolles 1981, over pairs of
sighting–wall pairings) of its specular sightings, for the plane adjustment
(:mod:`radioslam.slam.plane_adjustment`).

A sighting (φ, r) from pose (x, y, θ) is the line ψ = θ + φ, d = r + n(ψ)·(x, y). Every pairing of a
sighting with a wall within ``search_rad`` proposes a heading correction δθ = ψ_wall − ψ; under it,
two pairings with walls that are not parallel fix the translation δt (two equations
n_L·δt = d_L − d). The correction that puts most sightings on distinct walls within the gates wins,
if it puts at least ``min_inliers`` there, on walls of two directions, and no correction farther
than the gates from it puts as many (a symmetric room's twin leaves the scan where it was).
"""

from __future__ import annotations

import numpy as np

from radioslam.slam.se2 import wrap_angle
from radioslam.slam.wall_association import nearest_walls, world_lines


def place(pose: np.ndarray, observed: np.ndarray, walls: np.ndarray, search_rad: float, search_m: float,
          gate_rad: float, gate_m: float, min_inliers: int = 3) -> tuple[np.ndarray, np.ndarray] | None:
    """The corrected pose (3,) of a scan at ``pose`` with sightings ``observed`` (A, 2) on ``walls``
    (L, 2: ψ, d), and the wall of each sighting (A,; −1 for none); None where no correction within
    ±``search_m`` / ±``search_rad`` puts its sightings on the walls unambiguously."""
    if len(observed) < min_inliers or not len(walls):
        return None
    psi, _ = world_lines(np.broadcast_to(pose, (len(observed), 3)), observed)
    turns = wrap_angle(walls[None, :, 0] - psi[:, None])
    proposals = np.unique(np.round(turns[np.abs(turns) <= search_rad] / (gate_rad / 2)) * (gate_rad / 2))
    found = []  # (inliers, residual, correction)
    for turn in proposals:  # a few dozen headings; every pair of pairings at once under each
        found += _translations(pose, observed, walls, turn, search_m, gate_rad, gate_m)
    if not found:
        return None
    found.sort(key=lambda f: (-f[0], f[1]))
    inliers, _, best = found[0]
    rivals = [c for n, _, c in found[1:] if n == inliers and (np.hypot(*(c[:2] - best[:2])) > gate_m
                                                                   or abs(wrap_angle(c[2] - best[2])) > gate_rad)]
    if inliers < min_inliers or rivals:
        return None
    corrected = pose + best
    psi, d = world_lines(np.broadcast_to(corrected, (len(observed), 3)), observed)
    labels = nearest_walls(psi, d, walls, gate_rad, gate_m)
    seen = walls[labels[labels >= 0], 0]
    if np.max(np.abs(np.sin(seen[:, None] - seen[None, :])), initial=0.0) < 0.5:  # one direction: slides
        return None
    return corrected, labels


def _translations(pose: np.ndarray, observed: np.ndarray, walls: np.ndarray, turn: float, search_m: float,
                  gate_rad: float, gate_m: float) -> list[tuple[int, float, np.ndarray]]:
    """Under the heading correction ``turn``, the translation of each pair of non-parallel pairings,
    with the number of sightings it puts on distinct walls and their summed gate-normalized offset."""
    turned = pose + np.array([0.0, 0.0, turn])
    psi, d = world_lines(np.broadcast_to(turned, (len(observed), 3)), observed)
    a, w = np.nonzero(np.abs(wrap_angle(psi[:, None] - walls[None, :, 0])) <= gate_rad)
    i, j = np.triu_indices(len(a), 1)
    normal = np.stack([np.cos(walls[w, 0]), np.sin(walls[w, 0])], axis=1)
    det = normal[i, 0] * normal[j, 1] - normal[i, 1] * normal[j, 0]
    ok = (a[i] != a[j]) & (np.abs(det) > 0.5)  # two sightings, on walls at least 30° apart
    i, j, det = i[ok], j[ok], det[ok]
    rhs_i, rhs_j = walls[w[i], 1] - d[a[i]], walls[w[j], 1] - d[a[j]]
    shift = np.stack([(rhs_i * normal[j, 1] - rhs_j * normal[i, 1]) / det,
                      (normal[i, 0] * rhs_j - normal[j, 0] * rhs_i) / det], axis=1)
    shift = shift[np.linalg.norm(shift, axis=1) <= search_m]
    shift = np.unique(np.round(shift / (gate_m / 4)), axis=0) * (gate_m / 4)  # one per quarter gate
    out = []
    for t in shift:  # each candidate scored by the distinct walls its sightings land on
        moved = turned + np.array([t[0], t[1], 0.0])
        p2, d2 = world_lines(np.broadcast_to(moved, (len(observed), 3)), observed)
        labels = nearest_walls(p2, d2, walls, gate_rad, gate_m)
        hit = labels >= 0
        offset = np.abs(d2[hit] - walls[labels[hit], 1]).sum() / gate_m
        out.append((int(hit.sum()), float(offset), moved - pose))
    return out
