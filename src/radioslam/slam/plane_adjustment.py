"""Plane bundle adjustment: every pose refined jointly with the walls its specular arcs face.

A specular arc (:mod:`radioslam.slam.normals`) is a direct sighting of a surface: the wall is the
line n(φ)·x = r in the terminal frame, φ to ≈ 0.2° from the arc's power profile and r to
≈ 1.5 cm from its strongest echo (paper-cnv at 10 dB, measured at the true poses). In the world
frame a sighting from pose (x, y, θ) is the line of normal bearing ψ = θ + φ at offset
d = r + n(ψ)·(x, y) from the origin: the same (ψ, d) from every pose that sees that wall. The
mirror image of the terminal in that wall is the "virtual anchor" of multipath SLAM (Leitinger
et al., "A belief propagation algorithm for multipath-based SLAM", IEEE TWC 2019); here the wall
itself is the landmark, as planes are in LiDAR bundle adjustment (Liu & Zhang, "BALM", RA-L 2021;
Zhou et al., "π-LSAM", ICRA 2021).

After the pose graph, the sightings are associated to walls (gated, in scan order), and poses and
walls are solved together: for sighting s of wall L from pose k the residuals are

    e_ψ = (θ_k + φ_s − ψ_L) / σ_ψ,      e_d = (r_s + cos ψ_L·x_k + sin ψ_L·y_k − d_L) / σ_d,

weighted by Tukey's biweight of their norm (an outlier sighting, a wrong association, fades out
smoothly: no cliff), plus between factors holding the pose graph's own steps at the front end's
step covariances inflated (the scans' information is already in them: not counted twice at full
weight). The steps keep the scans that see no wall; where walls are seen, they fix the pose to
about a centimetre. Each solve is Levenberg–Marquardt on the sparse normal equations
(scipy.sparse): gtsam has no 2D plane landmark factor, and a Python ``CustomFactor`` per sighting
would loop over sightings in Python.

Why it matters beyond accuracy: the front end's discrete choices (lattice leaves, basins of the
field) make the pose graph's result chaotic in its inputs (issue #12, point 6); this last solve
is smooth in the sightings, so a micrometre on the ranges moves its result by micrometres
wherever the walls, not the front end, fix the poses.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
from scipy.integrate import trapezoid
from scipy.sparse.linalg import spsolve

from radioslam.slam.config import PlaneAdjustmentConfig
from radioslam.slam.errors import SlamError
from radioslam.slam.se2 import between, compose, inverse, wrap_angle
from radioslam.slam.wall_association import associate, wall_means
from radioslam.slam.wall_placement import place


@dataclass(frozen=True)
class PlaneAdjustmentResult:
    poses: np.ndarray  # (P, 3) refined
    walls: np.ndarray  # (L, 2) world normal bearing ψ and offset d of each wall landmark
    sightings_used: int  # sightings with a positive weight at the solution
    sightings: int  # sightings of every scan
    placed: list[int] = field(default_factory=list)  # unplaced scans the walls placed


class PlaneAdjustment:
    """Built from plain settings by :meth:`from_config`; :meth:`refine` after the pose graph."""

    def __init__(self, sigma: np.ndarray, gate_rad: float, gate_m: float, min_sightings: int, robust_c: float,
                 anchor_sigma: np.ndarray, step_inflation: float, iterations: int, search_rad: float, search_m: float,
                 loose_sigma: np.ndarray, degenerate_search_rad: float):
        self.sigma, self.gate_rad, self.gate_m, self.min_sightings = sigma, gate_rad, gate_m, min_sightings
        self.robust_c, self.anchor_sigma, self.loose_sigma = robust_c, anchor_sigma, loose_sigma
        self.search_rad, self.search_m, self.degenerate_search_rad = search_rad, search_m, degenerate_search_rad
        self.step_inflation, self.iterations = step_inflation, iterations

    @classmethod
    def from_config(cls, cfg: PlaneAdjustmentConfig) -> "PlaneAdjustment":
        return cls(np.array([np.radians(cfg.bearing_sigma_deg), cfg.range_sigma_m]), np.radians(cfg.gate_deg),
                   cfg.gate_m, cfg.min_sightings, cfg.robust_c,
                   np.array([cfg.anchor_sigma_m, cfg.anchor_sigma_m, np.radians(cfg.anchor_sigma_deg)]),
                   cfg.step_inflation, cfg.iterations, np.radians(cfg.place_search_deg), cfg.place_search_m,
                   np.array([cfg.loose_sigma_m, cfg.loose_sigma_m, np.radians(cfg.loose_sigma_deg)]),
                   np.radians(cfg.degenerate_search_deg))

    def refine(self, poses: np.ndarray, sightings: list[np.ndarray], step_covariance: dict[int, np.ndarray],
               unplaced: np.ndarray | None = None, degenerate: np.ndarray | None = None,
               pose_sigma: np.ndarray | None = None,
               odometry_covariance: np.ndarray | None = None) -> PlaneAdjustmentResult:
        """Poses (P, 3) refined with the scans' sightings (A_k, 2: bearing, range) of walls;
        ``step_covariance[k]`` is the covariance of the step into pose k in pose k − 1's frame;
        ``unplaced`` (P,) marks the poses the front end left to the motion model (predicted,
        skipped): each is first placed on the walls the others sighted
        (:func:`radioslam.slam.wall_placement.place`) and held to the pose graph only loosely;
        ``degenerate`` (P,) marks the poses the front end fixed in heading and across the walls only:
        each is placed within ±``degenerate_search`` of its heading and, once placed, held as loosely;
        ``pose_sigma`` (P, 3) is the pose graph's marginal σ of each pose (None: the anchor's alone);
        ``odometry_covariance`` (3, 3): the external odometry's noise per step, which measured every step
        of the pose graph too (its information added to each step's hold)."""
        poses = np.asarray(poses, dtype=np.float64)
        if len(sightings) != len(poses):
            raise SlamError(f"{len(sightings)} sighting lists for {len(poses)} poses", field="(sightings)")
        total = int(sum(len(s) for s in sightings))
        if not total:
            return PlaneAdjustmentResult(poses.copy(), np.zeros((0, 2)), 0, 0)
        centre = np.append(poses[:, :2].mean(axis=0), 0.0)  # walls' offsets from the trajectory's centre
        local = poses - centre
        scan = np.repeat(np.arange(len(poses)), [len(s) for s in sightings])
        observed = np.concatenate([np.zeros((0, 2))] + [np.asarray(s, dtype=np.float64) for s in sightings])
        unplaced = np.zeros(len(poses), bool) if unplaced is None else np.asarray(unplaced, bool)
        degenerate = np.zeros(len(poses), bool) if degenerate is None else np.asarray(degenerate, bool) & ~unplaced
        wall = associate(local, scan, observed, self.gate_rad, self.gate_m, self.min_sightings)
        search = np.where(unplaced, self.search_rad, np.where(degenerate, self.degenerate_search_rad, 0.0))
        start, wall = self._place(local, scan, observed, wall, search)
        moved = np.any(start != local, axis=1)
        placed = [int(k) for k in np.flatnonzero(moved)]
        unplaced = unplaced | (degenerate & moved)
        if wall.max(initial=-1) < 0:
            return PlaneAdjustmentResult(poses.copy(), np.zeros((0, 2)), 0, total)
        keep = wall >= 0
        scan, observed = scan[keep], observed[keep]
        _, wall = np.unique(wall[keep], return_inverse=True)  # dense again: placement can empty a wall
        # each pose held to the pose graph's as loosely as the pose graph knows it (its marginal σ, at least
        # the anchor's): a stretch no loop closed drifts by decimetres and degrees, and the walls must move it
        anchor = self.anchor_sigma if pose_sigma is None else np.maximum(self.anchor_sigma, pose_sigma)
        anchor_sigma = np.where(unplaced[:, None], self.loose_sigma, anchor)
        steps = self._steps(poses, step_covariance, unplaced, odometry_covariance)
        problem = _Problem(start, scan, observed, wall, steps, self.sigma, self.robust_c, anchor_sigma, local)
        refined, walls, used = problem.solve(self.iterations)
        # the first pose defines the map frame (DESIGN.md): the solution carried rigidly back onto it
        jump = compose(poses[0], inverse(refined[0] + centre))
        walls[:, 1] += np.cos(walls[:, 0]) * centre[0] + np.sin(walls[:, 0]) * centre[1]
        walls[:, 0] = wrap_angle(walls[:, 0] + jump[2])
        walls[:, 1] += np.cos(walls[:, 0]) * jump[0] + np.sin(walls[:, 0]) * jump[1]
        return PlaneAdjustmentResult(compose(jump, refined + centre), walls, used, total, placed)

    def _place(self, poses: np.ndarray, scan: np.ndarray, observed: np.ndarray, wall: np.ndarray,
               search: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Starting poses and walls of the sightings, the poses with a heading ``search`` (P,) > 0
        placed within it on the walls that the other scans' sightings make (their means at the pose
        graph's poses)."""
        unplaced = search > 0
        reach = self.search_m * _steps_from_fixed(unplaced)  # each step left to the motion may be off that much
        start, wall = poses.copy(), wall.copy()
        placed_by = (wall >= 0) & ~unplaced[scan]
        if not unplaced.any() or not placed_by.any():
            return start, wall
        walls, counts = wall_means(poses, scan[placed_by], observed[placed_by], wall[placed_by], int(wall.max()) + 1)
        walls, number = walls[counts > 0], np.flatnonzero(counts > 0)
        for k in np.flatnonzero(unplaced):
            rows = np.flatnonzero(scan == k)
            found = place(poses[k], observed[rows], walls, search[k], reach[k], self.gate_rad, self.gate_m / 3)
            if found is not None:
                start[k] = found[0]
                wall[rows] = np.where(found[1] >= 0, number[found[1]], -1)
        return start, wall

    def _steps(self, poses: np.ndarray, step_covariance: dict[int, np.ndarray], unplaced: np.ndarray,
               odometry_covariance: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """The pose graph's steps (P − 1, 3) and their whitening matrices (P − 1, 3, 3): Wᵀ W = Σ⁻¹,
        Σ the front end's step covariance inflated (a step without one: loose). The steps into and out
        of an unplaced pose are loose too: the front end matched the next scan against the map, not
        against the motion model's guess, and a degenerate scan's step is only as good as its match.
        External odometry measured each step as well, whatever the scans: its information adds (the pose
        graph's step already fuses its value, so only its weight enters here, not its value again)."""
        steps = between(poses[:-1], poses[1:])
        loose = np.diag(self.loose_sigma**2)
        cov = np.array([step_covariance.get(k, loose) for k in range(1, len(poses))]).reshape(-1, 3, 3)
        cov = 0.5 * (cov + np.swapaxes(cov, 1, 2)) + (unplaced[:-1] | unplaced[1:])[:, None, None] * loose
        information = np.linalg.inv(cov * self.step_inflation**2)
        if odometry_covariance is not None:
            information = information + np.linalg.inv(odometry_covariance)
        whiten = np.swapaxes(np.linalg.cholesky(information), 1, 2)  # L Lᵀ = Σ⁻¹ → W = Lᵀ
        return steps, whiten


def tukey_weights(norm: np.ndarray, c: float) -> np.ndarray:
    """Tukey's biweight (1 − (u/c)²)² for u < c, else 0: smooth, and exactly 0 far out."""
    return np.where(norm < c, (1.0 - (norm / c) ** 2) ** 2, 0.0)


def biweight_consistency(c: float) -> float:
    """E[w·x²] / E[w] for one component x of 2D unit Gaussian noise under Tukey's biweight w of its
    norm at ``c`` (1 for c = ∞): the biweighted variance divided by this is consistent (0.82 at
    c = 4.685). Rayleigh-distributed norm, trapezoidal quadrature."""
    if not np.isfinite(c):
        return 1.0
    u = np.linspace(0.0, c, 4001)
    density = u * np.exp(-0.5 * u**2) * tukey_weights(u, c)
    return float(trapezoid(density * 0.5 * u**2, u) / trapezoid(density, u))


class _Problem:
    """Every pose and wall as one parameter vector (the anchors hold the gauge)."""

    def __init__(self, poses: np.ndarray, scan: np.ndarray, observed: np.ndarray, wall: np.ndarray,
                 steps: tuple[np.ndarray, np.ndarray], sigma: np.ndarray, robust_c: float,
                 anchor_sigma: np.ndarray, anchor: np.ndarray):
        self.start, self.scan, self.observed, self.wall = poses, scan, observed, wall
        self.step, self.whiten = steps
        self.n_poses, self.n_walls = len(poses), int(wall.max()) + 1
        self.prior_sigma, self.robust_c, self.c = sigma, robust_c, robust_c
        self.sigma = np.tile(sigma, (self.n_walls, 1))  # (L, 2) each wall's bearing and range noise
        self.anchor, self.anchor_sigma = anchor, anchor_sigma  # (P, 3) the pose graph's poses, (P, 3) sd

    def solve(self, iterations: int,
              widths: tuple[float, ...] = (8.0, 4.0, 2.0, 1.0)) -> tuple[np.ndarray, np.ndarray, int]:
        """Graduated non-convexity (Blake & Zisserman 1987; Yang et al., "Graduated non-convexity for
        robust spatial perception", RA-L 2020): Tukey's support starts ``widths[0]`` times wider, where
        every sighting near its wall counts and the walls pull a stretch of poses the pose graph put a
        few centimetres off back onto them, and narrows to ``robust_c``; ``iterations`` of
        Levenberg–Marquardt at most per width."""
        poses = self.start.copy()
        walls, _ = wall_means(poses, self.scan, self.observed, self.wall, self.n_walls)  # from the starting poses
        self.c = np.inf
        self._wall_noise(poses, walls)  # at the pose graph's poses: its errors count as the walls' noise
        for width in widths:
            self.c = self.robust_c * width
            poses, walls = self._levenberg_marquardt(poses, walls, iterations)
            self._wall_noise(poses, walls)
        _, _, weight = self._linearize(poses, walls)
        used = int(np.count_nonzero(weight[: 2 * len(self.scan): 2] > 0))
        return poses, walls, used

    def _levenberg_marquardt(self, poses: np.ndarray, walls: np.ndarray, iterations: int):
        residual, jac, weight = self._linearize(poses, walls)
        cost = self._cost(residual, weight)
        damping = 1e-4
        for _ in range(iterations):
            jw = jac.multiply(np.sqrt(weight)[:, None]).tocsr()
            hessian = (jw.T @ jw).tocsc()
            gradient = jw.T @ (np.sqrt(weight) * residual)
            step = spsolve(hessian + damping * sp.diags(hessian.diagonal() + 1e-9), -gradient)
            trial_poses, trial_walls = self._moved(poses, walls, step)
            r_trial, j_trial, w_trial = self._linearize(trial_poses, trial_walls)
            trial_cost = self._cost(r_trial, w_trial)
            if trial_cost < cost:
                poses, walls, cost = trial_poses, trial_walls, trial_cost
                residual, jac, weight = r_trial, j_trial, w_trial
                damping = max(damping / 3, 1e-9)
                if np.max(np.abs(step)) < 1e-7:
                    break
            else:
                damping *= 4
                if damping > 1e6:
                    break
        return poses, walls

    def _wall_noise(self, poses: np.ndarray, walls: np.ndarray, prior_weight: float = 3.0) -> None:
        """Each wall's own sighting noise (bearing, range): its sightings' weighted squared residuals,
        made consistent for Gaussian noise under the biweight (:func:`biweight_consistency`), pooled
        with ``prior_weight`` sightings at the configured noise (an inverse-gamma prior, so a wall
        seen three times keeps near the prior). Walls differ by an order of magnitude: metal shelves
        2 m away are sighted to 1 mm, concrete walls 10 m away behind them to 3–9 cm."""
        residual, _, weight = self._linearize(poses, walls)
        n = 2 * len(self.scan)
        raw = residual[:n].reshape(-1, 2) * self.sigma[self.wall]  # back to radians and metres
        w = weight[:n:2]
        total = np.bincount(self.wall, w, self.n_walls)[:, None]
        spread = np.stack([np.bincount(self.wall, w * raw[:, i] ** 2, self.n_walls) for i in (0, 1)], axis=1)
        spread /= biweight_consistency(self.c)
        self.sigma = np.sqrt((prior_weight * self.prior_sigma**2 + spread) / (prior_weight + total))

    def _moved(self, poses: np.ndarray, walls: np.ndarray, step: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        poses, walls = poses.copy(), walls.copy()
        poses += step[: 3 * self.n_poses].reshape(-1, 3)
        walls += step[3 * self.n_poses:].reshape(-1, 2)
        poses[:, 2], walls[:, 0] = wrap_angle(poses[:, 2]), wrap_angle(walls[:, 0])
        return poses, walls

    def _cost(self, residual: np.ndarray, weight: np.ndarray) -> float:
        """Σ ρ over the sightings (Tukey's ρ of each one's norm) plus half the steps' and anchors' squared
        residuals."""
        n = 2 * len(self.scan)
        norm = np.hypot(residual[:n:2], residual[1:n:2])
        c = self.c
        rho = np.where(norm < c, c**2 / 6 * (1 - (1 - (norm / c) ** 2) ** 3), c**2 / 6)
        return float(rho.sum() + 0.5 * np.sum(residual[n:] ** 2))

    def _linearize(self, poses: np.ndarray, walls: np.ndarray):
        """Stacked whitened residuals, their sparse Jacobian and the IRLS weights (1 for the steps)."""
        k, L = self.scan, self.wall
        sig_psi, sig_d = self.sigma[L, 0], self.sigma[L, 1]
        x, y, th = poses[k, 0], poses[k, 1], poses[k, 2]
        psi, d = walls[L, 0], walls[L, 1]
        c, s = np.cos(psi), np.sin(psi)
        e_psi = wrap_angle(th + self.observed[:, 0] - psi) / sig_psi
        e_d = (self.observed[:, 1] + c * x + s * y - d) / sig_d
        n_s = len(k)
        wall_col = 3 * self.n_poses + 2 * L
        pose_col = 3 * k  # each pose's first parameter column
        rows, cols, vals = [], [], []

        def put(row, col, val):
            rows.append(row), cols.append(col), vals.append(np.broadcast_to(val, row.shape))

        r_psi, r_d = 2 * np.arange(n_s), 2 * np.arange(n_s) + 1
        put(r_psi, pose_col + 2, 1 / sig_psi)
        put(r_psi, wall_col, -1 / sig_psi)
        put(r_d, pose_col, c / sig_d)
        put(r_d, pose_col + 1, s / sig_d)
        put(r_d, wall_col, (-s * x + c * y) / sig_d)
        put(r_d, wall_col + 1, -1 / sig_d)
        # the steps: h = (R(θ_a)ᵀ(t_b − t_a), θ_b − θ_a) against the pose graph's step, whitened
        a, b = poses[:-1], poses[1:]
        ca, sa = np.cos(a[:, 2]), np.sin(a[:, 2])
        dx, dy = b[:, 0] - a[:, 0], b[:, 1] - a[:, 1]
        h = np.stack([ca * dx + sa * dy, -sa * dx + ca * dy, b[:, 2] - a[:, 2]], axis=1)
        err = h - self.step
        err[:, 2] = wrap_angle(err[:, 2])
        zero, one = np.zeros_like(ca), np.ones_like(ca)
        j_a = np.stack([np.stack([-ca, -sa, -sa * dx + ca * dy], 1), np.stack([sa, -ca, -ca * dx - sa * dy], 1),
                        np.stack([zero, zero, -one], 1)], 1)  # (P−1, 3, 3) ∂h/∂(x_a, y_a, θ_a)
        j_b = np.stack([np.stack([ca, sa, zero], 1), np.stack([-sa, ca, zero], 1), np.stack([zero, zero, one], 1)], 1)
        w_a, w_b = self.whiten @ j_a, self.whiten @ j_b
        step_res = np.einsum("kij,kj->ki", self.whiten, err).ravel()
        base = 2 * n_s + 3 * np.arange(len(a))
        idx = np.arange(len(a))
        for i in range(3):
            for j in range(3):
                put(base + i, 3 * idx + j, w_a[:, i, j])
                put(base + i, 3 * (idx + 1) + j, w_b[:, i, j])
        # the anchors: each pose held near the pose graph's, loosely (its errors are centimetres)
        every = np.arange(self.n_poses)
        base = 2 * n_s + 3 * len(a) + 3 * every
        anchor_res = (poses - self.anchor) / self.anchor_sigma
        anchor_res[:, 2] = wrap_angle(poses[:, 2] - self.anchor[:, 2]) / self.anchor_sigma[:, 2]
        for i in range(3):
            put(base + i, 3 * every + i, 1.0 / self.anchor_sigma[:, i])
        n_rows = 2 * n_s + 3 * len(a) + 3 * self.n_poses
        n_cols = 3 * self.n_poses + 2 * self.n_walls
        jac = sp.coo_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                            shape=(n_rows, n_cols))
        residual = np.concatenate([np.stack([e_psi, e_d], axis=1).ravel(), step_res, anchor_res.ravel()])
        sighted = np.repeat(tukey_weights(np.hypot(e_psi, e_d), self.c), 2)
        weight = np.concatenate([sighted, np.ones(3 * len(a) + 3 * self.n_poses)])
        return residual, jac, weight


def _steps_from_fixed(flags: np.ndarray) -> np.ndarray:
    """For each flagged pose the number of steps to the nearest unflagged one, either way (the whole
    length where none is; 0 where not flagged): how many steps its position rests on the motion."""
    flags = np.asarray(flags, bool)
    count, index = len(flags), np.arange(len(flags))
    before = np.maximum.accumulate(np.where(flags, -1, index))  # the last unflagged pose up to each
    after = np.minimum.accumulate(np.where(flags, count, index)[::-1])[::-1]  # the next from each on
    steps = np.minimum(np.where(before >= 0, index - before, count), np.where(after < count, after - index, count))
    return np.where(flags, steps, 0).astype(float)
