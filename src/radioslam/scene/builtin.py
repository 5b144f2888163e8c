"""Built-in scenes, listed by ``radioslam scenes``.

paper-cnv     the paper's Fig. 6 simulation: a 16 m × 16 m concrete room, the concrete
              letters "CNV" (about 1 m each) at its centre, 60 poses on a 5 m circle,
              heading tangent, SNR 10 dB.
glass-door    the paper's Fig. 4 experiment: an open glass door on the array normal (the
              1 m leaf stands ajar by 5°, hinged at (5, −0.5); it crosses the normal at
              4.96 m and its own specular return falls on it), side glass and concrete
              partitions at x = 5 m, a concrete wall 15 m away seen through the glass and
              the door gap, side walls at ±7.5 m and the wall behind the terminal at −8 m.
single-plate  Table I: a 1 m metal plate on the array normal at a configurable range
              (``single-plate:6.4``; 4 m by default), nothing else.
corridor-loop a 4 m wide corridor around a 14 m × 6 m block of rooms (doors open onto
              the corridor, partitions and glass inside), walked 1.2 times around on its
              centre line with rounded corners, slowing in the turns, its speed varying ±20 %.
shelf-hall    a 20 m × 16 m hall with two rows of metal shelves (a cross aisle in each)
              and two concrete pillars; the terminal goes down the central aisle, turns
              around at the end and comes back 0.8 m to the side, then along the north
              aisle and back the same way.

narrow-corridor a 2.4 m wide corridor around a 11.2 m × 4 m block (two doors into it), walked
              once around on its centre line: every wall on the sides is 1.2 m away, inside
              the 1.5 m gate of a receiver whose leakage is not calibrated (issue #13).
paper-cnv-laps  paper-cnv's room walked N times around (``paper-cnv-laps:16``; 4 by default),
              60 poses a lap, the radius wandering 5 ± 0.25 m over 2.7 laps a period, so that
              no lap retraces another: how SLAM's cost grows with revisits (issue #14).

corridor-loop and shelf-hall keep the terminal 2 m from every wall: before issue #13 nearer walls
fell inside the receiver's leakage gate (1.5 m) and only the skirts of their echoes were seen.

The last two were not used to tune anything (issue #4: scenes the SLAM was not tuned on).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from radioslam.scene.errors import SceneError
from radioslam.scene.loader import scene_from_mapping
from radioslam.scene.model import Scene
from radioslam.scene.trajectory import waypoint_poses


def _wall(points, material: str) -> dict:
    return {"points": [[float(x), float(y)] for x, y in points], "material": material}


def _paper_cnv_walls() -> list[dict]:
    h = 8.0
    letters = [
        _wall([(-1.7, 0.5), (-2.5, 0.5), (-2.5, -0.5), (-1.7, -0.5)], "concrete"),  # C
        _wall([(-0.5, -0.5), (-0.5, 0.5), (0.5, -0.5), (0.5, 0.5)], "concrete"),  # N
        _wall([(1.5, 0.5), (2.0, -0.5), (2.5, 0.5)], "concrete"),  # V
    ]
    return [_wall([(-h, -h), (h, -h), (h, h), (-h, h), (-h, -h)], "concrete"), *letters]


def paper_cnv() -> Scene:
    return scene_from_mapping({
        "version": 1, "name": "paper-cnv", "walls": _paper_cnv_walls(),
        "trajectory": {"circle": {"center": [0.0, 0.0], "radius": 5.0, "poses": 60, "heading": "tangent"}},
        "radio": {"snr_db": 10.0},
    }, "builtin:paper-cnv")


LAP_POSES = 60  # per lap, as paper-cnv's circle
LAP_RADIUS_SWING_M = 0.25  # the radius wanders 5 m ± this, over 2.7 laps a period (no lap retraces another)


def paper_cnv_laps(laps: int = 4) -> Scene:
    """paper-cnv's room walked ``laps`` times around its 5 m circle, the radius wandering smoothly by
    ±0.25 m (issue #14: how SLAM's cost grows with every revisit)."""
    i = np.arange(laps * LAP_POSES)
    phi, wander = 2.0 * np.pi * i / LAP_POSES, 2.0 * np.pi * i / (2.7 * LAP_POSES)
    radius = 5.0 + LAP_RADIUS_SWING_M * np.sin(wander)
    xy = radius[:, None] * np.column_stack([np.cos(phi), np.sin(phi)])
    # the path's tangent: r'·(cos φ, sin φ) + r·φ'·(−sin φ, cos φ), per pose index
    radial, along = LAP_RADIUS_SWING_M * np.cos(wander) / 2.7, radius
    heading = phi + np.pi / 2 - np.arctan2(radial, along)
    heading = np.angle(np.exp(1j * heading))
    return scene_from_mapping({
        "version": 1, "name": f"paper-cnv-laps-{laps}", "walls": _paper_cnv_walls(),
        "trajectory": {"poses": np.column_stack([xy, heading]).tolist()},
        "radio": {"snr_db": 10.0},
    }, f"builtin:paper-cnv-laps:{laps}")


def glass_door() -> Scene:
    opening = np.radians(5.0)
    hinge = np.array([5.0, -0.5])
    leaf_end = hinge + np.array([-np.sin(opening), np.cos(opening)])
    return scene_from_mapping({
        "version": 1, "name": "glass-door",
        "walls": [
            _wall([hinge, leaf_end], "glass"),  # the open door leaf
            _wall([(5.0, 0.5), (5.0, 3.0)], "glass"), _wall([(5.0, -3.0), (5.0, -0.5)], "glass"),
            _wall([(5.0, 3.0), (5.0, 7.5)], "concrete"), _wall([(5.0, -7.5), (5.0, -3.0)], "concrete"),
            _wall([(-8.0, -7.5), (15.0, -7.5), (15.0, 7.5), (-8.0, 7.5), (-8.0, -7.5)], "concrete"),
        ],
        "trajectory": {"poses": [[0.0, 0.0, 0.0]]},
    }, "builtin:glass-door")


def single_plate(range_m: float = 4.0) -> Scene:
    return scene_from_mapping({
        "version": 1, "name": f"single-plate-{range_m:g}m",
        "walls": [_wall([(range_m, -0.5), (range_m, 0.5)], "metal")],
        "trajectory": {"poses": [[0.0, 0.0, 0.0]]},
    }, f"builtin:single-plate:{range_m:g}")


def _rectangle(x0: float, y0: float, x1: float, y1: float) -> list[tuple[float, float]]:
    return [(x0, y0), (x1, y0), (x1, y1), (x0, y1), (x0, y0)]


def _path(waypoints) -> list[list[float]]:
    poses = waypoint_poses(np.array(waypoints, dtype=float), step_m=0.5, turn_step_deg=12.0, corner_radius_m=1.0,
                           speed_variation=0.2)
    return np.round(poses, 6).tolist()


def _runs(points: list, material: str) -> list[dict]:
    """Walls along ``points``, broken where an entry is None (a door)."""
    out, run = [], []
    for q in [*points, None]:
        if q is not None:
            run.append(q)
            continue
        if len(run) >= 2:
            out.append(_wall(run, material))
        run = []
    return out


def corridor_loop() -> Scene:
    # the block's outer wall, with a 1 m door into each of its four rooms
    block = [*_runs([(-7.0, -3.0), (-4.5, -3.0), None, (-3.5, -3.0), (2.5, -3.0), None, (3.5, -3.0), (7.0, -3.0),
                     (7.0, 3.0), (4.5, 3.0), None, (3.5, 3.0), (-2.5, 3.0), None, (-3.5, 3.0), (-7.0, 3.0),
                     (-7.0, -3.0)], "concrete")]
    inside = [_wall([(-3.0, -3.0), (-3.0, 3.0)], "concrete"), _wall([(3.0, -3.0), (3.0, 3.0)], "concrete"),
              _wall([(-3.0, 0.0), (3.0, 0.0)], "glass"), _wall([(-7.0, 0.5), (-5.0, 0.5)], "concrete")]
    return scene_from_mapping({
        "version": 1, "name": "corridor-loop",
        "walls": [_wall(_rectangle(-11.0, -7.0, 11.0, 7.0), "concrete"), *block, *inside],
        "trajectory": {"poses": _path([(-9.0, -5.0), (9.0, -5.0), (9.0, 5.0), (-9.0, 5.0), (-9.0, -5.0),
                                       (-2.0, -5.0)])},
        "radio": {"snr_db": 10.0},
    }, "builtin:corridor-loop")


def narrow_corridor() -> Scene:
    block = _runs([(-5.6, -2.0), (-2.5, -2.0), None, (-1.5, -2.0), (5.6, -2.0), (5.6, 2.0), (1.5, 2.0), None,
                   (0.5, 2.0), (-5.6, 2.0), (-5.6, -2.0)], "concrete")
    return scene_from_mapping({
        "version": 1, "name": "narrow-corridor",
        "walls": [_wall(_rectangle(-8.0, -4.4, 8.0, 4.4), "concrete"), *block],
        "trajectory": {"poses": _path([(-6.8, -3.2), (6.8, -3.2), (6.8, 3.2), (-6.8, 3.2), (-6.8, -3.2),
                                       (0.0, -3.2)])},
        "radio": {"snr_db": 10.0},
    }, "builtin:narrow-corridor")


def shelf_hall() -> Scene:
    shelves = [_wall(_rectangle(x0, y0, x1, y0 + 0.8), "metal")
               for y0 in (-3.0, 2.2) for x0, x1 in ((-5.5, -0.6), (0.6, 5.5))]
    pillars = [_wall(_rectangle(x - 0.25, y - 0.25, x + 0.25, y + 0.25), "concrete") for x in (-3.0, 3.0)
               for y in (-6.0,)]
    return scene_from_mapping({
        "version": 1, "name": "shelf-hall",
        "walls": [_wall(_rectangle(-10.0, -8.0, 10.0, 8.0), "concrete"), *shelves, *pillars],
        "trajectory": {"poses": _path([(-8.0, -0.2), (7.6, -0.2), (8.0, -0.2), (8.0, 0.6), (7.6, 0.6),
                                       (-8.0, 0.6), (-8.0, 5.1), (7.6, 5.1), (8.0, 5.1), (8.0, 5.9), (7.6, 5.9),
                                       (-8.0, 5.9)])},
        "radio": {"snr_db": 10.0},
    }, "builtin:shelf-hall")


BUILTIN_SCENES: dict[str, tuple[Callable[..., Scene], str]] = {
    "paper-cnv": (paper_cnv, "paper Fig. 6: 16 m concrete room, concrete 'CNV', 60 poses on a 5 m circle"),
    "glass-door": (glass_door, "paper Fig. 4: open glass door on the normal, concrete wall at 15 m"),
    "single-plate": (single_plate, "Table I: 1 m metal plate on the normal; 'single-plate:R' sets R m"),
    "corridor-loop": (corridor_loop, "4 m corridor around a block of rooms, 1.2 laps, rounded corners, ±20 % speed"),
    "shelf-hall": (shelf_hall, "20 m hall, two rows of metal shelves, down and back two aisles"),
    "narrow-corridor": (narrow_corridor, "2.4 m corridor around a block, walls 1.2 m to each side, one lap"),
    "paper-cnv-laps": (paper_cnv_laps, "paper-cnv walked N laps ('paper-cnv-laps:N', 4 by default), radius 5 ± 0.25 m"),
}

# the built-ins that take an argument: (kind, least, most, what it is)
BUILTIN_ARGUMENTS: dict[str, tuple[type, float, float, str]] = {
    "single-plate": (float, 0.3, 100.0, "a range, 0.3 … 100 m"),
    "paper-cnv-laps": (int, 1, 100, "a lap count, 1 … 100"),
}


def builtin_scene(name: str) -> Scene:
    """A built-in scene by name; ``single-plate:R`` passes the range R in metres, ``paper-cnv-laps:N``
    the number of laps."""
    base, _, arg = name.partition(":")
    if base not in BUILTIN_SCENES:
        raise SceneError(f"no such file or built-in scene (built-ins: {', '.join(BUILTIN_SCENES)})",
                         file=name, field="(file)")
    builder = BUILTIN_SCENES[base][0]
    if not arg:
        return builder()
    if base not in BUILTIN_ARGUMENTS:
        takes = "; ".join(f"{b} takes {what}" for b, (_, _, _, what) in BUILTIN_ARGUMENTS.items())
        raise SceneError(f"{base} takes no argument ({takes})", file=name, field="(argument)")
    kind, least, most, what = BUILTIN_ARGUMENTS[base]
    try:
        value = kind(arg)
    except ValueError:
        raise SceneError(f"'{arg}' is not {what}", file=name, field="(argument)") from None
    if not least <= value <= most:
        raise SceneError(f"{base} takes {what}", file=name, field="(argument)")
    return builder(value)
