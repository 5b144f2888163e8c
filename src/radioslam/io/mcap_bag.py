"""A run as a ROS 2 bag in MCAP (issue #17), for Foxglove Studio and RViz 2 (``ros2 bag play``), written with
the ``mcap`` and ``mcap-ros2-support`` packages (no ROS install).

Topics (frames: ``map`` the SLAM's map frame, the terminal's frame at the first pose; ``base_link`` the
terminal; ``world`` the scene's frame, where the run has a ground truth):

- ``/radioslam/scan`` sensor_msgs/PointCloud2 per scan in ``base_link``, stamped at its pose: x, y, z,
  power_db (dB re. the scan's or row's strongest), range_m (float32), beam, elevation_beam (int32),
  orientation (uint8);
- ``/tf`` tf2_msgs/TFMessage per scan: map → base_link, the SLAM pose;
- ``/tf_static`` world → map (the first true pose), where there is a ground truth;
- ``/radioslam/path/slam``, ``/radioslam/path/front_end`` (map) and ``/radioslam/path/ground_truth``
  (world) nav_msgs/Path, whole, at the first stamp;
- ``/map`` nav_msgs/OccupancyGrid (0 free, 100 occupied, −1 unknown), at the first stamp;
- ``/radioslam/loop_closures`` visualization_msgs/MarkerArray, a line from each loop closure's anchor pose to
  its pose, at the first stamp.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from radioslam.io.atomic import atomic_path
from radioslam.io.ros2_messages import message_definition
from radioslam.io.ros_map import FREE, OCCUPIED
from radioslam.sensing.pointcloud import Scan

POINT_FIELDS = [("x", 7, "<f4"), ("y", 7, "<f4"), ("z", 7, "<f4"), ("power_db", 7, "<f4"), ("range_m", 7, "<f4"),
                ("beam", 5, "<i4"), ("elevation_beam", 5, "<i4"), ("orientation", 2, "u1")]  # (name, ROS type, numpy)
OCCUPIED_CELL, FREE_CELL, UNKNOWN_CELL = 100, 0, -1
TOPICS = {"scan": "/radioslam/scan", "tf": "/tf", "tf_static": "/tf_static", "slam": "/radioslam/path/slam",
          "front_end": "/radioslam/path/front_end", "ground_truth": "/radioslam/path/ground_truth", "map": "/map",
          "loops": "/radioslam/loop_closures"}


@dataclass(frozen=True)
class OccupancyImage:
    """A map_server grid: cells (NX, NY) of the trinary image (:mod:`radioslam.io.ros_map`'s pixel values)."""

    cells: np.ndarray
    resolution_m: float
    origin: tuple[float, float]


@dataclass(frozen=True)
class BagContents:
    stamps_s: np.ndarray  # (N,) each scan's time
    scans: list[Scan]  # terminal frame
    slam: np.ndarray  # (N, 3) SE(2) poses in the map frame
    front_end: np.ndarray  # (N, 3)
    grid: OccupancyImage
    loop_closures: list[tuple[int, int]]  # (anchor, pose)
    truth: np.ndarray | None = None  # (N, 3) in the scene's frame


def _time(seconds: float) -> dict:
    whole = int(np.floor(seconds))
    return {"sec": whole, "nanosec": int(round((seconds - whole) * 1e9))}


def _header(seconds: float, frame: str) -> dict:
    return {"stamp": _time(seconds), "frame_id": frame}


def _quaternion(theta: float) -> dict:
    return {"x": 0.0, "y": 0.0, "z": float(np.sin(theta / 2)), "w": float(np.cos(theta / 2))}


def _pose(pose: np.ndarray) -> dict:
    return {"position": {"x": float(pose[0]), "y": float(pose[1]), "z": 0.0}, "orientation": _quaternion(pose[2])}


def point_cloud(scan: Scan, seconds: float) -> dict:
    """sensor_msgs/PointCloud2 of a scan (little endian, one row, dense)."""
    dtype = np.dtype([(name, numpy) for name, _, numpy in POINT_FIELDS])
    points = np.zeros(len(scan), dtype=dtype)
    xyz = scan.xyz
    points["x"], points["y"], points["z"] = xyz[:, 0], xyz[:, 1], xyz[:, 2]
    points["power_db"], points["range_m"] = scan.power_db, scan.range_m
    points["beam"], points["elevation_beam"], points["orientation"] = scan.beam, scan.elevation_beam, scan.orientation
    fields = [{"name": name, "offset": dtype.fields[name][1], "datatype": ros, "count": 1}
              for name, ros, _ in POINT_FIELDS]
    return {"header": _header(seconds, "base_link"), "height": 1, "width": len(scan), "fields": fields,
            "is_bigendian": False, "point_step": dtype.itemsize, "row_step": dtype.itemsize * len(scan),
            "data": points.tobytes(), "is_dense": True}


def path_message(stamps: np.ndarray, poses: np.ndarray, seconds: float, frame: str) -> dict:
    return {"header": _header(seconds, frame),
            "poses": [{"header": _header(float(t), frame), "pose": _pose(p)} for t, p in zip(stamps, poses)]}


def transform(seconds: float, parent: str, child: str, pose: np.ndarray) -> dict:
    return {"header": _header(seconds, parent), "child_frame_id": child,
            "transform": {"translation": {"x": float(pose[0]), "y": float(pose[1]), "z": 0.0},
                          "rotation": _quaternion(pose[2])}}


def occupancy_grid(grid: OccupancyImage, seconds: float) -> dict:
    """nav_msgs/OccupancyGrid, row-major from the origin's cell (x fastest)."""
    values = np.full(grid.cells.shape, UNKNOWN_CELL, dtype=np.int8)
    values[grid.cells == OCCUPIED] = OCCUPIED_CELL
    values[grid.cells == FREE] = FREE_CELL
    nx, ny = grid.cells.shape
    origin = np.array([grid.origin[0], grid.origin[1], 0.0])
    info = {"map_load_time": _time(seconds), "resolution": float(grid.resolution_m), "width": nx, "height": ny,
            "origin": _pose(origin)}
    return {"header": _header(seconds, "map"), "info": info, "data": values.T.ravel().tolist()}


def loop_markers(poses: np.ndarray, loops: list[tuple[int, int]], seconds: float) -> dict:
    """One LINE_LIST marker: a segment from each loop closure's anchor pose to its pose."""
    points = [{"x": float(poses[k, 0]), "y": float(poses[k, 1]), "z": 0.0} for pair in loops for k in pair]
    marker = {"header": _header(seconds, "map"), "ns": "loop_closures", "id": 0, "type": 5, "action": 0,
              "pose": _pose(np.zeros(3)), "scale": {"x": 0.05, "y": 0.0, "z": 0.0},
              "color": {"r": 1.0, "g": 0.4, "b": 0.0, "a": 1.0}, "lifetime": {"sec": 0, "nanosec": 0},
              "frame_locked": False, "points": points, "colors": [], "text": "", "mesh_resource": "",
              "mesh_use_embedded_materials": False}
    return {"markers": [marker]}


def write_mcap(path: str | Path, bag: BagContents) -> dict[str, int]:
    """Write the bag (atomically); the number of messages per topic."""
    from mcap_ros2.writer import Writer

    counts: dict[str, int] = {}
    with atomic_path(path) as tmp, open(tmp, "wb") as stream:
        writer = Writer(stream)
        schemas: dict[str, object] = {}

        def put(topic: str, datatype: str, message: dict, seconds: float) -> None:
            if datatype not in schemas:
                schemas[datatype] = writer.register_msgdef(datatype, message_definition(datatype))
            time_ns = int(round(seconds * 1e9))
            writer.write_message(topic, schemas[datatype], message, log_time=time_ns, publish_time=time_ns,
                                 sequence=counts.get(topic, 0))
            counts[topic] = counts.get(topic, 0) + 1

        first = float(bag.stamps_s[0]) if len(bag.stamps_s) else 0.0
        if bag.truth is not None:  # the map frame is the terminal's frame at the first pose
            put(TOPICS["tf_static"], "tf2_msgs/msg/TFMessage",
                {"transforms": [transform(first, "world", "map", bag.truth[0])]}, first)
            put(TOPICS["ground_truth"], "nav_msgs/msg/Path", path_message(bag.stamps_s, bag.truth, first, "world"),
                first)
        put(TOPICS["slam"], "nav_msgs/msg/Path", path_message(bag.stamps_s, bag.slam, first, "map"), first)
        put(TOPICS["front_end"], "nav_msgs/msg/Path", path_message(bag.stamps_s, bag.front_end, first, "map"), first)
        put(TOPICS["map"], "nav_msgs/msg/OccupancyGrid", occupancy_grid(bag.grid, first), first)
        put(TOPICS["loops"], "visualization_msgs/msg/MarkerArray", loop_markers(bag.slam, bag.loop_closures, first),
            first)
        for t, pose, scan in zip(bag.stamps_s, bag.slam, bag.scans):
            seconds = float(t)
            put(TOPICS["tf"], "tf2_msgs/msg/TFMessage", {"transforms": [transform(seconds, "map", "base_link", pose)]},
                seconds)
            put(TOPICS["scan"], "sensor_msgs/msg/PointCloud2", point_cloud(scan, seconds), seconds)
        writer.finish()
    return counts
