"""Generated offices (issue #47): rooms on both sides of a corridor 1.3–2.5 m wide, each entered
through a door, walked as a robot tours a floor: along the corridor, into some of the rooms and out,
to the corridor's end and back (the return revisits every place: loops to close).

An office is what today's rooms are not: narrow (a pose 0.5 m from a wall), long (nothing along the
corridor fixes the position but its ends and the door jambs), and repetitive (doors every few
metres). Rooms hold a box or two of furniture. Every pose keeps ``clearance`` from every wall.
"""

from __future__ import annotations

import numpy as np

from radioslam.scene.geometry import point_segment_distance
from radioslam.scene.loader import scene_from_mapping
from radioslam.scene.procedural import Case, MotionKind, RoomKind, _rotate, _segments
from radioslam.scene.trajectory import waypoint_poses

PARTITIONS = ("concrete", "concrete", "drywall", "wood")  # a room's side walls; the corridor's are concrete


def _rooms(length: float, rng: np.random.Generator) -> np.ndarray:
    """Room boundaries along the corridor (R + 1,): about 4 m wide each (±20 %), filling ``length``."""
    widths = rng.uniform(0.8, 1.2, max(1, int(round(length / 4.0))))
    return np.concatenate([[0.0], np.cumsum(widths) / widths.sum() * length])


def _side(edges: np.ndarray, wall_y: float, depth: float, sign: float, door_m: float,
          rng: np.random.Generator) -> tuple[list[np.ndarray], list[str], np.ndarray, list[np.ndarray]]:
    """One side's walls (the corridor wall with a door per room, the partitions), their materials, the
    doors' centres along x (R,), and each room's rectangle (for its furniture and the tour)."""
    corridor, partitions, materials, doors, rooms = [], [], [], [], []
    far = wall_y + sign * depth
    cursor = edges[0]
    for a, b in zip(edges[:-1], edges[1:]):
        door = rng.uniform(a + 0.4 + door_m / 2, b - 0.4 - door_m / 2)
        corridor.append(np.array([[cursor, wall_y], [door - door_m / 2, wall_y]]))
        cursor = door + door_m / 2
        doors.append(door)
        rooms.append(np.array([[a, min(wall_y, far)], [b, max(wall_y, far)]]))
        if b < edges[-1]:
            partitions.append(np.array([[b, wall_y], [b, far]]))
            materials.append(str(rng.choice(PARTITIONS)))
    corridor.append(np.array([[cursor, wall_y], [edges[-1], wall_y]]))
    return corridor + partitions, ["concrete"] * len(corridor) + materials, np.array(doors), rooms


def office_case(seed: int, snr_db: float | None = None, step_m: float = 0.5, max_poses: int = 160) -> Case:
    """One reproducible office and its tour, everything drawn from ``default_rng(seed)``."""
    rng = np.random.default_rng(seed)
    snr = float(rng.uniform(0, 20)) if snr_db is None else float(snr_db)
    width, length = rng.uniform(1.3, 2.5), rng.uniform(14.0, 24.0)
    depth_north, depth_south = rng.uniform(3.0, 5.0), rng.uniform(3.0, 5.0)
    door = rng.uniform(1.1, 1.4)
    north = _side(_rooms(length, rng), width / 2, depth_north, 1.0, door, rng)
    south = _side(_rooms(length, rng), -width / 2, depth_south, -1.0, door, rng)
    outer = np.array([[0.0, -width / 2 - depth_south], [length, -width / 2 - depth_south],
                      [length, width / 2 + depth_north], [0.0, width / 2 + depth_north],
                      [0.0, -width / 2 - depth_south]])
    walls = [(outer, "concrete")] + list(zip(north[0] + south[0], north[1] + south[1]))
    # the tour: along the corridor's centre line, into about half of the rooms (door, the room's middle,
    # back out) in the order their doors come, to the end, and back to the start
    visits = sorted(list(zip(north[2], north[3])) + list(zip(south[2], south[3])), key=lambda v: v[0])
    waypoints = [[1.0, 0.0]]
    for x, room in visits:
        if rng.uniform() < 0.5:
            inside = room.mean(axis=0)
            waypoints += [[x, 0.0], [x, inside[1]], [x, 0.0]]
    waypoints += [[length - 1.0, 0.0], [1.0, 0.0]]
    poses = waypoint_poses(np.array(waypoints), step_m, 60.0, 0.3)[:max_poses]
    walls += _furniture(north[3] + south[3], _segments([w for w, _ in walls]), poses[:, :2], rng)
    name = f"office-tour-{seed}"
    scene = scene_from_mapping({
        "version": 1, "name": name,
        "walls": [{"points": np.round(w, 6).tolist(), "material": m} for w, m in walls],
        "trajectory": {"poses": np.round(poses, 6).tolist()},
        "radio": {"snr_db": round(snr, 3)},
    }, f"office:{name}")  # the scene's own check refuses a pose within 0.2 m of a wall
    return Case(RoomKind.OFFICE, MotionKind.TOUR, seed, snr, step_m, scene)


def _furniture(rooms: list[np.ndarray], segments: np.ndarray, walk: np.ndarray,
               rng: np.random.Generator) -> list[tuple[np.ndarray, str]]:
    """Up to two boxes (desks, cabinets) per room, 0.5 m from its walls and 0.6 m from the walk."""
    out = []
    for room in rooms:
        for _ in range(int(rng.integers(0, 3))):
            for _ in range(30):
                w, h = rng.uniform(0.5, 1.6), rng.uniform(0.5, 0.9)
                box = _rotate(np.array([[-w, -h], [w, -h], [w, h], [-w, h], [-w, -h]]) / 2,
                              rng.choice([0.0, np.pi / 2]))
                box = box + rng.uniform(room[0] + 0.3, room[1] - 0.3)
                seg = _segments([box])
                if point_segment_distance(box, segments).min() >= 0.5 and \
                        point_segment_distance(walk, seg).min() >= 0.6:
                    out.append((box, str(rng.choice(["wood", "metal"]))))
                    segments = np.concatenate([segments, seg])
                    break
    return out


def office_suite(runs: int = 24, seed: int = 0) -> list[Case]:
    """``runs`` generated offices, seeds derived from ``seed``."""
    return [office_case(7000 + seed * 1000 + i) for i in range(runs)]
