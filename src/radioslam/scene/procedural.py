"""Procedurally generated scenes and walks for robustness checks (issue #12).

A case is a room shape, a motion and an SNR, all drawn from one seeded generator:

- rooms: axis-aligned rectangles, L shapes, rectangles rotated off the axes, irregular
  convex polygons (no right angles) and long halls up to 30 m, with obstacles (boxes,
  pillars, partitions) of every material, glass included, kept clear of the walk;
- motions: rounded corners (``smooth``), every corner turned between two scans
  (``sharp``), turning on the spot in 30° steps (``spot``), a terminal that never
  rotates (``fixed``), a walk to the end and a 180° U-turn in one step (``uturn``),
  lawnmower rows with 90° turns in one step (``lawnmower``), and a random walk whose
  turns between scans take any value from 0° to 180° (``random``); steps up to 1 m.

Every pose keeps ``clearance`` (2 m by default) from every wall: nearer walls fall inside the
receiver's 1.5 m leakage gate. The scenes are ordinary :class:`~radioslam.scene.Scene`
objects, written as scene files by ``scene_to_yaml`` like any other.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

import numpy as np

from radioslam.scene.geometry import point_segment_distance
from radioslam.scene.loader import scene_from_mapping
from radioslam.scene.model import Scene
from radioslam.scene.trajectory import waypoint_poses

MATERIALS = ("concrete", "metal", "wood", "glass", "drywall")
SHARP_TURN_DEG = 1e4  # a turn step this large turns any corner between two scans


class RoomKind(str, Enum):
    RECTANGLE = "rectangle"
    L_SHAPE = "l-shape"
    ROTATED = "rotated"
    POLYGON = "polygon"
    HALL = "hall"
    # issue #47 (scene/lookalike.py, scene/offices.py): rooms alike under a turn or a mirror, offices
    SYMMETRIC_HALF = "symmetric-half"
    SYMMETRIC_QUARTER = "symmetric-quarter"
    SYMMETRIC_MIRROR = "symmetric-mirror"
    OFFICE = "office"


class MotionKind(str, Enum):
    SMOOTH = "smooth"
    SHARP = "sharp"
    SPOT = "spot"
    FIXED = "fixed"
    UTURN = "uturn"
    LAWNMOWER = "lawnmower"
    RANDOM = "random"
    # issue #47: smooth curves through look-alike rooms, and a tour of an office's rooms
    FIGURE_EIGHT = "figure-eight"
    CLOVER = "clover"
    TOUR = "tour"


# the suite of issue #12 (bench_robustness's original cases, kept as they were)
CLASSIC_ROOMS = (RoomKind.RECTANGLE, RoomKind.L_SHAPE, RoomKind.ROTATED, RoomKind.POLYGON, RoomKind.HALL)
CLASSIC_MOTIONS = (MotionKind.SMOOTH, MotionKind.SHARP, MotionKind.SPOT, MotionKind.FIXED, MotionKind.UTURN,
                   MotionKind.LAWNMOWER, MotionKind.RANDOM)


@dataclass(frozen=True)
class Case:
    """One generated run: what a benchmark row reports."""

    room: RoomKind
    motion: MotionKind
    seed: int
    snr_db: float
    step_m: float
    scene: Scene

    @property
    def name(self) -> str:
        return self.scene.name


def _rotate(points: np.ndarray, angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return points @ np.array([[c, s], [-s, c]])


def _ccw(polygon: np.ndarray) -> np.ndarray:
    area = 0.5 * np.sum(polygon[:, 0] * np.roll(polygon[:, 1], -1) - np.roll(polygon[:, 0], -1) * polygon[:, 1])
    return polygon if area > 0 else polygon[::-1]


def inset(polygon: np.ndarray, distance: float) -> np.ndarray:
    """The simple polygon (N, 2) (open: last ≠ first) with every edge moved ``distance`` inwards:
    consecutive offset edge lines intersected (exact for convex and rectilinear rooms)."""
    p = _ccw(polygon)
    edge = np.roll(p, -1, axis=0) - p
    inward = np.stack([-edge[:, 1], edge[:, 0]], axis=1) / np.linalg.norm(edge, axis=1)[:, None]
    a = p + distance * inward  # a point on each offset edge line, direction edge
    prev_a, prev_e = np.roll(a, 1, axis=0), np.roll(edge, 1, axis=0)
    # a_prev + s·e_prev = a + t·e  →  solve for t
    denom = prev_e[:, 0] * edge[:, 1] - prev_e[:, 1] * edge[:, 0]
    rel = a - prev_a
    t = (prev_e[:, 1] * rel[:, 0] - prev_e[:, 0] * rel[:, 1]) / denom
    return a + t[:, None] * edge


def room_polygon(kind: RoomKind, rng: np.random.Generator) -> np.ndarray:
    """The outer wall (N, 2), open polygon, counter-clockwise, centred near the origin."""
    if kind is RoomKind.RECTANGLE:
        w, h = rng.uniform(9, 20), rng.uniform(8, 14)
        return np.array([[-w / 2, -h / 2], [w / 2, -h / 2], [w / 2, h / 2], [-w / 2, h / 2]])
    if kind is RoomKind.HALL:
        w, h = rng.uniform(18, 30), rng.uniform(7, 10)
        return np.array([[-w / 2, -h / 2], [w / 2, -h / 2], [w / 2, h / 2], [-w / 2, h / 2]])
    if kind is RoomKind.ROTATED:
        w, h = rng.uniform(9, 18), rng.uniform(8, 13)
        box = np.array([[-w / 2, -h / 2], [w / 2, -h / 2], [w / 2, h / 2], [-w / 2, h / 2]])
        return _rotate(box, np.radians(rng.uniform(15, 75)))
    if kind is RoomKind.L_SHAPE:
        w, h = rng.uniform(14, 22), rng.uniform(12, 18)
        nw, nh = w * rng.uniform(0.4, 0.55), h * rng.uniform(0.4, 0.55)  # the notch cut from one corner
        x0, y0 = -w / 2, -h / 2
        return np.array([[x0, y0], [x0 + w, y0], [x0 + w, y0 + h - nh], [x0 + w - nw, y0 + h - nh],
                         [x0 + w - nw, y0 + h], [x0, y0 + h]])
    n = int(rng.integers(5, 8))
    angle = 2 * np.pi * (np.arange(n) + rng.uniform(-0.2, 0.2, n)) / n + rng.uniform(0, 2 * np.pi)
    radius = rng.uniform(7, 10) * rng.uniform(0.85, 1.15, n)
    return np.stack([radius * np.cos(angle), radius * np.sin(angle)], axis=1)


def _segments(polylines: list[np.ndarray]) -> np.ndarray:
    return np.concatenate([np.stack([p[:-1], p[1:]], axis=1) for p in polylines])


def _clear(points: np.ndarray, segments: np.ndarray, clearance: float) -> bool:
    return bool(point_segment_distance(points, segments).min() >= clearance)


def _dense(waypoints: np.ndarray, spacing: float = 0.25) -> np.ndarray:
    out = [waypoints[:1]]
    for a, b in zip(waypoints[:-1], waypoints[1:]):
        n = max(1, int(np.ceil(np.linalg.norm(b - a) / spacing)))
        out.append(a + (b - a) * (np.arange(1, n + 1) / n)[:, None])
    return np.concatenate(out)


def lawnmower_waypoints(path_polygon: np.ndarray, spacing: float) -> np.ndarray:
    """Rows along x through the polygon (the longest interval of each row), alternating direction."""
    lo, hi = path_polygon[:, 1].min(), path_polygon[:, 1].max()
    rows = lo + spacing / 2 + np.arange(max(1, int((hi - lo) / spacing))) * spacing
    a, b = path_polygon, np.roll(path_polygon, -1, axis=0)
    out = []
    for i, y in enumerate(rows):
        cross = (a[:, 1] - y) * (b[:, 1] - y) <= 0
        den = np.where(np.abs(b[:, 1] - a[:, 1]) > 1e-12, b[:, 1] - a[:, 1], 1.0)
        xs = np.sort((a[:, 0] + (y - a[:, 1]) * (b[:, 0] - a[:, 0]) / den)[cross & (np.abs(b[:, 1] - a[:, 1]) > 1e-12)])
        if len(xs) < 2:
            continue
        pairs = xs[: len(xs) // 2 * 2].reshape(-1, 2)
        x0, x1 = pairs[np.argmax(pairs[:, 1] - pairs[:, 0])]
        if x1 - x0 < 1.0:
            continue
        row = [[x0, y], [x1, y]]
        out.extend(row if i % 2 == 0 else row[::-1])
    return np.array(out)


def random_walk_waypoints(segments: np.ndarray, start: np.ndarray, legs: int, clearance: float,
                          rng: np.random.Generator) -> np.ndarray:
    """Legs of 2.5–6 m, each turning by any angle from 0° to 180° (either side), kept clear of walls."""
    points, heading = [np.asarray(start, dtype=float)], rng.uniform(-np.pi, np.pi)
    for _ in range(legs):
        for _ in range(200):
            turn = rng.uniform(0, np.pi) * rng.choice([-1.0, 1.0])
            length = rng.uniform(2.5, 6.0)
            end = points[-1] + length * np.array([np.cos(heading + turn), np.sin(heading + turn)])
            if _clear(_dense(np.stack([points[-1], end])), segments, clearance):
                points.append(end)
                heading += turn
                break
    return np.array(points)


def _obstacles(segments: np.ndarray, path: np.ndarray, count: int, clearance: float,
               rng: np.random.Generator) -> list[dict]:
    """Boxes, pillars and partitions of random materials at least ``clearance`` from the path."""
    lo, hi = segments.reshape(-1, 2).min(axis=0), segments.reshape(-1, 2).max(axis=0)
    out = []
    for _ in range(count * 30):
        if len(out) >= count:
            break
        centre = rng.uniform(lo, hi)
        shape = rng.choice(["box", "pillar", "partition"])
        if shape == "partition":
            half = rng.uniform(0.5, 1.5) * np.array([np.cos(a := rng.uniform(0, np.pi)), np.sin(a)])
            poly = np.stack([centre - half, centre + half])
        else:
            w, h = (rng.uniform(0.3, 0.6),) * 2 if shape == "pillar" else rng.uniform(0.5, 2.0, 2)
            box = np.array([[-w, -h], [w, -h], [w, h], [-w, h], [-w, -h]]) / 2
            poly = _rotate(box, rng.uniform(0, np.pi / 2)) + centre
        seg = _segments([poly])
        if point_segment_distance(path, seg).min() < clearance:
            continue
        if point_segment_distance(poly, segments).min() < 0.5 or not _inside(centre, segments):
            continue
        segments = np.concatenate([segments, seg])
        out.append({"points": poly.tolist(), "material": str(rng.choice(MATERIALS))})
    return out


def _inside(point: np.ndarray, segments: np.ndarray) -> bool:
    """Even-odd rule against every segment (a ray along +x)."""
    a, b = segments[:, 0], segments[:, 1]
    straddle = (a[:, 1] > point[1]) != (b[:, 1] > point[1])
    den = np.where(straddle, b[:, 1] - a[:, 1], 1.0)
    x = a[:, 0] + (point[1] - a[:, 1]) * (b[:, 0] - a[:, 0]) / den
    return bool(np.sum(straddle & (x > point[0])) % 2)


def motion_poses(motion: MotionKind, path_polygon: np.ndarray, segments: np.ndarray, step: float,
                 clearance: float, rng: np.random.Generator, max_poses: int) -> np.ndarray:
    """Poses (P, 3) of one motion kind on the room whose walkable loop is ``path_polygon``."""
    start = int(rng.integers(len(path_polygon)))
    loop = np.vstack([np.roll(path_polygon, -start, axis=0), np.roll(path_polygon, -start, axis=0)[:1]])
    if motion is MotionKind.SMOOTH:
        return waypoint_poses(loop, step, 15.0, 1.0, speed_variation=0.2)[:max_poses]
    if motion is MotionKind.SPOT:
        return waypoint_poses(loop, step, 30.0, 0.0)[:max_poses]
    if motion is MotionKind.LAWNMOWER:
        rows = lawnmower_waypoints(path_polygon, rng.uniform(2.0, 3.0))
        return waypoint_poses(np.vstack([rows, rows[-2::-1]]), step, SHARP_TURN_DEG, 0.0)[:max_poses]  # and back
    if motion is MotionKind.UTURN:
        # along the longest side to its end, a U-turn in one step, back, and again
        side = int(np.argmax(np.linalg.norm(np.roll(path_polygon, -1, axis=0) - path_polygon, axis=1)))
        a, b = path_polygon[side], path_polygon[(side + 1) % len(path_polygon)]
        return waypoint_poses(np.stack([a, b, a, b]), step, SHARP_TURN_DEG, 0.0)[:max_poses]
    if motion is MotionKind.RANDOM:
        walk = random_walk_waypoints(segments, path_polygon[0], 40, clearance, rng)
        return waypoint_poses(walk, step, SHARP_TURN_DEG, 0.0)[:max_poses]
    poses = waypoint_poses(loop, step, SHARP_TURN_DEG, 0.0)[:max_poses]
    if motion is MotionKind.FIXED:
        poses[:, 2] = rng.uniform(-np.pi, np.pi)
    return poses


def generate_case(room: RoomKind, motion: MotionKind, seed: int, snr_db: float | None = None,
                  step_m: float | None = None, max_poses: int = 60, clearance: float = 2.0,
                  obstacles: int | None = None) -> Case:
    """One reproducible case: everything not given is drawn from ``default_rng(seed)``."""
    rng = np.random.default_rng(seed)
    snr = float(rng.uniform(0, 20)) if snr_db is None else float(snr_db)
    step = float(rng.uniform(0.4, 1.0)) if step_m is None else float(step_m)
    outer = room_polygon(room, rng)
    walls = [{"points": np.vstack([outer, outer[:1]]).tolist(), "material": "concrete"}]
    segments = _segments([np.vstack([outer, outer[:1]])])
    path_polygon = inset(outer, clearance + rng.uniform(0.2, 1.0))
    poses = motion_poses(motion, path_polygon, segments, step, clearance, rng, max_poses)
    count = int(rng.integers(1, 5)) if obstacles is None else obstacles
    walls += _obstacles(segments, _dense(poses[:, :2]), count, clearance, rng)
    name = f"{room.value}-{motion.value}-{seed}"
    scene = scene_from_mapping({
        "version": 1, "name": name, "walls": walls,
        "trajectory": {"poses": np.round(poses, 6).tolist()},
        "radio": {"snr_db": round(snr, 3)},
    }, f"procedural:{name}")
    return Case(room, motion, seed, snr, step, scene)


def robustness_suite(runs: int = 40, seed: int = 0) -> list[Case]:
    """``runs`` cases cycling through every motion and room kind (rooms shifted per lap, so each
    motion meets each room), seeds derived from ``seed``."""
    rooms, motions = CLASSIC_ROOMS, CLASSIC_MOTIONS
    cases = []
    for i in range(runs):
        motion = motions[i % len(motions)]
        room = rooms[(i + i // len(motions)) % len(rooms)]
        if motion is MotionKind.UTURN and room is RoomKind.POLYGON:
            room = RoomKind.HALL
        cases.append(generate_case(room, motion, seed * 1000 + i))
    return cases


@dataclass(frozen=True)
class Kidnap:
    """A scene whose terminal was carried elsewhere for ``length`` scans from scan ``start``."""

    scene: Scene
    start: int
    length: int

    @property
    def kidnapped(self) -> np.ndarray:
        """(P,) True on the scans taken elsewhere."""
        mask = np.zeros(len(self.scene.poses), bool)
        mask[self.start: self.start + self.length] = True
        return mask


def kidnapped(scene: Scene, rng: np.random.Generator, length: int = 5, min_distance_m: float = 3.0) -> Kidnap:
    """The kidnapped-terminal case of issue #12: from the middle of the walk, ``length`` scans are
    taken elsewhere in the room, then the walk resumes where it was left. "Elsewhere" is a stretch
    of the walk's own earlier poses (so clear of every wall and inside the mapped room) starting at
    least ``min_distance_m`` from where the terminal was taken, turned by a random heading."""
    poses = scene.poses
    start = len(poses) // 2
    here = poses[start - 1, :2]
    origins = np.arange(0, start - length)
    far = origins[np.linalg.norm(poses[origins, :2] - here, axis=1) >= min_distance_m]
    if not len(far):
        raise ValueError(f"{scene.name}: no earlier pose {min_distance_m} m from scan {start}")
    origin = int(rng.choice(far))
    elsewhere = poses[origin: origin + length].copy()
    elsewhere[:, 2] = np.angle(np.exp(1j * (elsewhere[:, 2] + rng.uniform(-np.pi, np.pi))))
    walk = np.vstack([poses[:start], elsewhere, poses[start:]])
    data = scene.spec.model_dump(mode="json", exclude_none=True)
    data["name"] = f"{scene.name}-kidnapped"
    data["trajectory"] = {"poses": np.round(walk, 6).tolist()}
    return Kidnap(scene_from_mapping(data, f"kidnapped:{scene.name}"), start, length)
