"""Occupancy grids in the ROS ``map_server`` convention: ``map.pgm`` (P5, row 0 at the top,
i.e. the largest y) and ``map.yaml`` (image, resolution, origin of the lower-left pixel,
negate, occupied_thresh, free_thresh, mode trinary). Occupied cells are 0 (black), free 254,
unknown 205, as ``map_saver`` writes them.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import yaml

from radioslam.io.atomic import atomic_path, atomic_write_text
from radioslam.io.errors import RosMapError
from radioslam.slam.occupancy import OccupancyGrid

OCCUPIED_THRESH, FREE_THRESH = 0.65, 0.196
OCCUPIED, FREE, UNKNOWN = 0, 254, 205


def write_ros_map(yaml_path: str | Path, grid: OccupancyGrid) -> None:
    """Write ``<name>.pgm`` next to ``yaml_path`` and the YAML that points at it (atomically)."""
    yaml_path = Path(yaml_path)
    pgm_path = yaml_path.with_suffix(".pgm")
    p = grid.probability
    image = np.full(p.shape, UNKNOWN, dtype=np.uint8)
    image[p > OCCUPIED_THRESH] = OCCUPIED
    image[p < FREE_THRESH] = FREE
    rows = image.T[::-1]  # (NY, NX), top row = largest y
    header = f"P5\n# radioslam occupancy grid\n{rows.shape[1]} {rows.shape[0]}\n255\n".encode()
    with atomic_path(pgm_path) as tmp:
        Path(tmp).write_bytes(header + rows.tobytes())
    meta = {"image": pgm_path.name, "resolution": float(grid.resolution),
            "origin": [float(grid.origin[0]), float(grid.origin[1]), 0.0], "negate": 0,
            "occupied_thresh": OCCUPIED_THRESH, "free_thresh": FREE_THRESH, "mode": "trinary"}
    atomic_write_text(yaml_path, yaml.safe_dump(meta, sort_keys=False))


def read_ros_map(yaml_path: str | Path) -> tuple[np.ndarray, dict]:
    """The trinary image as cells (NX, NY) indexed like :class:`OccupancyGrid` and the YAML fields."""
    yaml_path = Path(yaml_path)
    try:
        meta = yaml.safe_load(yaml_path.read_text(encoding="utf-8"))
        data = (yaml_path.parent / meta["image"]).read_bytes()
    except FileNotFoundError as exc:
        raise RosMapError("no such file", file=exc.filename, field="(file)") from None
    except (KeyError, TypeError, yaml.YAMLError):
        raise RosMapError("not a map_server YAML with an image", file=yaml_path, field="image") from None
    parts = data.split(b"\n", 4)
    if parts[0] != b"P5" or len(parts) < 5:
        raise RosMapError("not a binary PGM (P5)", file=yaml_path.parent / meta["image"], field="header")
    width, height = (int(v) for v in parts[2].split())
    pixels = np.frombuffer(parts[4], dtype=np.uint8)
    if pixels.size != width * height:
        raise RosMapError(f"{pixels.size} pixels, expected {width}×{height}", file=yaml_path.parent / meta["image"],
                          field="data")
    return pixels.reshape(height, width)[::-1].T, meta
