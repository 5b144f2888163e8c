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


def specular_normals(scan: Scan, arc_range_m: float, seam_gap_rad: float) -> np.ndarray:
    """Terminal-frame bearing (P,) of the surface normal each point's echo came from; NaN: unknown."""
    return specular_arcs(scan, arc_range_m, seam_gap_rad)[0]


def arc_runs(scan: Scan, arc_range_m: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The scan's arcs: runs of consecutive beams on one orientation at one range (within ``arc_range_m``),
    one echo seen through adjacent beams. Returns the order (P,) that sorts the points by orientation and
    beam, each sorted point's arc (P,), and each arc's start and end (A,) in that order."""
    order = np.lexsort((scan.beam, scan.orientation))
    beam, orient, rng = scan.beam[order], scan.orientation[order], scan.range_m[order]
    breaks = (np.diff(beam) != 1) | (np.diff(orient) != 0) | (np.abs(np.diff(rng)) > arc_range_m)
    arc = np.concatenate([[0], np.cumsum(breaks)]) if len(scan) else np.zeros(0, dtype=np.intp)
    start = np.flatnonzero(np.concatenate([[True], breaks])) if len(scan) else np.zeros(0, dtype=np.intp)
    end = np.concatenate([start[1:], [len(arc)]])
    return order, arc, start, end


def echo_weights(scan: Scan, arc_range_m: float) -> np.ndarray:
    """Each point's share (P,) of one independent observation: 1/n for the n points of an arc (the beams
    that see one echo of one surface through their overlapping main lobes and sidelobes, their ranges one
    measurement), 1 for a point alone."""
    order, arc, start, end = arc_runs(scan, arc_range_m)
    weights = np.empty(len(scan))
    weights[order] = 1.0 / (end - start)[arc]
    return weights


def specular_arcs(scan: Scan, arc_range_m: float, seam_gap_rad: float) -> tuple[np.ndarray, np.ndarray]:
    """The normals of :func:`specular_normals` (P,), and each specular arc's sighting of its
    surface (A, 2): the normal's terminal-frame bearing φ and the range of the arc's strongest
    point, the specular foot's distance (the surface is the line n(φ)·x = r in the terminal
    frame: what :mod:`radioslam.slam.plane_adjustment` adjusts).

    A wall whose normal lies between two orientations' sectors (45° off both boresights, a terminal
    held at 45° to the room) peaks on the last beam of each: neither arc has an interior peak. Two such
    arcs of adjacent orientations at one range, their peaks within ``seam_gap_rad``, are fitted together:
    the parabola through their strongest point and its nearest neighbour on each side (one sighting).
    An edge arc beside an arc peaking inside its sector keeps no normal (taking that arc's: tried, worse:
    such an arc is often another surface's or an oblique view's)."""
    normals = np.full(len(scan), np.nan)
    if len(scan) < 3:
        return normals, np.zeros((0, 2))
    order, arc, start, end = arc_runs(scan, arc_range_m)
    orient = scan.orientation[order]
    rng, power, absolute = scan.range_m[order], scan.power_db[order], wrap_angle(scan.angle_rad[order])
    boresight = orient * (np.pi / 2)
    angle = wrap_angle(absolute - boresight)  # off this orientation's boresight: no ±π seam
    # the strongest point of each arc and whether it has a neighbour on both sides
    strongest = np.flatnonzero(power == np.maximum.reduceat(power, start)[arc])
    peak = strongest[np.unique(arc[strongest], return_index=True)[1]]
    interior = (peak > start) & (peak < end - 1)
    k = peak[interior]
    vertex = parabola_vertex(np.stack([angle[k - 1], angle[k], angle[k + 1]], axis=1),
                             np.stack([power[k - 1], power[k], power[k + 1]], axis=1))
    # each fit: its normal (terminal frame), its foot's range, and the arcs it holds (second: −1 if one)
    bearing, foot = wrap_angle(vertex + boresight[k]), rng[k]
    first, second = np.flatnonzero(interior), np.full(len(k), -1)
    pairs = seam_partners(orient[peak], absolute[peak], rng[peak], ~interior & ((end - start) >= 2), arc_range_m,
                          seam_gap_rad)
    if len(pairs):
        seam_bearing, seam_foot = seam_fits(arc, pairs, power, absolute, rng)
        fits = ~np.isnan(seam_bearing)  # both arcs' points on one side only: no vertex
        pairs, seam_bearing, seam_foot = pairs[fits], seam_bearing[fits], seam_foot[fits]
        bearing, foot = np.concatenate([bearing, seam_bearing]), np.concatenate([foot, seam_foot])
        first, second = np.concatenate([first, pairs[:, 0]]), np.concatenate([second, pairs[:, 1]])
    wall = oblique_walls(bearing, foot, arc_range_m)
    fitted = np.where(wall >= 0, bearing[wall], bearing)
    arc_normal = np.full(len(start), np.nan)
    arc_normal[first] = fitted
    arc_normal[second[second >= 0]] = fitted[second >= 0]
    normals[order] = arc_normal[arc]
    return normals, np.stack([bearing, foot], axis=1)[wall < 0]


def parabola_vertex(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """The vertex (F,) of the parabola through three points per row (x, y: (F, 3), x increasing, the
    middle one the highest), clipped to the outer two: spacing may be unequal (beams uniform in sin)."""
    d01, d12 = (y[:, 1] - y[:, 0]) / (x[:, 1] - x[:, 0]), (y[:, 2] - y[:, 1]) / (x[:, 2] - x[:, 1])
    curvature = (d12 - d01) / (x[:, 2] - x[:, 0])
    vertex = 0.5 * (x[:, 0] + x[:, 1]) - d01 / (2 * np.minimum(curvature, -1e-12))
    return np.clip(vertex, x[:, 0], x[:, 2])


def seam_partners(orient: np.ndarray, absolute: np.ndarray, foot: np.ndarray, edge: np.ndarray,
                  arc_range_m: float, gap_rad: float) -> np.ndarray:
    """Per arc (A,): its orientation, its peak's terminal-frame bearing and range, whether it peaks on
    its sector's edge. The pairs (Q, 2) of edge arcs of adjacent orientations at one range (within
    ``arc_range_m``) whose peaks lie within ``gap_rad`` of each other, each the other's nearest."""
    gap = np.abs(wrap_angle(absolute[:, None] - absolute[None, :]))
    near = edge[:, None] & edge[None, :] & np.isin((orient[:, None] - orient[None, :]) % 4, (1, 3)) & \
        (np.abs(foot[:, None] - foot[None, :]) <= arc_range_m) & (gap <= gap_rad)
    partner = np.where(near.any(axis=1), np.argmin(np.where(near, gap, np.inf), axis=1), -1)
    arcs = np.arange(len(orient))
    first = np.flatnonzero((partner > arcs) & (partner[np.maximum(partner, 0)] == arcs))  # mutual, counted once
    return np.stack([first, partner[first]], axis=1)


def seam_fits(arc: np.ndarray, pairs: np.ndarray, power: np.ndarray, absolute: np.ndarray,
              rng: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The normal (Q,) and foot range (Q,) of each pair of arcs (Q, 2) met at a seam: the parabola
    through their strongest point and its nearest neighbour on each side in bearing (NaN where one
    side has none)."""
    pair_of_arc = np.full(int(arc.max()) + 1, -1)
    pair_of_arc[pairs[:, 0]] = pair_of_arc[pairs[:, 1]] = np.arange(len(pairs))
    member = np.flatnonzero(pair_of_arc[arc] >= 0)
    pid = pair_of_arc[arc[member]]
    by_power = member[np.lexsort((-power[member], pid))]
    top = by_power[np.unique(pair_of_arc[arc[by_power]], return_index=True)[1]]  # (Q,) each pair's strongest
    offset = wrap_angle(absolute[member] - absolute[top[pid]])
    x, y = np.full((len(pairs), 3), np.nan), np.full((len(pairs), 3), np.nan)
    x[:, 1], y[:, 1] = 0.0, power[top]
    for column, side in ((0, offset < 0), (2, offset > 0)):
        nearest = np.lexsort((np.abs(offset[side]), pid[side]))  # per pair, nearest first
        pick = nearest[np.unique(pid[side][nearest], return_index=True)[1]]
        x[pid[side][pick], column] = offset[side][pick]
        y[pid[side][pick], column] = power[member[side][pick]]
    bearing = wrap_angle(absolute[top] + parabola_vertex(x, y))
    return np.where(np.isnan(x).any(axis=1), np.nan, bearing), rng[top]


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

