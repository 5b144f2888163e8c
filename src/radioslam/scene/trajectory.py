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


def waypoint_poses(waypoints: np.ndarray, step_m: float, turn_step_deg: float, corner_radius_m: float,
                   speed_variation: float = 0.0, period_m: float = 7.0) -> np.ndarray:
    """Poses along a polyline whose corners are rounded to ``corner_radius_m`` (shrunk where
    the legs are short), heading along the path.

    The terminal advances one unit of "progress" per pose, progress = s/step + |Δθ|/turn
    step, so it goes ``step_m`` apart on straight legs and slows down in turns; its
    straight-leg speed varies by ±``speed_variation`` (relative) with period ``period_m``,
    so that a constant-velocity model is not exact.
    """
    p = np.asarray(waypoints, dtype=np.float64)
    leg = np.diff(p, axis=0)
    length = np.linalg.norm(leg, axis=1)
    direction = leg / length[:, None]
    turn = np.angle(np.exp(1j * (np.arctan2(direction[1:, 1], direction[1:, 0])
                                 - np.arctan2(direction[:-1, 1], direction[:-1, 0]))))
    # fillet of radius r at each interior waypoint: tangent points t·tan(|turn|/2)·r back and ahead
    half = np.tan(np.abs(turn) / 2)
    room = 0.5 * np.minimum(length[:-1], length[1:])
    radius = np.where(half > 1e-9, np.minimum(corner_radius_m, room / np.maximum(half, 1e-9)), 0.0)
    cut = radius * half
    # a dense polyline (1 cm, and 0.5° in turns) of the rounded path with its heading
    xy, heading = [], []
    for i in range(len(leg)):
        a = p[i] + direction[i] * (cut[i - 1] if i > 0 else 0.0)
        b = p[i + 1] - direction[i] * (cut[i] if i < len(cut) else 0.0)
        n = max(2, int(np.ceil(np.linalg.norm(b - a) / 0.01)))
        t = np.linspace(0.0, 1.0, n)[:, None]
        xy.append(a + t * (b - a))
        heading.append(np.full(n, np.arctan2(direction[i, 1], direction[i, 0])))
        if i < len(cut) and radius[i] > 0:
            side = np.sign(turn[i])
            normal = side * np.array([-direction[i, 1], direction[i, 0]])
            centre = b + radius[i] * normal
            start = np.arctan2(b[1] - centre[1], b[0] - centre[0])
            sweep = np.linspace(0.0, turn[i], max(2, int(np.ceil(np.degrees(abs(turn[i])) / 0.5))))
            xy.append(centre + radius[i] * np.stack([np.cos(start + sweep), np.sin(start + sweep)], axis=1))
            heading.append(heading[-1][-1] + sweep)
    xy, heading = np.concatenate(xy), np.unwrap(np.concatenate(heading))
    ds = np.linalg.norm(np.diff(xy, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(ds)])
    speed = 1.0 + speed_variation * np.sin(2 * np.pi * s[1:] / period_m)
    progress = np.concatenate([[0.0], np.cumsum(ds / (step_m * speed) + np.abs(np.diff(heading))
                                                 / np.radians(turn_step_deg))])
    at = np.arange(0.0, progress[-1] + 1e-9, 1.0)
    x, y = np.interp(at, progress, xy[:, 0]), np.interp(at, progress, xy[:, 1])
    theta = np.interp(at, progress, heading)
    return np.stack([x, y, np.angle(np.exp(1j * theta))], axis=-1)
