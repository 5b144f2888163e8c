"""SLAM speed (issue #4): the median SLAM time per scan on paper-cnv (scans sensed once, then
the SLAM run repeated), and the wall time of the whole ``radioslam demo`` (simulate, sense,
SLAM, evaluate, report) as a user runs it.

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

from radioslam.scene import load_scene
from radioslam.sensing import Receiver
from radioslam.sim import Simulator
from radioslam.slam import RadioSlam


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    scene = load_scene("paper-cnv")
    receiver = Receiver(scene.radio, scene.radio.hardware_delay_s)
    scans = [receiver.sense(c).scan for c in Simulator.from_scene(scene).simulate(args.seed)]
    per_scan, per_run = [], []
    for _ in range(args.repeats):
        t = time.perf_counter()
        result = RadioSlam().run(scans)
        per_run.append(time.perf_counter() - t)
        per_scan.append(result.seconds_per_scan)
    per_scan = np.concatenate(per_scan)
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
