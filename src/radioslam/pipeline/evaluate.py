"""The evaluate stage: metrics.json against the scene's ground truth (DESIGN.md §6 ★ keys)."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from radioslam.errors import RadioslamError
from radioslam.eval.map3d import height_error_summary, match_surfaces
from radioslam.eval.map_metrics import map_coverage, map_error
from radioslam.eval.ranging import beam_half_width_rad, robust_rmse, specular_range_errors
from radioslam.eval.trajectory_metrics import align, ate_rmse, rpe_rmse
from radioslam.io import read_scan, read_tum
from radioslam.io.manifest import RunManifest
from radioslam.io.ply import read_map_points
from radioslam.io.ros_map import FREE, OCCUPIED, UNKNOWN, read_ros_map
from radioslam.io.rundir import RunDir
from radioslam.io.slam_summary import read_slam_summary
from radioslam.pipeline.simulate import write_json
from radioslam.scene import load_scene
from radioslam.scene.extrude import scene_mesh
from radioslam.slam.se2 import transform_points


def evaluate_stage(out: Path) -> dict:
    """metrics.json (DESIGN.md §6 ★ keys) against the scene's ground truth."""
    with RunManifest(out).stage("evaluate"):
        return _evaluate(RunDir(out))


def _evaluate(run: RunDir) -> dict:
    tick = time.perf_counter()
    _, truth = read_tum(run.ground_truth)
    _, estimate = read_tum(run.trajectory)
    _, odometry = read_tum(run.trajectory_odometry)
    if not len(truth) == len(estimate) == len(odometry):
        raise RadioslamError(f"{len(estimate)} poses against {len(truth)} true ones", file=run.trajectory,
                             field="(poses)")
    scene = load_scene(str(run.scene))
    summary = read_slam_summary(run.slam_summary)
    _, transform = align(estimate, truth)
    cloud = read_map_points(run.map_cloud, horizontal=True)  # the SLAM's slice: the 2D metrics' points
    points = transform_points(transform, cloud)
    counts = summary.get("points_per_scan", [])
    ranging_rmse, ranging_points = robust_rmse(_ranging_errors(run, scene, truth))
    metrics = {
        "ate_rmse_m": ate_rmse(estimate, truth),
        "ate_rmse_odometry_m": ate_rmse(odometry, truth),
        "rpe_rmse_m": rpe_rmse(estimate, truth),
        "map_error_m": map_error(points, scene.segments),
        "map_coverage": map_coverage(points, scene.segments),
        **map_point_cells(run, cloud),
        "ranging_rmse_m": ranging_rmse,
        "ranging_points": ranging_points,
        "loop_closures": len(summary.get("loop_closures", [])),
        "poses": len(truth),
        "points_per_scan": float(np.mean(counts)) if counts else 0.0,
        "tracking_lost": bool(summary.get("tracking_lost", False)),
        "ambiguous_trajectory": bool(summary.get("ambiguous_trajectory", False)),
        "status_counts": summary.get("status_counts", {}),
        "lost_scans": summary.get("lost_scans", []),
        "slam_ms_per_scan": summary.get("slam_ms_per_scan_median"),
        **map_3d_metrics(run, scene, transform),
        "timings_s": {**summary.get("timings_s", {}), "evaluate": time.perf_counter() - tick},
    }
    write_json(run.metrics, metrics)
    return metrics


def map_point_cells(run: RunDir, cloud: np.ndarray) -> dict:
    """The fractions of map.ply's points that lie on occupied and on free cells of map.pgm (what
    the grid keeps of what the points show, issue #12 point 8)."""
    if not run.map_yaml.exists() or not len(cloud):
        return {}
    cells, meta = read_ros_map(run.map_yaml)
    index = np.floor((cloud - np.array(meta["origin"][:2])) / meta["resolution"]).astype(int)
    inside = np.all((index >= 0) & (index < cells.shape), axis=1)
    value = np.full(len(cloud), UNKNOWN)
    value[inside] = cells[index[inside, 0], index[inside, 1]]
    return {"map_points_occupied": float(np.mean(value == OCCUPIED)), "map_points_free": float(np.mean(value == FREE))}


def _ranging_errors(run: RunDir, scene, truth: np.ndarray) -> np.ndarray:
    """Every scan's specular ranging errors at the true poses (:mod:`radioslam.eval.ranging`)."""
    tolerance = beam_half_width_rad(scene.radio.array_elements)  # the foot within the beam's half-power width
    files = [run.scan_file(k) for k in range(len(truth))]
    if not all(f.exists() for f in files):
        return np.zeros(0)
    return np.concatenate([specular_range_errors(pose, scan.range_m, scan.angle_rad, scene.segments, tolerance)
                           for pose, scan in zip(truth, (read_scan(f).horizontal() for f in files))]
                          or [np.zeros(0)])


def map_3d_metrics(run: RunDir, scene, transform: np.ndarray) -> dict:
    """With elevation beams and a 3D scene: map.ply's points (aligned like the trajectory) against the true
    surfaces (:mod:`radioslam.eval.map3d`): the median 3D distance and the height errors on horizontal
    faces (floor, ceiling, furniture tops); nothing for a flat map or a 2D scene."""
    mesh = scene_mesh(scene)
    cloud = read_map_points(run.map_cloud, dims=3)
    if mesh is None or not len(cloud) or not np.any(np.abs(cloud[:, 2] - cloud[0, 2]) > 0):
        return {}
    points = np.column_stack([transform_points(transform, cloud[:, :2]), cloud[:, 2]])
    summary = height_error_summary(match_surfaces(points, mesh))
    return {"map_error_3d_m": summary.pop("distance_median_m", None), "height_error": summary}
