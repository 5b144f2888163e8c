"""The stages over a run directory (DESIGN.md §5 ★): simulate → sense → slam → evaluate.

Each stage reads what the one before wrote, so the command line can run them one by one
(``simulate``, ``sense``, ``slam``, ``evaluate``) or all at once (``run``, ``demo``).
"""

from __future__ import annotations

import hashlib
import re
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from radioslam.choices import ChannelKind
from radioslam.errors import RadioslamError
from radioslam.eval.map3d import height_error_summary, match_surfaces
from radioslam.eval.map_metrics import map_coverage, map_error
from radioslam.eval.ranging import beam_half_width_rad, robust_rmse, specular_range_errors
from radioslam.eval.trajectory_metrics import align, ate_rmse, rpe_rmse
from radioslam.io import read_calibration, read_scan, read_tum, write_calibration, write_scan, write_tum
from radioslam.io.atomic import atomic_write_text
from radioslam.io.json_io import dumps
from radioslam.io.manifest import RunManifest
from radioslam.io.ply import read_map_points
from radioslam.io.ros_map import FREE, OCCUPIED, UNKNOWN, read_ros_map, write_ros_map
from radioslam.io.rundir import RunDir
from radioslam.io.slam_summary import read_slam_summary
from radioslam.io.trace_cache import TraceCache
from radioslam.scene import Scene, load_scene, scene_to_yaml
from radioslam.scene.extrude import scene_mesh
from radioslam.sensing import Receiver, SensingConfig, estimate_hardware_delay
from radioslam.sensing.pointcloud import Scan
from radioslam.sim import Simulator
from radioslam.sim.calibration_targets import calibration_ranges, simulate_calibration
from radioslam.sim.channel_backend import check_channel
from radioslam.sim.memory import check_budget, default_budget
from radioslam.sim.odometry import odometry_rng, simulated_odometry
from radioslam.slam import RadioSlam, ScanStatus, SlamConfig, SlamResult
from radioslam.slam.occupancy import occupancy_grid
from radioslam.slam.se2 import transform_points
from radioslam.slam.thinning import thin_scan

SIMULATED_ODOMETRY = "simulated"  # run --odometry simulated: the scene's own drifting odometry


def simulated_calibration(radio, seed: int, targets: int | None = None, spacing: float | None = None):
    """eq. (11) on metal plates simulated with this radio, and the leakage of a sweep with nothing in range."""
    ranges = calibration_ranges(radio, targets, spacing)
    captures, empty = simulate_calibration(radio, ranges, seed)
    return estimate_hardware_delay(captures, ranges, source=f"simulated: {len(ranges)} metal plates and an empty "
                                   f"sweep, seed {seed}", empty=empty)


def calibrated_receiver(radio, seed: int, sensing: SensingConfig | None = None) -> Receiver:
    """The receiver a run of this radio senses with: T_H and the leakage from :func:`simulated_calibration`."""
    cal = simulated_calibration(radio, seed)
    return Receiver(radio, cal.hardware_delay_s, sensing, cal.leakage)


def calibrate_simulated(radio, out: Path, seed: int, targets: int | None = None, spacing: float | None = None):
    """:func:`simulated_calibration`, written to ``calibration.json``."""
    cal = simulated_calibration(radio, seed, targets, spacing)
    write_calibration(out, cal)
    return cal


def write_json(path: Path, doc: dict) -> None:
    """Strict JSON: a figure that does not exist (NaN) is null."""
    atomic_write_text(path, dumps(doc, indent=2) + "\n")


def simulate_stage(scene_name: str, out: Path, seed: int, snr_db: float | None, force: bool = False,
                   captures: Callable[[Scene, RunDir, set[str]], None] | None = None, max_memory: int | None = None,
                   resume: bool = False, channel: ChannelKind = ChannelKind.BUILTIN):
    """A new run in ``out`` (the old one there replaced whole, run.json): scene.yaml, ground_truth.tum and
    calibration.json (eq. (11) on plates simulated with this scene's radio), and what ``captures`` writes
    (given the files a resumed run kept); the scene, the run directory and the calibration. With
    ``resume``, an unfinished run of the same scene, seed and settings there is gone on with."""
    scene = load_scene(scene_name).with_radio(snr_db=snr_db)
    # what one pose needs, and the calibration's empty sweep (every beam too), before anything is written
    check_budget(Simulator.from_scene(scene, channel=channel).memory(), max_memory or default_budget(), scene_name)
    check_channel(channel, scene, scene_name)
    run, manifest = RunDir(out), RunManifest(out)
    manifest.new_run(seed, scene_name, force, resume)
    scene_text = scene_to_yaml(scene)
    settings = {"scene": scene_name, "scene_sha256": hashlib.sha256(scene_text.encode()).hexdigest(), "seed": seed,
                "snr_db": snr_db, "save_iq": captures is not None, "radio": scene.radio.model_dump(mode="json"),
                "channel": ChannelKind(channel).value}
    if resume and manifest.is_complete("simulate", settings):
        return scene, run, read_calibration(run.calibration)
    with manifest.stage("simulate", settings, resume) as kept:
        atomic_write_text(run.scene, scene_text)
        write_tum(run.ground_truth, run.pose_timestamps(len(scene.poses)), scene.poses)
        if scene.spec.odometry is not None:  # a drifting wheel/IMU odometry of the same walk
            write_tum(run.odometry, run.pose_timestamps(len(scene.poses)),
                      simulated_odometry(scene.poses, scene.spec.odometry, odometry_rng(seed)))
        cal = calibrate_simulated(scene.radio, run.calibration, seed)
        if captures is not None:
            captures(scene, run, kept)
    return scene, run, cal


def scene_simulator(scene: Scene, run: RunDir, channel: ChannelKind = ChannelKind.BUILTIN) -> Simulator:
    """The simulator of a run's scene; a ray tracer's paths are kept in the run's traces/ (issue #16)."""
    return Simulator.from_scene(scene, channel=channel, trace_cache=TraceCache(run.traces))


def sensing_settings(sensing: SensingConfig | None, cal, calibration: Path) -> dict:
    """What run.json records of a sense stage: the receiver's settings and the calibration it used."""
    return {"sensing": (sensing or SensingConfig()).model_dump(mode="json"), "calibration": str(calibration),
            "hardware_delay_s": cal.hardware_delay_s}


def simulate_and_sense(scene_name: str, out: Path, seed: int, snr_db: float | None, advance=None,
                       sensing: SensingConfig | None = None, force: bool = False,
                       max_memory: int | None = None, resume: bool = False,
                       channel: ChannelKind = ChannelKind.BUILTIN) -> dict:
    """The files of :func:`simulate_stage` and scans/ (IQ sensed in memory, by a receiver set by
    ``sensing``); stage seconds. With ``resume``, the poses whose scans an unfinished run of the same
    settings wrote (and recorded) are not simulated again."""
    timings = {}
    tick = time.perf_counter()
    scene, run, cal = simulate_stage(scene_name, out, seed, snr_db, force, max_memory=max_memory, resume=resume,
                                     channel=channel)
    timings["calibrate"] = time.perf_counter() - tick
    receiver, manifest = Receiver(scene.radio, cal.hardware_delay_s, sensing, cal.leakage), RunManifest(out)
    simulate_s = sense_s = 0.0
    with manifest.stage("sense", sensing_settings(sensing, cal, run.calibration), resume) as kept:
        done = frozenset(k for k in range(len(scene.poses)) if run.relative(run.scan_file(k)) in kept)
        for _ in done:
            if advance:
                advance()
        captures = scene_simulator(scene, run, channel).simulate(seed, skip=done)
        for _ in range(len(scene.poses) - len(done)):
            tick = time.perf_counter()
            capture = next(captures)
            simulate_s += time.perf_counter() - tick
            tick = time.perf_counter()
            path = run.scan_file(capture.pose_index)
            write_scan(path, receiver.sense(capture).scan, comment=f"pose {capture.pose_index}")
            manifest.record("sense", [path])
            sense_s += time.perf_counter() - tick
            if advance:
                advance()
    timings.update(simulate=simulate_s, sense=sense_s)
    return timings


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
               odometry: Path | None = None) -> SlamResult:
    """Trajectories, maps and slam.json from scans/ (and an external odometry TUM file, if given)."""
    run, cfg = RunDir(out), cfg or SlamConfig()
    settings = {"slam": cfg.model_dump(mode="json"), "odometry": None if odometry is None else str(odometry)}
    with RunManifest(out).stage("slam", settings, external=[odometry] if odometry is not None else []):
        scans = read_scans(run)
        odometry_poses = read_odometry(odometry, len(scans)) if odometry is not None else None
        tick = time.perf_counter()
        try:
            result = RadioSlam(cfg).run(scans, odometry_poses)
        except RadioslamError as exc:  # the driver knows the field and reason, this stage the files
            raise RadioslamError(exc.reason, file=exc.file or run.scans, field=exc.field) from None
        write_slam_outputs(run, scans, result, cfg, {**(timings or {}), "slam": time.perf_counter() - tick},
                           odometry)
    return result


def write_slam_outputs(run: RunDir, scans: list[Scan], result: SlamResult, cfg: SlamConfig, timings: dict,
                       odometry: Path | None = None) -> None:
    """trajectory.tum, trajectory_odometry.tum, map.pgm + map.yaml, map.ply and slam.json of a SLAM run."""
    stamps = run.pose_timestamps(len(scans))
    write_tum(run.trajectory, stamps, result.poses)
    write_tum(run.trajectory_odometry, stamps, result.odometry)
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
    """External odometry poses (P, 3) from a TUM file, one per scan in pose order."""
    _, poses = read_tum(path)
    if len(poses) != scans:
        raise RadioslamError(f"{len(poses)} odometry poses for {scans} scans (one per scan)", file=path,
                             field="(poses)")
    return poses


def run_scene(scene_name: str, out: Path, seed: int, snr_db: float | None, advance=None,
              cfg: SlamConfig | None = None, odometry: Path | None = None,
              sensing: SensingConfig | None = None, force: bool = False,
              max_memory: int | None = None, resume: bool = False,
              channel: ChannelKind = ChannelKind.BUILTIN) -> tuple[SlamResult, dict]:
    """Simulate and sense, SLAM, evaluate: a whole run directory; the SLAM result and metrics."""
    simulated = odometry is not None and str(odometry) == SIMULATED_ODOMETRY
    if simulated and load_scene(scene_name).spec.odometry is None:
        raise RadioslamError("the scene has no odometry: block to simulate one from", file=scene_name,
                             field="odometry")
    timings = simulate_and_sense(scene_name, out, seed, snr_db, advance, sensing, force, max_memory, resume, channel)
    result = slam_stage(out, cfg, timings, RunDir(out).odometry if simulated else odometry)
    return result, evaluate_stage(out)


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


def evaluate_stage(out: Path) -> dict:
    """metrics.json (DESIGN.md §6 ★ keys) against the scene's ground truth."""
    with RunManifest(out).stage("evaluate"):
        return _evaluate(RunDir(out))


def report_stage(out: Path) -> Path:
    """report.html and its figures."""
    from radioslam.viz.report import write_report

    with RunManifest(out).stage("report"):
        return write_report(out)


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
        "status_counts": summary.get("status_counts", {}),
        "lost_scans": summary.get("lost_scans", []),
        "slam_ms_per_scan": summary.get("slam_ms_per_scan_median"),
        **map_3d_metrics(run, scene, transform),
        "timings_s": {**summary.get("timings_s", {}), "evaluate": time.perf_counter() - tick},
    }
    write_json(run.metrics, metrics)
    return metrics
