"""Specular surface normals of a radio scan (paper §IV-A, single target per beam).

A flat surface returns its strongest echo from the specular point, where its normal
faces the terminal; beams near that direction all see the echo through their main
lobe at the same range d, so a wall shows up as an *arc* of constant range around the
terminal, not as a line. The arc's geometry is blind to the terminal's rotation; its
power profile is not: the two-way beam gain peaks on the normal. Fitting a parabola
through the strongest beam and its two neighbours (in dB against beam angle) gives the
normal's bearing φ to about 0.1° (against a beam spacing of 1.8°).

Each point of such an arc (consecutive beams of one orientation, ranges within
``arc_range_m`` of each other, an interior power peak) carries the arc's φ; other
points carry NaN (no normal known).
"""

from __future__ import annotations

import numpy as np

from radioslam.sensing.pointcloud import Scan
from radioslam.slam.se2 import wrap_angle


def specular_normals(scan: Scan, arc_range_m: float) -> np.ndarray:
    """Terminal-frame bearing (P,) of the surface normal each point's echo came from; NaN: unknown."""
    return specular_arcs(scan, arc_range_m)[0]


def specular_arcs(scan: Scan, arc_range_m: float) -> tuple[np.ndarray, np.ndarray]:
    """The normals of :func:`specular_normals` (P,), and each specular arc's sighting of its
    surface (A, 2): the normal's terminal-frame bearing φ and the range of the arc's strongest
    point, the specular foot's distance (the surface is the line n(φ)·x = r in the terminal
    frame: what :mod:`radioslam.slam.plane_adjustment` adjusts)."""
    normals = np.full(len(scan), np.nan)
    if len(scan) < 3:
        return normals, np.zeros((0, 2))
    order = np.lexsort((scan.beam, scan.orientation))
    beam, orient = scan.beam[order], scan.orientation[order]
    rng, power = scan.range_m[order], scan.power_db[order]
    boresight = orient * (np.pi / 2)
    angle = wrap_angle(scan.angle_rad[order] - boresight)  # off this orientation's boresight: no ±π seam
    # arcs: runs of consecutive beams on one orientation at one range
    breaks = (np.diff(beam) != 1) | (np.diff(orient) != 0) | (np.abs(np.diff(rng)) > arc_range_m)
    arc = np.concatenate([[0], np.cumsum(breaks)])
    start = np.flatnonzero(np.concatenate([[True], breaks]))
    end = np.concatenate([start[1:], [len(arc)]])
    # the strongest point of each arc and whether it has a neighbour on both sides
    strongest = np.flatnonzero(power == np.maximum.reduceat(power, start)[arc])
    peak = strongest[np.unique(arc[strongest], return_index=True)[1]]
    interior = (peak > start) & (peak < end - 1)
    k = peak[interior]
    x = np.stack([angle[k - 1], angle[k], angle[k + 1]], axis=1)
    y = np.stack([power[k - 1], power[k], power[k + 1]], axis=1)
    # vertex of the parabola through three points (unequal spacing: beams are uniform in sin)
    d01, d12 = (y[:, 1] - y[:, 0]) / (x[:, 1] - x[:, 0]), (y[:, 2] - y[:, 1]) / (x[:, 2] - x[:, 1])
    curvature = (d12 - d01) / (x[:, 2] - x[:, 0])
    vertex = 0.5 * (x[:, 0] + x[:, 1]) - d01 / (2 * np.minimum(curvature, -1e-12))
    bearing = wrap_angle(np.clip(vertex, x[:, 0], x[:, 2]) + boresight[k])  # each arc's normal, terminal frame
    wall = oblique_walls(bearing, rng[k], arc_range_m)
    arc_normal = np.full(len(start), np.nan)
    arc_normal[interior] = np.where(wall >= 0, bearing[wall], bearing)
    normals[order] = arc_normal[arc]
    return normals, np.stack([bearing, rng[k]], axis=1)[wall < 0]


def oblique_walls(bearing: np.ndarray, foot_range: np.ndarray, tolerance: float,
                  max_angle: float = np.radians(75.0)) -> np.ndarray:
    """For each arc (normal ``bearing``, peak range ``foot_range``), the nearer arc whose wall line it
    lies on (−1: none): a beam at θ meets the wall of normal ψ and foot range ρ at range ρ / cos(θ − ψ),
    so an arc there at r with r·cos(φ − ψ) = ρ (within ``tolerance``) is that wall seen obliquely,
    its power peaking on another orientation's pattern rather than on the wall's normal. It carries
    that wall's normal, not a false one (a false normal made the nearest-normal lookups of a walk
    along a wall prefer a zero step), and is no sighting of a wall of its own."""
    if len(bearing) == 0:
        return np.zeros(0, dtype=np.intp)
    turn = wrap_angle(bearing[:, None] - bearing[None, :])
    on_line = np.abs(foot_range[:, None] * np.cos(turn) - foot_range[None, :]) <= tolerance
    oblique = on_line & (foot_range[None, :] < foot_range[:, None] - tolerance) & (np.abs(turn) < max_angle)
    nearest = np.argmin(np.where(oblique, foot_range[None, :], np.inf), axis=1)  # the nearest such wall
    return np.where(oblique.any(axis=1), nearest, -1)


def wall_points(scan: Scan, normals: np.ndarray) -> np.ndarray:
    """Terminal-frame points (P, 2) with each arc point moved to where its beam meets the
    arc's wall: the line through the specular foot (range r, bearing φ) normal to φ, at
    range r / cos(θ − φ) along the beam θ. Points without a normal stay where they are."""
    known = ~np.isnan(normals)
    stretch = np.ones(len(scan))
    stretch[known] = 1.0 / np.cos(scan.angle_rad[known] - normals[known])
    return scan.xy * stretch[:, None]
