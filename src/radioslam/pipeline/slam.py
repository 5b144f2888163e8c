"""The slam stage: trajectories, maps and slam.json from scans/."""

from __future__ import annotations

import re
import time
from pathlib import Path

import numpy as np

from radioslam.errors import RadioslamError
from radioslam.io import read_scan, read_tum, write_scan, write_tum
from radioslam.io.manifest import RunManifest
from radioslam.io.ros_map import write_ros_map
from radioslam.io.rundir import RunDir
from radioslam.io.tum import headings_at, read_angular_rate
from radioslam.pipeline.simulate import write_json
from radioslam.progress import SILENT, Progress
from radioslam.sensing.pointcloud import Scan
from radioslam.slam import RadioSlam, ScanStatus, SlamConfig, SlamResult
from radioslam.slam.occupancy import occupancy_grid
from radioslam.slam.se2 import compose, transform_points
from radioslam.slam.thinning import thin_scan


def read_scans(run: RunDir) -> list[Scan]:
    """scans/NNNN.ply in pose order; every pose from 0 on must have one."""
    files = sorted((f for f in run.scans.glob("*.ply") if re.fullmatch(r"\d{4,}\.ply", f.name)),
                   key=lambda f: int(f.stem)) if run.scans.is_dir() else []
    if not files:
        raise RadioslamError("no scans (NNNN.ply); run 'radioslam sense' first", file=run.scans, field="(directory)")
    indices = [int(f.stem) for f in files]
    if indices != list(range(len(files))):
        missing = sorted(set(range(max(indices) + 1)) - set(indices))[0]
        raise RadioslamError("missing scan of a pose", file=run.scan_file(missing), field="(file)")
    return [read_scan(f) for f in files]


def slam_stage(out: Path, cfg: SlamConfig | None = None, timings: dict | None = None,
               odometry: Path | None = None, scene_frame: bool = False, progress: Progress = SILENT) -> SlamResult:
    """Trajectories, maps and slam.json from scans/ (and an external odometry TUM file, if given); with
    ``scene_frame``, trajectory_scene.tum too: the trajectory in the scene's frame, the map frame (the
    terminal's frame at the first pose) placed at the first true pose of ground_truth.tum."""
    run, cfg = RunDir(out), cfg or SlamConfig()
    settings = {"slam": cfg.model_dump(mode="json"), "odometry": None if odometry is None else str(odometry)}
    if scene_frame:
        settings["scene_frame"] = True
    with RunManifest(out).stage("slam", settings, external=[odometry] if odometry is not None else []):
        scans = read_scans(run)
        odometry_poses = read_odometry(odometry, len(scans)) if odometry is not None else None
        tick = time.perf_counter()
        try:
            result = RadioSlam(cfg).run(scans, odometry_poses, progress)
        except RadioslamError as exc:  # the driver knows the field and reason, this stage the files
            raise RadioslamError(exc.reason, file=exc.file or run.scans, field=exc.field) from None
        write_slam_outputs(run, scans, result, cfg, {**(timings or {}), "slam": time.perf_counter() - tick},
                           odometry)
        if scene_frame:
            write_scene_frame(run, result.poses)
    return result


def write_scene_frame(run: RunDir, poses: np.ndarray) -> None:
    """trajectory_scene.tum: ``poses`` (map frame) composed onto the first true pose."""
    if not run.ground_truth.exists():
        raise RadioslamError("no ground truth to place the map frame by (--scene-frame: a simulated run's)",
                             file=run.ground_truth, field="(file)")
    _, truth = read_tum(run.ground_truth)
    if len(truth) != len(poses):
        raise RadioslamError(f"{len(truth)} true poses for {len(poses)} scans", file=run.ground_truth,
                             field="(poses)")
    write_tum(run.trajectory_scene, run.pose_timestamps(len(poses)), compose(truth[0][None, :], poses))


def write_slam_outputs(run: RunDir, scans: list[Scan], result: SlamResult, cfg: SlamConfig, timings: dict,
                       odometry: Path | None = None) -> None:
    """trajectory.tum, trajectory_odometry.tum, map.pgm + map.yaml, map.ply and slam.json of a SLAM run."""
    stamps = run.pose_timestamps(len(scans))
    write_tum(run.trajectory, stamps, result.poses)
    write_tum(run.trajectory_odometry, stamps, result.odometry)
    if result.alternative is not None:  # the runner-up within the stated odds (ambiguous_trajectory)
        write_tum(run.trajectory_alternative, stamps, result.alternative)
    kept = [k for k, status in enumerate(result.status) if status is not ScanStatus.SKIPPED]
    clouds, scans = scans, [scan.horizontal() for scan in scans]  # 3D clouds; the SE(2) SLAM's slice
    thinned = [thin_scan(scans[k], cfg.scan.max_points, cfg.scan.max_range_m, cfg.grid.resolution_m)[0] for k in kept]
    write_ros_map(run.map_yaml, occupancy_grid(result.poses[kept], [s.xy for s in thinned], cfg.map))
    fused = Scan.concatenate([clouds[k] for k in kept])
    world = (np.concatenate([transform_points(result.poses[k], clouds[k].xy) for k in kept]) if kept
             else np.zeros((0, 2)))
    terminal_height, height_from = run.terminal_height_m()
    height = fused.z + terminal_height  # the terminal is level: a point's height above the floor
    write_scan(run.map_cloud, fused, comment="fused map, world frame, z above the floor",
               xyz=np.column_stack([world, height]))
    write_json(run.slam_summary, {
        "scan_status": [status.value for status in result.status],
        "map_height": {"terminal_height_m": terminal_height, "from": height_from},
        "status_counts": result.status_counts(),
        "tracking_lost": result.tracking_lost,
        "lost_scans": result.lost_scans,
        "ambiguous_trajectory": result.ambiguous_trajectory,
        "trajectory_source": result.source,
        "alternative": None if result.alternative is None else {
            "source": result.alternative_source, "odds": round(result.alternative_odds, 3)},
        "match_score": [None if np.isnan(v) else round(float(v), 4) for v in result.match_score],
        "ms_per_scan": [round(float(v) * 1e3, 3) for v in result.seconds_per_scan],
        "loop_closures": [{"anchor": lc.anchor, "pose": lc.key, "score": lc.score, "weight": lc.weight}
                          for lc in result.loop_closures],
        "relocalizations": [{"anchor": lc.anchor, "pose": lc.key, "score": lc.score}
                            for lc in result.loops if lc.relocalization],
        "plane_adjustment": None if result.planes is None else {
            "walls": [[round(float(np.degrees(psi)), 4), round(float(d), 4)] for psi, d in result.planes.walls],
            "sightings": result.planes.sightings, "sightings_used": result.planes.sightings_used,
            "placed_scans": result.planes.placed,
            "ms": round(result.adjustment_seconds * 1e3, 3)},
        "points_per_scan": [len(s) for s in scans],
        "odometry": str(odometry) if odometry is not None else None,
        "warnings": result.warnings,
        "slam_ms_per_scan_median": float(np.median(result.seconds_per_scan) * 1e3),
        "timings_s": timings,
        "config": cfg.model_dump(mode="json"),
    })


def read_odometry(path: Path, scans: int) -> np.ndarray:
    """External odometry poses (P, 3), one per scan in pose order: a TUM file (x and y ``nan`` on every line:
    a gyro, its turns alone measured), or an IMU's angular rate (``.csv``: timestamp, wz) integrated to the
    scans' timestamps (then x and y are NaN)."""
    path = Path(path)
    if path.suffix.lower() == ".csv":
        times, rates = read_angular_rate(path)
        stamps = RunDir.pose_timestamps(scans)
        if stamps[0] < times[0] or stamps[-1] > times[-1]:
            raise RadioslamError(f"the rates span {times[0]:g}–{times[-1]:g} s, the scans {stamps[0]:g}–"
                                 f"{stamps[-1]:g} s", file=path, field="timestamp")
        heading = headings_at(stamps, times, rates)
        return np.column_stack([np.full(scans, np.nan), np.full(scans, np.nan), heading])
    _, poses = read_tum(path, unknown_translation=True)
    if len(poses) != scans:
        raise RadioslamError(f"{len(poses)} odometry poses for {scans} scans (one per scan)", file=path,
                             field="(poses)")
    return poses
