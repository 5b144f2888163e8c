"""Point clouds as PLY (binary little endian) through ``plyfile``.

A scan is one ``vertex`` element with x, y, z (terminal frame; z the height above
the arrays' centre, 0 for a flat scan), power_db (relative to the strongest return
of the point's elevation row), beam (codebook index i), orientation (k) and range_m
(DESIGN.md §5), and elevation_beam (the elevation codebook index j, issue #16;
optional on reading: a flat scan's files before it have none). A map's x, y, z are
world frame, z the height above the floor.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from plyfile import PlyData, PlyElement, PlyParseError

from radioslam.io.atomic import atomic_path
from radioslam.io.errors import PlyError
from radioslam.sensing.pointcloud import Scan

# property types Open3D's tensor reader keeps (uchar, int, float, double; 0.20 skips char, short, ushort and
# uint with a warning), so every reader sees every property
VERTEX_DTYPE = [("x", "<f8"), ("y", "<f8"), ("z", "<f8"), ("power_db", "<f4"), ("beam", "<i4"),
                ("orientation", "<u1"), ("range_m", "<f8")]
OPTIONAL_DTYPE = [("elevation_beam", "<i4")]


def write_scan(path: str | Path, scan: Scan, comment: str = "", xyz: np.ndarray | None = None) -> None:
    """Write a scan (atomically); an empty scan is a valid file with zero vertices.

    ``xyz`` (P, 3) replaces the terminal-frame coordinates (a fused map in the world frame).
    """
    vertices = np.empty(len(scan), dtype=VERTEX_DTYPE + OPTIONAL_DTYPE)
    xyz = scan.xyz if xyz is None else xyz
    vertices["x"], vertices["y"], vertices["z"] = xyz[:, 0], xyz[:, 1], xyz[:, 2]
    vertices["elevation_beam"] = scan.elevation_beam
    vertices["power_db"], vertices["beam"] = scan.power_db, scan.beam
    vertices["orientation"], vertices["range_m"] = scan.orientation, scan.range_m
    data = PlyData([PlyElement.describe(vertices, "vertex")], text=False, byte_order="<",
                   comments=[c for c in [comment] if c])
    with atomic_path(path) as tmp:
        data.write(str(tmp))


def read_vertices(path: str | Path) -> np.ndarray:
    """The vertex table of a scan or map PLY, checked for every property and finite x, y."""
    path = Path(path)
    if not path.exists():
        raise PlyError("no such file", file=path, field="(file)")
    try:
        vertex = PlyData.read(str(path))["vertex"].data
    except (KeyError, ValueError, EOFError, OSError, PlyParseError) as exc:
        raise PlyError(f"not a readable PLY point cloud: {exc}", file=path, field="vertex") from None
    missing = [name for name, _ in VERTEX_DTYPE if name not in vertex.dtype.names]
    if missing:
        raise PlyError("missing vertex property", file=path, field=f"vertex.{missing[0]}")
    for name in ("x", "y", "z", "power_db", "range_m"):  # every float field finite (NaN power: a broken sensor)
        bad = np.flatnonzero(~np.isfinite(np.asarray(vertex[name], float)))
        if len(bad):
            raise PlyError(f"non-finite value at vertex {bad[0]} ({len(bad)} in all)", file=path,
                           field=f"vertex.{name}")
    bad = np.flatnonzero(np.asarray(vertex["range_m"], float) < 0)
    if len(bad):
        raise PlyError(f"negative range at vertex {bad[0]}", file=path, field="vertex.range_m")
    return vertex


def read_scan(path: str | Path) -> Scan:
    """Read a scan written by :func:`write_scan` (azimuth from x, y; elevation from z over the range)."""
    vertex = read_vertices(path)
    x, y, z = (np.asarray(vertex[k], float) for k in ("x", "y", "z"))
    r = np.asarray(vertex["range_m"], float)
    elevation = np.arctan2(z, np.hypot(x, y))
    beam = (np.asarray(vertex["elevation_beam"], np.int64) if "elevation_beam" in vertex.dtype.names
            else np.zeros(len(r), np.int64))
    return Scan(r, np.arctan2(y, x), np.asarray(vertex["power_db"], float), np.asarray(vertex["beam"], np.int64),
                np.asarray(vertex["orientation"], np.int64), elevation, beam)


def read_map_points(path: str | Path, dims: int = 2, horizontal: bool = False) -> np.ndarray:
    """World-frame x, y (P, 2), or x, y, z (P, 3) with ``dims=3``, of a fused map cloud; ``horizontal``:
    only the horizontal elevation row's points (the SLAM's slice, what the 2D map metrics compare)."""
    vertex = read_vertices(path)
    keep = np.ones(len(vertex), bool)
    if horizontal and "elevation_beam" in vertex.dtype.names:
        keep = np.asarray(vertex["elevation_beam"]) == 0
    return np.column_stack([np.asarray(vertex[k], float)[keep] for k in ("x", "y", "z")[:dims]])
