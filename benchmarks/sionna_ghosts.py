"""What Sionna RT's extra paths do to the point clouds and the map (issue #16, point 2): floor and ceiling
returns and higher-order (wall–floor, wall–wall) ghosts, through each detector and point filter.

For paper-cnv extruded (3 m walls) without and with a concrete floor and ceiling, and for the built-in
caster, each pose is simulated as waveform IQ and sensed with the single detector (the paper's −13 dB
rule against the scan's peak, and our per-range rule) and the multi-target detector. A point is a
ghost when it lies more than ``GHOST_M`` from every true wall at the true pose. Then whole runs
(``radioslam run``-equivalent, in memory: SLAM on the scans) show which ghosts reach the map.

    python benchmarks/sionna_ghosts.py [--seed 1]    (needs Sionna RT; all 60 poses, ≈ 10 min here)
"""

from __future__ import annotations

import argparse

import numpy as np
from cross_check_sionna import extruded

from radioslam.choices import ChannelKind
from radioslam.eval.trajectory_metrics import align, ate_rmse
from radioslam.scene.geometry import point_segment_distance
from radioslam.sensing import Receiver, SensingConfig
from radioslam.sensing.config import Detector, PointFilter
from radioslam.sim import Simulator
from radioslam.slam import SlamConfig, SlamSession
from radioslam.slam.se2 import transform_points

GHOST_M = 0.10
SENSING = {"single, −13 dB of the scan's peak (the paper)": SensingConfig(point_filter=PointFilter.SCAN_PEAK),
           "single, −13 dB per range (default)": SensingConfig(),
           "multi (CFAR + cancellation)": SensingConfig(detector=Detector.MULTI)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()
    cases = [("built-in caster", extruded("paper-cnv"), ChannelKind.BUILTIN),
             ("Sionna, no floor or ceiling", extruded("paper-cnv"), ChannelKind.SIONNA),
             ("Sionna, concrete floor and ceiling", extruded("paper-cnv", "concrete", "concrete"), ChannelKind.SIONNA)]
    print("| channel | sensing | points a scan | ghosts (> 10 cm from every wall) | ghost points' power, median dB "
          "below the scan peak | SLAM ATE m (all poses) | map points > 10 cm from a wall |")
    print("|---|---|---|---|---|---|---|")
    for label, scene, kind in cases:
        simulator = Simulator.from_scene(scene, channel=kind)
        captures = list(simulator.simulate(args.seed))
        for name, sensing in SENSING.items():
            receiver = Receiver(scene.radio, scene.radio.hardware_delay_s, sensing)
            scans = [receiver.sense(c).scan for c in captures]
            points, ghosts, power = 0, 0, []
            for pose, scan in zip(scene.poses, scans):
                xy = transform_points(pose, scan.xy)
                far = point_segment_distance(xy, scene.segments).min(axis=1) > GHOST_M
                points, ghosts = points + len(scan), ghosts + int(far.sum())
                power.append(scan.power_db[far])
            session = SlamSession(SlamConfig())
            for scan in scans:
                session.add(scan)
            result = session.finish()
            aligned, _ = align(result.poses, scene.poses)  # the map frame onto the world's
            cloud = np.concatenate([transform_points(pose, scan.xy) for pose, scan in zip(aligned, scans)])
            in_map = np.mean(point_segment_distance(cloud, scene.segments).min(axis=1) > GHOST_M)
            ghost_db = np.concatenate(power)
            print(f"| {label} | {name} | {points / len(scans):.1f} | {ghosts / max(points, 1):.1%} | "
                  f"{np.median(ghost_db) if len(ghost_db) else float('nan'):.1f} | "
                  f"{ate_rmse(result.poses, scene.poses):.3f} | {in_map:.1%} |")


if __name__ == "__main__":
    main()
