"""SLAM speed (issues #4, #12): the median SLAM time per scan on paper-cnv and on a 100-pose hall
(scans sensed once, then the SLAM run repeated), the share of it spent in the global search
(rotation candidates from the normal histograms and the branch-and-bound search over them),
and the wall time of the whole ``radioslam demo`` (simulate, sense, SLAM, evaluate, report) as
a user runs it. The plane adjustment (the last solve, once per run) is timed on its own and is not
in the per-scan figures; its row also gives it per scan of the run.

    python benchmarks/bench_slam.py [--repeats 5] [--seed 1]
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from radioslam.pipeline import calibrated_receiver
from radioslam.scene import load_scene
from radioslam.scene.procedural import MotionKind, RoomKind, generate_case
from radioslam.sim import Simulator
from radioslam.slam import RadioSlam, front_end
from radioslam.slam.branch_bound import BranchAndBound
from radioslam.slam.rotation_search import HeadingSearch


def sensed(scene, seed):
    receiver = calibrated_receiver(scene.radio, seed)
    return [receiver.sense(c).scan for c in Simulator.from_scene(scene).simulate(seed)]


def timed(scans, repeats):
    """Seconds per scan (all runs), per run, the share spent in the front end's global search, and the
    plane adjustment's seconds per run."""
    spent = [0.0]

    def clocked(function):
        def wrapper(*args, **kwargs):
            tick = time.perf_counter()
            try:
                return function(*args, **kwargs)
            finally:
                spent[0] += time.perf_counter() - tick
        return wrapper

    class FrontEndSearch(BranchAndBound):  # the front end's wide search only, not loop closure's
        search = clocked(BranchAndBound.search)

    class FrontEndHeadings(HeadingSearch):  # its rotation candidates (histogram correlation)
        headings = clocked(HeadingSearch.headings)

    front_end.BranchAndBound, front_end.HeadingSearch = FrontEndSearch, FrontEndHeadings
    per_scan, per_run, adjustment = [], [], []
    try:
        for _ in range(repeats):
            t = time.perf_counter()
            result = RadioSlam().run(scans)
            per_run.append(time.perf_counter() - t)
            per_scan.append(result.seconds_per_scan)
            adjustment.append(result.adjustment_seconds)
    finally:
        front_end.BranchAndBound, front_end.HeadingSearch = BranchAndBound, HeadingSearch
    return np.concatenate(per_scan), per_run, spent[0] / sum(per_run), np.array(adjustment)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    scene = load_scene("paper-cnv")
    scans = sensed(scene, args.seed)
    per_scan, per_run, share, adjust = timed(scans, args.repeats)
    hall = generate_case(RoomKind.HALL, MotionKind.SMOOTH, 4, snr_db=10.0, step_m=0.6, max_poses=100).scene
    hall_scans = sensed(hall, args.seed)
    hall_per_scan, _, hall_share, hall_adjust = timed(hall_scans, args.repeats)
    demo = []
    with tempfile.TemporaryDirectory() as tmp:
        for i in range(max(1, args.repeats // 2)):
            t = time.perf_counter()
            subprocess.run([str(Path(sys.executable).parent / "radioslam"), "demo", "--out", str(Path(tmp) / f"d{i}"),
                            "--seed", str(args.seed)], check=True, capture_output=True)
            demo.append(time.perf_counter() - t)
    rows = [
        ("SLAM per scan, paper-cnv (median)", f"{np.median(per_scan) * 1e3:.1f} ms",
         f"{np.percentile(per_scan, 90) * 1e3:.1f} ms", "≤ 20 ms"),
        ("  of it, global search (share)", f"{100 * share:.0f} %", "", "—"),
        ("plane adjustment, paper-cnv, per run", f"{np.median(adjust) * 1e3:.0f} ms",
         f"{np.median(adjust) / len(scans) * 1e3:.1f} ms/scan", "—"),
        (f"SLAM per scan, {len(hall_scans)}-pose hall (median)", f"{np.median(hall_per_scan) * 1e3:.1f} ms",
         f"{np.percentile(hall_per_scan, 90) * 1e3:.1f} ms", "≤ 40 ms"),
        ("  of it, global search (share)", f"{100 * hall_share:.0f} %", "", "—"),
        ("plane adjustment, hall, per run", f"{np.median(hall_adjust) * 1e3:.0f} ms",
         f"{np.median(hall_adjust) / len(hall_scans) * 1e3:.1f} ms/scan", "—"),
        ("SLAM whole run, 60 scans (median)", f"{np.median(per_run):.2f} s", f"{np.percentile(per_run, 90):.2f} s",
         "—"),
        ("radioslam demo wall time (median)", f"{np.median(demo):.1f} s", f"{max(demo):.1f} s (max)", "≤ 30 s"),
    ]
    print(f"{'measurement':36} {'median':>10} {'p90':>16}  target")
    for name, med, p90, target in rows:
        print(f"{name:36} {med:>10} {p90:>16}  {target}")
    print(f"({len(scans)} scans, {sum(len(s) for s in scans) / len(scans):.0f} points per scan, "
          f"{args.repeats} SLAM runs, {len(demo)} demo runs, seed {args.seed})")


if __name__ == "__main__":
    main()
