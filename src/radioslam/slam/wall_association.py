"""Which wall each specular sighting is of: data association for the plane bundle adjustment
(:mod:`radioslam.slam.plane_adjustment`).

A sighting (bearing φ, range r) from pose (x, y, θ) is the world line ψ = θ + φ,
d = r + n(ψ)·(x, y). In scan order, each sighting joins the wall whose (ψ, d) is nearest within
the gates at the pose graph's poses (one sighting per wall and scan: a scan that sees two
surfaces on one line sees two walls), or starts a new wall; each wall is the running mean of its
sightings, and one seen from fewer than ``min_sightings`` scans is left out.

The gates must hold the pose graph's errors (centimetres, tenths of a degree; 0.2 m and 1.3° where
it is worst), so a "ghost" wall (a metal shelf's double bounce, 0.3 m in front of a real wall) can
join the real one: the adjustment estimates each wall's own noise, and such a mixture is weighed
as the poor wall it is.
"""

from __future__ import annotations

import numpy as np

from radioslam.slam.se2 import wrap_angle


def world_lines(poses: np.ndarray, observed: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """World normal bearing ψ (S,) and offset d (S,) of sightings (S, 2: φ, r) from ``poses`` (S, 3)."""
    psi = wrap_angle(poses[:, 2] + observed[:, 0])
    return psi, observed[:, 1] + np.cos(psi) * poses[:, 0] + np.sin(psi) * poses[:, 1]


def wall_means(poses: np.ndarray, scan: np.ndarray, observed: np.ndarray, wall: np.ndarray,
               walls: int) -> tuple[np.ndarray, np.ndarray]:
    """Each of ``walls`` walls' (ψ, d) (L, 2) as the circular and plain means of the sightings labelled
    ``wall`` (S,), seen from ``poses[scan]``, and how many sightings each has (L,; 0: (0, 0))."""
    psi, d = world_lines(poses[scan], observed)
    counts = np.bincount(wall, minlength=walls)
    mean_psi = np.angle(np.bincount(wall, np.cos(psi), walls) + 1j * np.bincount(wall, np.sin(psi), walls))
    return np.stack([mean_psi, np.bincount(wall, d, walls) / np.maximum(counts, 1)], axis=1), counts


def associate(poses: np.ndarray, scan: np.ndarray, observed: np.ndarray, gate_rad: float, gate_m: float,
              min_sightings: int) -> np.ndarray:
    """The wall (S,) of each sighting (scan index (S,), observed (S, 2)) seen from ``poses`` (P, 3),
    −1 for none, numbered densely."""
    psi, offset = world_lines(poses[scan], observed)
    label = np.full(len(scan), -1)
    walls = np.zeros((0, 2))  # (ψ, d) running means
    counts = np.zeros(0)
    for k in np.unique(scan):  # a loop over scans; each scan's sightings against every wall at once
        rows = np.flatnonzero(scan == k)
        taken = nearest_walls(psi[rows], offset[rows], walls, gate_rad, gate_m)
        new = np.flatnonzero(taken < 0)
        taken[new] = len(walls) + np.arange(len(new))
        walls = np.concatenate([walls, np.stack([psi[rows[new]], offset[rows[new]]], axis=1)])
        counts = np.concatenate([counts, np.zeros(len(new))])
        counts[taken] += 1  # one sighting per wall and scan
        w = 1.0 / counts[taken]  # running means (a new wall: its own sighting)
        walls[taken, 0] = wrap_angle(walls[taken, 0] + w * wrap_angle(psi[rows] - walls[taken, 0]))
        walls[taken, 1] += w * (offset[rows] - walls[taken, 1])
        label[rows] = taken
    # walls seen from too few scans carry nothing: dropped, the others numbered densely
    kept = np.bincount(label, minlength=len(walls)) >= min_sightings
    renumber = np.where(kept, np.cumsum(kept) - 1, -1)
    return renumber[label]


def nearest_walls(psi: np.ndarray, offset: np.ndarray, walls: np.ndarray, gate_rad: float,
                  gate_m: float) -> np.ndarray:
    """Each sighting's nearest wall within the gates (distance in gate units; nearest pairs first,
    one sighting per wall), −1 for none."""
    d_psi = wrap_angle(psi[:, None] - walls[None, :, 0])
    d_off = offset[:, None] - walls[None, :, 1]
    gap = np.hypot(d_psi / gate_rad, d_off / gate_m)
    gap[(np.abs(d_psi) > gate_rad) | (np.abs(d_off) > gate_m)] = np.inf
    taken = np.full(len(psi), -1)
    for i in np.argsort(gap.min(axis=1, initial=np.inf), kind="stable"):  # a scan's few sightings
        if gap.shape[1] and np.isfinite(gap[i].min()):
            taken[i] = int(np.argmin(gap[i]))
            gap[:, taken[i]] = np.inf
    return taken
