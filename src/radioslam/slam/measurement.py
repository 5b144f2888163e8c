"""The measurement model (issue #47): the log-likelihood of a scan at a pose given a map, one number that
the front end's candidates compare as a likelihood ratio (Olson 2009 §III's correlative
log-likelihood, with the radio scan's correlations counted).

Each point's term is the likelihood field's value L at the point (:mod:`radioslam.slam.grid`: a Gaussian
of its distance to the nearest mapped surface, point-to-plane along a specular normal, times the normals'
agreement), floored at ``LIKELIHOOD_FLOOR`` (a point 3σ or more from every mapped surface: unexplained, a
surface the map does not hold), and twice the floor's log on space the map saw through (contradicted:
a wall where the map's echoes passed). Where the map never looked (no beam of its scans swept the cell)
a point is neither explained nor contradicted: it scores the prior likelihood of a surface there, the
field's mean over the space the map did observe (the likelihood field marginalized over an unknown map;
``LikelihoodGrid.neutral``), or the floor if that is higher. For a point on a specular arc (its surface's
orientation known) "looked" means more: some viewpoint of the map met that surface within 30° of its
normal (:func:`faced`); a wall parallel to every line of sight the map had (a side corridor's walls seen
from the corridor it branches off) is unseen however many beams crossed its place. An exploring pose,
whose new walls lie where the map never looked, then no longer loses to a twin that lays them over
mapped walls for that alone.

The points of one specular arc are one echo of one surface seen through adjacent beams (their ranges
are one measurement, their bearings the beams' pointing): counted as independent they would be
over-confident by the arc's length, so each point weighs 1/n of its arc's n
(:func:`radioslam.slam.normals.echo_weights`): the scan's evidence is that of its independent echoes.

The scan's own beams count too (a beam that sees through a mapped wall): a specular echo at range r
along bearing φ says that the line from the terminal to its wall's foot is clear (the echo's path went
there and back). Where the pose lays that line across a surface the map holds, one of the two is wrong:
each sighting's line, up to ``stop`` short of its foot (the free space's stop, :mod:`radioslam.slam.free_space`),
scores log(1 − (1 − floor)·q), q the map's largest likelihood value on it (the probability that a mapped
surface stands there), one observation per sighting (:func:`line_log_likelihoods`). A twin that lays the
scan's walls over the map's explains its points, and is caught by the lines it draws through them.

Calibration (``benchmarks/bench_measurement.py``, docs/notes.md session 29): over 3,100 scans of the
benchmark's four families, the true pose's mode against the distinct rivals branch and bound finds within
one step (truth-posed local maps), the log loss of the true pose is lowest with the log-likelihoods scaled
by ``TEMPERATURE``: the raw sums are somewhat over-confident (each echo is not fully independent of its
neighbours: one wall seen by two orientations' beams, a corner's two arcs), and scaled they compare as
likelihood ratios.
"""

from __future__ import annotations

import numpy as np

from radioslam.slam.free_space import ragged_steps
from radioslam.slam.grid import LIKELIHOOD_FLOOR, LikelihoodGrid
from radioslam.slam.refine import fit_terms

LOG_FLOOR = float(np.log(LIKELIHOOD_FLOOR))
# the largest incidence at which a wall shows in a scan: the sensing's −13 dB rule keeps diffuse echoes of
# walls met within about 30° of their normal (docs/architecture.md, § Echo model)
DETECTABLE_INCIDENCE = np.radians(30.0)
COS_DETECTABLE = float(np.cos(DETECTABLE_INCIDENCE))
# the log-likelihoods' scale that minimizes the true pose's log loss among its rivals (benchmarks/bench_measurement.py)
TEMPERATURE = 0.6


def point_log_likelihoods(values: np.ndarray, unseen: np.ndarray | bool = False, neutral: float = 0.0) -> np.ndarray:
    """Per point (any shape): log max(L, floor), or log max(L, neutral) where the map never looked
    (``unseen``), and 2·log floor where L < 0 (space the map saw through)."""
    floor = np.where(unseen, max(neutral, LIKELIHOOD_FLOOR), LIKELIHOOD_FLOOR)
    return np.where(values < 0, 2 * LOG_FLOOR, np.log(np.maximum(values, floor)))


def scan_log_likelihoods(grid: LikelihoodGrid, points: np.ndarray, normals: np.ndarray, weights: np.ndarray,
                         poses: np.ndarray, sightings: np.ndarray | None = None, stop: float = 0.0) -> np.ndarray:
    """log p(scan | pose, map) (C,) at each of ``poses`` (C, 3), up to a constant shared by every pose:
    the weighted sum of the points' terms on the interpolated field, plus the terms of the ``sightings``'
    (A, 2: bearing, range) clear lines (:func:`line_log_likelihoods`), times ``TEMPERATURE``."""
    poses = np.atleast_2d(np.asarray(poses, dtype=np.float64))
    lines = 0.0 if sightings is None else line_log_likelihoods(grid, sightings, poses, stop)
    return TEMPERATURE * (point_terms(grid, points, normals, weights, poses) + lines)


def point_terms(grid: LikelihoodGrid, points: np.ndarray, normals: np.ndarray, weights: np.ndarray,
                poses: np.ndarray) -> np.ndarray:
    """The points' share (C,) of the log-likelihood, unscaled: their terms on the interpolated field, weighted."""
    residual, _ = fit_terms(grid, points, normals, poses)
    unseen = False
    if grid.seen is not None:
        c, s = np.cos(poses[:, 2:3]), np.sin(poses[:, 2:3])
        world = np.stack([c * points[:, 0] - s * points[:, 1] + poses[:, 0:1],
                          s * points[:, 0] + c * points[:, 1] + poses[:, 1:2]], axis=-1)
        cells = grid.cells(world)
        unseen = ~grid.seen[cells[..., 0], cells[..., 1]]
        if grid.viewpoints is not None and len(grid.viewpoints):
            unseen = np.where(np.isnan(normals), unseen, ~faced(world, poses[:, 2:3] + normals, grid.viewpoints))
    return point_log_likelihoods(1.0 - residual, unseen, grid.neutral) @ weights


def line_log_likelihoods(grid: LikelihoodGrid, sightings: np.ndarray, poses: np.ndarray, stop: float) -> np.ndarray:
    """Σ_a log(1 − (1 − floor)·q_a) (C,) at each of ``poses`` (C, 3): q_a the largest point-field value
    (the likelihood of a mapped surface there) on sighting a's line from the terminal along its bearing to
    ``stop`` short of its range, sampled every half cell; a line that ends before it starts is its
    terminal alone."""
    if not len(sightings):
        return np.zeros(len(poses))
    phi, reach = sightings[:, 0], np.maximum(sightings[:, 1] - stop, 0.0)
    count = np.ceil(reach / (grid.resolution / 2)).astype(np.int64) + 1  # both ends sampled
    line, step = ragged_steps(count)
    first = np.cumsum(count) - count
    along = np.minimum(step * (grid.resolution / 2), reach[line])
    heading = poses[:, 2:3] + phi[line]
    world = np.stack([poses[:, 0:1] + along * np.cos(heading), poses[:, 1:2] + along * np.sin(heading)], axis=-1)
    cells = grid.cells(world)
    surface = np.maximum(grid.values[cells[..., 0], cells[..., 1]], 0.0)  # (C, S); free space holds none
    q = np.maximum.reduceat(surface, first, axis=1)  # (C, A) each line's largest
    return np.log1p(-(1.0 - LIKELIHOOD_FLOOR) * q).sum(axis=1)


def faced(world: np.ndarray, bearing: np.ndarray, viewpoints: np.ndarray) -> np.ndarray:
    """Whether a surface at each point (C, P, 2), facing back along the world ``bearing`` (C, P) of its
    specular normal, lay within reach of a viewpoint (J, 3: x, y, reach) that met it within
    ``DETECTABLE_INCIDENCE`` of its normal: a wall the map would have shown. A radio beam meeting a wall
    more obliquely returns too little (specular energy goes on, the diffuse lobe falls below the −13 dB
    rule): the map's silence there says nothing, however many of its beams crossed the place."""
    rel = world[:, :, None, :] - viewpoints[None, None, :, :2]  # (C, P, J, 2) from each viewpoint to the point
    distance = np.linalg.norm(rel, axis=-1)
    along = rel[..., 0] * np.cos(bearing)[..., None] + rel[..., 1] * np.sin(bearing)[..., None]
    return np.any((along >= COS_DETECTABLE * distance) & (distance <= viewpoints[:, 2]), axis=-1)
