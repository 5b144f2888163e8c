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
        image = yaml_path.parent / meta["image"]
        data = image.read_bytes()
    except FileNotFoundError as exc:
        raise RosMapError("no such file", file=exc.filename, field="(file)") from None
    except (KeyError, TypeError, yaml.YAMLError):
        raise RosMapError("not a map_server YAML with an image", file=yaml_path, field="image") from None
    pixels = read_pgm(data, image)
    if pixels.dtype != np.uint8:  # a 16-bit image: scaled to 8 bits, as map_server reads it
        pixels = (pixels.astype(np.uint32) * 255 // max(int(pixels.max()), 1)).astype(np.uint8)
    return pixels[::-1].T, meta


_PGM_WHITESPACE = b" \t\n\r\v\f"


def read_pgm(data: bytes, source: Path | str = "(data)") -> np.ndarray:
    """The pixels (rows, columns) of a PGM image (Netpbm: binary P5 or plain P2, maxval up to 65535,
    16-bit samples big-endian; any whitespace between the header's fields and ``#`` comments among them)."""
    fields, position = [], 0
    while len(fields) < 4:
        while position < len(data) and (data[position] in _PGM_WHITESPACE or data[position] == ord("#")):
            if data[position] == ord("#"):  # a comment runs to the end of its line
                end = data.find(b"\n", position)
                position = len(data) if end < 0 else end + 1
            else:
                position += 1
        start = position
        while position < len(data) and data[position] not in _PGM_WHITESPACE and data[position] != ord("#"):
            position += 1
        if start == position:
            raise RosMapError("the PGM header ends early", file=source, field="header")
        fields.append(data[start:position])
    magic = fields[0]
    if magic not in (b"P5", b"P2"):
        raise RosMapError(f"not a PGM (magic {magic[:8]!r}, P5 or P2)", file=source, field="header")
    try:
        width, height, maxval = (int(f) for f in fields[1:])
    except ValueError:
        raise RosMapError("width, height and maxval must be integers", file=source, field="header") from None
    if width <= 0 or height <= 0 or not 0 < maxval < 65536:
        raise RosMapError(f"a {width}×{height} image of maxval {maxval}", file=source, field="header")
    if magic == b"P2":
        try:
            values = np.array(data[position:].split(), dtype=np.int64)
        except ValueError:
            raise RosMapError("a plain PGM's samples must be integers", file=source, field="data") from None
    else:  # exactly one whitespace character after maxval, then the raster
        dtype = np.dtype(">u2") if maxval > 255 else np.dtype(np.uint8)
        raster = data[position + 1:position + 1 + width * height * dtype.itemsize]
        values = np.frombuffer(raster, dtype=dtype)
    if values.size != width * height:
        raise RosMapError(f"{values.size} pixels, expected {width}×{height}", file=source, field="data")
    if values.max(initial=0) > maxval:
        raise RosMapError(f"a sample above maxval {maxval}", file=source, field="data")
    return values.reshape(height, width).astype(np.uint8 if maxval <= 255 else np.uint16)
