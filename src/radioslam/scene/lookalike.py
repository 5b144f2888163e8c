"""Rooms that look alike under a turn or a mirror, and the smooth walks that fool a matcher in them
(issue #47): generated cases for the SLAM's benchmark, where a scan's pose has a twin the room
cannot tell apart.

- rooms: a rectangle with a point-symmetric pair of obstacles (alike under a half turn), a square
  with four pillars turned by quarter turns (alike under a quarter turn), an isosceles trapezoid
  with a mirrored pair (alike under a mirror); each with or without one asymmetric feature (a pillar
  standing out of one wall, off every symmetry), which is what tells the twins apart when it is in view;
- walks: a figure eight (a lemniscate of Bernoulli, turning ≤ 21° a step: its crossing is where a
  half-turned twin is nearest), a four-leaf clover (a rose r = a·cos 2φ through the centre), and the inset loop
  walked smoothly; heading along the path, 0.4–0.6 m a step.

Every pose keeps ``clearance`` from every wall and obstacle. Cases are ordinary
:class:`~radioslam.scene.procedural.Case` objects drawn from one seeded generator.
"""

from __future__ import annotations

from enum import Enum

import numpy as np

from radioslam.scene.geometry import point_segment_distance
from radioslam.scene.loader import scene_from_mapping
from radioslam.scene.procedural import Case, MotionKind, RoomKind, _inside, _rotate, _segments, inset
from radioslam.scene.trajectory import waypoint_poses


class Symmetry(str, Enum):
    HALF_TURN = "half-turn"
    QUARTER_TURN = "quarter-turn"
    MIRROR = "mirror"


ROOM_OF = {Symmetry.HALF_TURN: RoomKind.SYMMETRIC_HALF, Symmetry.QUARTER_TURN: RoomKind.SYMMETRIC_QUARTER,
           Symmetry.MIRROR: RoomKind.SYMMETRIC_MIRROR}
SMOOTH_TURN_DEG = 21.0  # a figure eight turns at most this much a step
WALKS = (MotionKind.FIGURE_EIGHT, MotionKind.CLOVER, MotionKind.SMOOTH)


def symmetric_outline(symmetry: Symmetry, rng: np.random.Generator) -> np.ndarray:
    """The outer wall (N, 2), open, counter-clockwise, its symmetry centre at the origin."""
    if symmetry is Symmetry.HALF_TURN:
        w, h = rng.uniform(10, 14), rng.uniform(8, 10)
        return np.array([[-w / 2, -h / 2], [w / 2, -h / 2], [w / 2, h / 2], [-w / 2, h / 2]])
    if symmetry is Symmetry.QUARTER_TURN:
        s = rng.uniform(9, 12) / 2
        return np.array([[-s, -s], [s, -s], [s, s], [-s, s]])
    bottom, top, h = rng.uniform(11, 14) / 2, rng.uniform(6, 9) / 2, rng.uniform(9, 11)
    return np.array([[-bottom, -h / 2], [bottom, -h / 2], [top, h / 2], [-top, h / 2]])


def images(polygon: np.ndarray, symmetry: Symmetry) -> list[np.ndarray]:
    """``polygon`` and its images under the symmetry group's other elements."""
    if symmetry is Symmetry.HALF_TURN:
        return [polygon, -polygon]
    if symmetry is Symmetry.QUARTER_TURN:
        return [_rotate(polygon, k * np.pi / 2) for k in range(4)]
    return [polygon, polygon * np.array([-1.0, 1.0])]


def curve_poses(curve: np.ndarray, step_m: float) -> np.ndarray:
    """Poses (P, 3) every ``step_m`` of arc length along a dense closed curve (N, 2), heading along it."""
    ds = np.linalg.norm(np.diff(curve, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(ds)])
    at = np.arange(0.0, s[-1], step_m)
    x, y = np.interp(at, s, curve[:, 0]), np.interp(at, s, curve[:, 1])
    ahead = np.minimum(at + 0.01, s[-1])
    dx, dy = np.interp(ahead, s, curve[:, 0]) - x, np.interp(ahead, s, curve[:, 1]) - y
    return np.column_stack([x, y, np.arctan2(dy, dx)])


def walk_curve(motion: MotionKind, extent: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """A dense closed curve (N, 2) of the walk, centred at the origin, spanning ±``extent`` (2,)."""
    t = np.linspace(0.0, 2 * np.pi, 4000)
    if motion is MotionKind.FIGURE_EIGHT:  # lemniscate of Bernoulli, its lobes along the longer side
        x, y = np.cos(t) / (1 + np.sin(t) ** 2), np.sin(t) * np.cos(t) / (1 + np.sin(t) ** 2)
        curve = np.column_stack([x, y]) if extent[0] >= extent[1] else np.column_stack([y, x])
    elif motion is MotionKind.CLOVER:  # four-leaf rose, turned so that its leaves point at the corners
        r = np.cos(2 * t)
        curve = _rotate(np.column_stack([r * np.cos(t), r * np.sin(t)]), np.pi / 4) * np.sqrt(2)
    else:
        raise ValueError(f"{motion.value}: not a curve walk")
    curve = curve * extent / np.maximum(np.abs(curve).max(axis=0), 1e-9)
    start = int(rng.integers(len(curve) - 1))  # any point of the closed curve starts the walk
    return np.vstack([curve[start:-1], curve[:start + 1]])


def lookalike_case(symmetry: Symmetry, motion: MotionKind, seed: int, asymmetric: bool,
                   snr_db: float | None = None, clearance: float | None = None, max_poses: int = 90) -> Case:
    """One reproducible case in a room alike under ``symmetry``; ``asymmetric`` adds a pillar out of one
    wall, off every symmetry. Everything not given is drawn from ``default_rng(seed)``."""
    rng = np.random.default_rng(seed)
    snr = float(rng.uniform(0, 20)) if snr_db is None else float(snr_db)
    clear = float(rng.uniform(0.5, 2.0)) if clearance is None else float(clearance)
    step = float(rng.uniform(0.4, 0.6))
    outer = symmetric_outline(symmetry, rng)
    walls = [np.vstack([outer, outer[:1]])]
    segments = _segments(walls)
    path = inset(outer, clear + 0.8)  # obstacles go between the walk and the walls
    if motion is MotionKind.SMOOTH:
        loop = np.vstack([path, path[:1]])
        poses = waypoint_poses(loop, step, 15.0, 1.0)
    else:
        extent = np.abs(path).min(axis=0) if symmetry is not Symmetry.MIRROR else \
            np.array([np.abs(path[:, 0]).max() * 0.55, np.abs(path[:, 1]).max()])
        curve = walk_curve(motion, extent, rng)
        poses = curve_poses(curve, step)
        turns = np.abs(np.angle(np.exp(1j * np.diff(poses[:, 2]))))
        if motion is MotionKind.FIGURE_EIGHT and turns.max() > np.radians(SMOOTH_TURN_DEG):
            step *= np.radians(SMOOTH_TURN_DEG) / turns.max()  # a smooth walk: shorter steps in its tightest turn
            poses = curve_poses(curve, step)
    for _ in range(50):  # shrink the walk about the centre until it keeps its clearance
        if point_segment_distance(poses[:, :2], segments).min() >= clear + 0.6:
            break
        poses[:, :2] *= 0.95
    poses = poses[:max_poses]
    obstacles = _symmetric_obstacles(symmetry, segments, poses[:, :2], clear, rng)
    if asymmetric:
        obstacles += _wall_pillar(outer, poses[:, :2], clear, rng)
    name = f"{ROOM_OF[symmetry].value}{'-feature' if asymmetric else ''}-{motion.value}-{seed}"
    scene = scene_from_mapping({
        "version": 1, "name": name,
        "walls": [{"points": np.round(w, 6).tolist(), "material": m} for w, m in
                  [(w, "concrete") for w in walls] + obstacles],
        "trajectory": {"poses": np.round(poses, 6).tolist()},
        "radio": {"snr_db": round(snr, 3)},
    }, f"lookalike:{name}")
    return Case(ROOM_OF[symmetry], motion, seed, snr, step, scene)


def _symmetric_obstacles(symmetry: Symmetry, segments: np.ndarray, walk: np.ndarray, clearance: float,
                         rng: np.random.Generator) -> list[tuple[np.ndarray, str]]:
    """A box of one material and its images under the symmetry (so the room stays alike), ≥ ``clearance``
    from the walk and 0.5 m from the walls; none where no place is found in 200 draws."""
    lo, hi = segments.reshape(-1, 2).min(axis=0), segments.reshape(-1, 2).max(axis=0)
    material = str(rng.choice(["concrete", "metal", "wood"]))
    for _ in range(200):
        w, h = rng.uniform(0.4, 1.2, 2)
        box = _rotate(np.array([[-w, -h], [w, -h], [w, h], [-w, h], [-w, -h]]) / 2, rng.uniform(0, np.pi / 2))
        polys = images(box + rng.uniform(lo, hi), symmetry)
        if point_segment_distance(walk, _segments(polys)).min() < clearance + 0.3:
            continue
        corners = np.concatenate(polys)
        if point_segment_distance(corners, segments).min() < 0.5 or not all(_inside(c, segments) for c in corners):
            continue
        return [(p, material) for p in polys]
    return []


def _wall_pillar(outer: np.ndarray, walk: np.ndarray, clearance: float,
                 rng: np.random.Generator) -> list[tuple[np.ndarray, str]]:
    """The asymmetric feature: a pillar 0.4–1.0 m wide standing 0.3–0.5 m out of one wall, at a place no
    symmetry maps onto itself (kept ``clearance`` from the walk)."""
    for _ in range(100):
        side = int(rng.integers(len(outer)))
        a, b = outer[side], outer[(side + 1) % len(outer)]
        along = (b - a) / np.linalg.norm(b - a)
        inward = np.array([-along[1], along[0]])  # counter-clockwise outline: the room lies to the left
        centre = a + (b - a) * rng.uniform(0.15, 0.4)  # off the wall's middle: no mirror keeps it
        half, depth = rng.uniform(0.2, 0.5), rng.uniform(0.3, 0.5)
        box = centre + np.array([-half * along, half * along, half * along + depth * inward,
                                 -half * along + depth * inward, -half * along])
        if point_segment_distance(walk, _segments([box])).min() >= clearance:
            return [(box, "concrete")]
    return []


def lookalike_suite(runs: int = 24, seed: int = 0) -> list[Case]:
    """``runs`` cases cycling through every symmetry, walk, and with or without the asymmetric feature."""
    out = []
    for i in range(runs):
        symmetry = list(Symmetry)[i % 3]
        motion = WALKS[(i // 3) % len(WALKS)]
        if symmetry is Symmetry.QUARTER_TURN and motion is MotionKind.FIGURE_EIGHT:
            motion = MotionKind.CLOVER  # the clover is the square's own walk
        out.append(lookalike_case(symmetry, motion, 5000 + seed * 1000 + i, asymmetric=bool((i // 9) % 2)))
    return out
