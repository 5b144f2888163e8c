"""Point clouds as PLY (binary little endian) through ``plyfile``.

A scan is one ``vertex`` element with x, y, z (terminal frame, z = 0), power_db
(relative to the scan's strongest return), beam (codebook index i), orientation
(k) and range_m (DESIGN.md §5). A map adds nothing else; its x, y are world frame.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from plyfile import PlyData, PlyElement, PlyParseError

from radioslam.io.atomic import atomic_path
from radioslam.io.errors import PlyError
from radioslam.sensing.pointcloud import Scan

VERTEX_DTYPE = [("x", "<f8"), ("y", "<f8"), ("z", "<f8"), ("power_db", "<f4"), ("beam", "<i2"),
                ("orientation", "<u1"), ("range_m", "<f8")]


def write_scan(path: str | Path, scan: Scan, comment: str = "", xy: np.ndarray | None = None) -> None:
    """Write a scan (atomically); an empty scan is a valid file with zero vertices.

    ``xy`` replaces the terminal-frame coordinates (a fused map in the world frame).
    """
    vertices = np.empty(len(scan), dtype=VERTEX_DTYPE)
    xy = scan.xy if xy is None else xy
    vertices["x"], vertices["y"], vertices["z"] = xy[:, 0], xy[:, 1], 0.0
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
    """Read a scan written by :func:`write_scan` (angle from x, y)."""
    vertex = read_vertices(path)
    x, y = np.asarray(vertex["x"], float), np.asarray(vertex["y"], float)
    return Scan(np.asarray(vertex["range_m"], float), np.arctan2(y, x), np.asarray(vertex["power_db"], float),
                np.asarray(vertex["beam"], np.int64), np.asarray(vertex["orientation"], np.int64))


def read_map_points(path: str | Path) -> np.ndarray:
    """World-frame x, y (P, 2) of a fused map cloud."""
    vertex = read_vertices(path)
    return np.column_stack([np.asarray(vertex["x"], float), np.asarray(vertex["y"], float)])
