"""A drifting wheel/IMU odometry for the scene's walk (issue #12), so that the SLAM's optional
odometry input is testable: each true step (x, y, θ in the previous pose's frame) is scaled by
1 + scale_bias, turned by heading_bias, and perturbed by white Gaussian noise; the steps are
composed from the first true pose. Scale and heading biases make it drift as real odometry does.
"""

from __future__ import annotations

import numpy as np

from radioslam.scene.schema import OdometrySpec

ODOMETRY_STREAM = 0x0D0  # the odometry's own random stream of the run's seed


def odometry_rng(seed: int) -> np.random.Generator:
    """The generator of a run's simulated odometry: independent of every capture's."""
    return np.random.default_rng(np.random.SeedSequence([seed, ODOMETRY_STREAM]))


def simulated_odometry(poses: np.ndarray, spec: OdometrySpec, rng: np.random.Generator) -> np.ndarray:
    """Odometry poses (P, 3) whose steps are the true steps of ``poses`` with the spec's biases and noise."""
    poses = np.asarray(poses, dtype=np.float64)
    c, s = np.cos(poses[:-1, 2]), np.sin(poses[:-1, 2])
    d = np.diff(poses[:, :2], axis=0)
    turn = np.angle(np.exp(1j * np.diff(poses[:, 2])))
    steps = np.column_stack([c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1], turn])  # previous pose's frame
    noise = rng.normal(size=steps.shape) * np.array([spec.sigma_m, spec.sigma_m, np.radians(spec.sigma_deg)])
    measured = steps * np.array([1 + spec.scale_bias, 1 + spec.scale_bias, 1.0]) + noise
    measured[:, 2] += np.radians(spec.heading_bias_deg)
    # composed from the first true pose: headings accumulate, each step turns by the heading before it
    heading = poses[0, 2] + np.concatenate([[0.0], np.cumsum(measured[:, 2])])
    ch, sh = np.cos(heading[:-1]), np.sin(heading[:-1])
    moves = np.column_stack([ch * measured[:, 0] - sh * measured[:, 1], sh * measured[:, 0] + ch * measured[:, 1]])
    xy = poses[0, :2] + np.concatenate([np.zeros((1, 2)), np.cumsum(moves, axis=0)])
    if spec.gyro_only:  # the turns alone: a gyro knows nothing of the translation
        xy = np.full_like(xy, np.nan)
    return np.column_stack([xy, np.angle(np.exp(1j * heading))])


def per_step_sigmas(spec: OdometrySpec, poses: np.ndarray) -> tuple[float, float]:
    """The odometry's error per step as one σ each (m, deg): its white noise and its biases on the walk's median
    step (the scale bias times the step's length, the heading bias), added in quadrature: what a between
    factor of one step can state of it."""
    steps = np.linalg.norm(np.diff(np.asarray(poses, dtype=np.float64)[:, :2], axis=0), axis=1)
    step = float(np.median(steps)) if len(steps) else 0.0
    return float(np.hypot(spec.sigma_m, spec.scale_bias * step)), float(np.hypot(spec.sigma_deg, spec.heading_bias_deg))
