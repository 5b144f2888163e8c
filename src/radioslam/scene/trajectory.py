"""Trajectories of the scene file: a circle of poses or an explicit list (DESIGN.md §4)."""

from __future__ import annotations

import numpy as np

from radioslam.scene.schema import CircleSpec, Heading, TrajectorySpec


def circle_poses(center: tuple[float, float], radius: float, n: int, heading: Heading) -> np.ndarray:
    """n equidistant SE(2) poses counter-clockwise on a circle, starting at angle 0.

    heading=tangent faces the direction of travel (φ + π/2); fixed keeps θ = 0.
    """
    phi = 2.0 * np.pi * np.arange(n) / n
    x = center[0] + radius * np.cos(phi)
    y = center[1] + radius * np.sin(phi)
    theta = phi + np.pi / 2 if heading is Heading.TANGENT else np.zeros(n)
    return np.stack([x, y, np.angle(np.exp(1j * theta))], axis=-1)


def trajectory_poses(spec: TrajectorySpec) -> np.ndarray:
    """(P, 3) poses (x, y, θ) of a trajectory spec."""
    if spec.circle is not None:
        c: CircleSpec = spec.circle
        return circle_poses(c.center, c.radius, c.poses, c.heading)
    return np.asarray(spec.poses, dtype=np.float64).reshape(-1, 3)
