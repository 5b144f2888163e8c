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
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from radioslam.scene.errors import SceneError
from radioslam.scene.loader import scene_from_mapping
from radioslam.scene.model import Scene


def _wall(points, material: str) -> dict:
    return {"points": [[float(x), float(y)] for x, y in points], "material": material}


def paper_cnv() -> Scene:
    h = 8.0
    letters = [
        _wall([(-1.7, 0.5), (-2.5, 0.5), (-2.5, -0.5), (-1.7, -0.5)], "concrete"),  # C
        _wall([(-0.5, -0.5), (-0.5, 0.5), (0.5, -0.5), (0.5, 0.5)], "concrete"),  # N
        _wall([(1.5, 0.5), (2.0, -0.5), (2.5, 0.5)], "concrete"),  # V
    ]
    return scene_from_mapping({
        "version": 1, "name": "paper-cnv",
        "walls": [_wall([(-h, -h), (h, -h), (h, h), (-h, h), (-h, -h)], "concrete"), *letters],
        "trajectory": {"circle": {"center": [0.0, 0.0], "radius": 5.0, "poses": 60, "heading": "tangent"}},
        "radio": {"snr_db": 10.0},
    }, "builtin:paper-cnv")


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


BUILTIN_SCENES: dict[str, tuple[Callable[..., Scene], str]] = {
    "paper-cnv": (paper_cnv, "paper Fig. 6: 16 m concrete room, concrete 'CNV', 60 poses on a 5 m circle"),
    "glass-door": (glass_door, "paper Fig. 4: open glass door on the normal, concrete wall at 15 m"),
    "single-plate": (single_plate, "Table I: 1 m metal plate on the normal; 'single-plate:R' sets R m"),
}


def builtin_scene(name: str) -> Scene:
    """A built-in scene by name; ``single-plate:R`` passes the range R in metres."""
    base, _, arg = name.partition(":")
    if base not in BUILTIN_SCENES:
        raise SceneError(f"no such file or built-in scene (built-ins: {', '.join(BUILTIN_SCENES)})",
                         file=name, field="(file)")
    builder = BUILTIN_SCENES[base][0]
    if not arg:
        return builder()
    try:
        value = float(arg)
    except ValueError:
        raise SceneError(f"'{arg}' is not a number", file=name, field="(argument)") from None
    if base != "single-plate" or not 0.3 <= value <= 100.0:
        raise SceneError("only single-plate takes a range, 0.3 … 100 m", file=name, field="(argument)")
    return builder(value)
