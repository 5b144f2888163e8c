"""Front ends alone (issue #14, point 2): radioslam's scan matching without loop closure or the last
solve, against kiss-icp and small_gicp on the same radio scans, in one run, each peer at the best of a
sweep of its settings on each scene (the best chosen on the truth: an upper bound on what a user of
that peer would get). Scenes: paper-cnv (60 scans), corridor-loop (155), shelf-hall (186).

small_gicp needs 3D structure: with z = 0 alone its normals all point along z and it never moves, so
each 2D point is extruded into a 5-point vertical column (±0.25 m). Its scan-to-model mode aligns each
scan against the last ``MODEL_SCANS`` scans placed at their estimated poses.

    python benchmarks/bench_front_end.py [--seed 1] [--cache DIR] [--scenes paper-cnv corridor-loop shelf-hall]
"""

from __future__ import annotations

import argparse
import itertools
import time
from pathlib import Path

import numpy as np
from bench_robustness import cached_scans
from bench_slam_growth import clock

from radioslam.eval.trajectory_metrics import ate_rmse
from radioslam.scene import load_scene
from radioslam.slam import SlamConfig, SlamSession
from radioslam.slam.front_end import FrontEnd

MODEL_SCANS = 10
COLUMN = np.linspace(-0.25, 0.25, 5)


def se2_of(matrix: np.ndarray) -> np.ndarray:
    return np.array([matrix[0, 3], matrix[1, 3], np.arctan2(matrix[1, 0], matrix[0, 0])])


def matrix_of(pose: np.ndarray) -> np.ndarray:
    c, s = np.cos(pose[2]), np.sin(pose[2])
    out = np.eye(4)
    out[:2, :2] = [[c, -s], [s, c]]
    out[:2, 3] = pose[:2]
    return out


def ours(scans) -> dict:
    """radioslam's front end alone: no loop closure (no candidate submap is near enough), no last solve;
    its forks, relocalization and lost-and-found stay (they are how it registers a scan)."""
    cfg = SlamConfig(loop_closure={"radius_m": 1e-9}, plane_adjustment={"enabled": False})
    spent, register = [0.0], FrontEnd.register
    clock(FrontEnd, ("register",), spent)  # timed for this run only
    try:
        session = SlamSession(cfg)
        for scan in scans:
            session.add(scan)
        result = session.finish()
    finally:
        FrontEnd.register = register
    return {"poses": result.poses, "ms": float(np.median(result.seconds_per_scan) * 1e3),
            "register_ms": spent[0] / len(scans) * 1e3, "setting": "defaults"}


def _columns(xy: np.ndarray) -> np.ndarray:
    """Each 2D point a vertical column of 5 points (±0.25 m)."""
    return np.column_stack([np.repeat(xy, len(COLUMN), axis=0), np.tile(COLUMN, len(xy))])


def small_gicp_run(scans, kind: str, to_model: bool, downsampling: float, max_distance: float) -> dict:
    import small_gicp

    clouds = [_columns(s.xy) for s in scans]
    poses, tick = [np.eye(4)], time.perf_counter()
    for k in range(1, len(clouds)):
        if to_model:
            first = max(0, k - MODEL_SCANS)
            target = np.concatenate([(poses[m][:3, :3] @ clouds[m].T).T + poses[m][:3, 3] for m in range(first, k)])
            init = poses[-1]
        else:
            target, init = clouds[k - 1], np.eye(4)
        found = small_gicp.align(target, clouds[k], init_T_target_source=init, registration_type=kind,
                                 downsampling_resolution=downsampling, voxel_resolution=max(2 * downsampling, 0.2),
                                 max_correspondence_distance=max_distance, num_threads=1)
        poses.append(found.T_target_source if to_model else poses[-1] @ found.T_target_source)
    seconds = time.perf_counter() - tick
    return {"poses": np.array([se2_of(p) for p in poses]), "ms": seconds / len(clouds) * 1e3,
            "setting": f"{kind} {'scan-to-model' if to_model else 'scan-to-scan'} ds {downsampling} d {max_distance}"}


def kiss_icp_run(scans, voxel: float, columns: bool) -> dict:
    from kiss_icp.config import KISSConfig
    from kiss_icp.kiss_icp import KissICP

    cfg = KISSConfig()
    cfg.data.max_range, cfg.data.min_range, cfg.data.deskew = 40.0, 0.0, False
    cfg.mapping.voxel_size = voxel
    odometry, poses, tick = KissICP(cfg), [], time.perf_counter()
    for scan in scans:
        cloud = _columns(scan.xy) if columns else np.column_stack([scan.xy, np.zeros(len(scan))])
        odometry.register_frame(cloud.astype(np.float64), np.zeros(len(cloud)))
        poses.append(se2_of(odometry.last_pose))
    return {"poses": np.array(poses), "ms": (time.perf_counter() - tick) / len(scans) * 1e3,
            "setting": f"voxel {voxel}{' columns' if columns else ''}"}


def best(runs, truth) -> dict:
    """The run of a peer's settings sweep with the least ATE (a failure counts as infinite)."""
    scored = []
    for run in runs:
        try:
            done = run()
            scored.append({**done, "ate": ate_rmse(done["poses"], truth)})
        except Exception as exc:  # noqa: BLE001 - a peer's failure on a setting is a result
            scored.append({"ate": float("inf"), "ms": float("nan"), "setting": f"{type(exc).__name__}"})
    return min(scored, key=lambda r: r["ate"])


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--cache", type=Path, default=Path.home() / ".cache" / "radioslam" / "front-end")
    ap.add_argument("--scenes", nargs="+", default=["paper-cnv", "corridor-loop", "shelf-hall"])
    args = ap.parse_args()
    print(f"{'scene':14} {'front end':11} {'ATE m':>7} {'ms/scan':>8}  setting")
    for name in args.scenes:
        scene = load_scene(name)
        scans, truth = cached_scans(scene, args.seed, args.cache), scene.poses
        radio = ours(scans)
        gicp = best([lambda k=k, m=m, d=d, c=c, s=scans: small_gicp_run(s, k, m, d, c) for k, m, d, c in
                     itertools.product(["ICP", "PLANE_ICP", "GICP", "VGICP"], [False, True], [0.05, 0.1], [0.5, 1.0])],
                    truth)
        kiss = best([lambda v=v, c=c, s=scans: kiss_icp_run(s, v, c) for v, c in
                     itertools.product([0.1, 0.25, 0.5], [False, True])], truth)
        print(f"{name:14} {'radioslam':11} {ate_rmse(radio['poses'], truth):7.3f} {radio['ms']:8.2f}  "
              f"(register alone {radio['register_ms']:.2f} ms)")
        for peer, row in (("small_gicp", gicp), ("kiss-icp", kiss)):
            print(f"{'':14} {peer:11} {row['ate']:7.3f} {row['ms']:8.2f}  best of its sweep: {row['setting']}")
    print(f"(seed {args.seed}; targets, issue #14: radioslam ≤ 5 ms a scan on paper-cnv, its ATE ≤ half the best "
          "peer's on two scenes of three and never worse)")


if __name__ == "__main__":
    main()
