"""Write examples/furnished-room/: a Mitsuba 3 XML scene of a furnished room (issue #16) and its scene
YAML. A 7 × 5 m room 2.8 m high (concrete walls, floor and ceiling) with a wooden table (top 0.75 m), a
metal cabinet (top 1.1 m), a low wooden shelf (top 1.2 m) and a tall metal shelf (top 2.0 m); the
terminal, 1.5 m above the floor, walks a loop around the table. The 2D walls the SLAM is judged against
are the mesh cut at 1.5 m: the room and the tall shelf; the rest is seen only by the elevation beams:
9 rows (±30°), since the table's top, 1.2–2 m from the loop and 0.75 m below the arrays, lies 20–32°
below them (7 rows, ±22°, gave it no point).

    python scripts/furnished_room.py [--out examples/furnished-room]
    radioslam run examples/furnished-room/room.yaml --out runs/furnished --channel sionna
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import yaml

from radioslam.scene.materials import ItuMaterial
from radioslam.scene.mesh import Mesh
from radioslam.scene.mitsuba import write_mitsuba

NAMES = ("concrete", "wood", "metal")
ITU = {"concrete": ItuMaterial.CONCRETE, "wood": ItuMaterial.WOOD, "metal": ItuMaterial.METAL}
LENGTH, WIDTH, HEIGHT, WALL = 7.0, 5.0, 2.8, 0.1
# (low corner, high corner, material): the furniture; its tops are what the elevation beams must find
FURNITURE = {
    "table": ((2.6, 1.9, 0.0), (4.2, 2.8, 0.75), "wood"),
    "cabinet": ((0.1, 3.6, 0.0), (0.6, 4.6, 1.1), "metal"),
    "low shelf": ((4.6, 4.5, 0.0), (6.4, 4.9, 1.2), "wood"),
    "tall shelf": ((6.5, 0.6, 0.0), (6.9, 2.2, 2.0), "metal"),
}


def room_mesh() -> Mesh:
    concrete = NAMES.index("concrete")
    slabs = [((-WALL, -WALL, -WALL), (LENGTH + WALL, WIDTH + WALL, 0.0)),  # floor
             ((-WALL, -WALL, HEIGHT), (LENGTH + WALL, WIDTH + WALL, HEIGHT + WALL)),  # ceiling
             ((-WALL, -WALL, 0.0), (0.0, WIDTH + WALL, HEIGHT)),
             ((LENGTH, -WALL, 0.0), (LENGTH + WALL, WIDTH + WALL, HEIGHT)),
             ((0.0, -WALL, 0.0), (LENGTH, 0.0, HEIGHT)), ((0.0, WIDTH, 0.0), (LENGTH, WIDTH + WALL, HEIGHT))]
    parts = [Mesh.box(lo, hi, concrete, NAMES) for lo, hi in slabs]
    parts += [Mesh.box(lo, hi, NAMES.index(m), NAMES) for lo, hi, m in FURNITURE.values()]
    return Mesh.join(parts)


def loop_poses(count: int = 24) -> list[list[float]]:
    """A rounded rectangle around the table, 1.2 m from it, heading along the path."""
    t = np.linspace(0.0, 2 * np.pi, count, endpoint=False)
    cx, cy, ax, ay = 3.4, 2.35, 2.0, 1.3
    x, y = cx + ax * np.cos(t), cy + ay * np.sin(t)
    heading = np.arctan2(ay * np.cos(t), -ax * np.sin(t))
    return [[round(float(a), 4), round(float(b), 4), round(float(h), 4)] for a, b, h in zip(x, y, heading)]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path(__file__).resolve().parents[1] / "examples" / "furnished-room")
    out = parser.parse_args().out
    write_mitsuba(out / "room.xml", room_mesh(), ITU)
    scene = {"version": 1, "name": "furnished-room", "mitsuba": "room.xml",
             "radio": {"height_m": 1.5, "elevation_beams": 9, "sionna_samples": 20_000},
             "trajectory": {"poses": loop_poses()}}
    (out / "room.yaml").write_text(yaml.safe_dump(scene, sort_keys=False), encoding="utf-8")
    print(f"wrote {out / 'room.xml'} and {out / 'room.yaml'}")


if __name__ == "__main__":
    main()
