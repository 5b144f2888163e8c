"""The named scenes' no-regression figures (issue #47): the demo's paper-cnv on seeds 1–5 (target ≤ 0.02 m)
and corridor-loop, shelf-hall and narrow-corridor on seeds 1 and 2 (target ≤ 0.15 m), ATE after the whole
SLAM, the front end's, ms per scan, the run's flags (``tracking_lost``, ``ambiguous_trajectory``) and the scans'
statuses. Scans are cached as bench_robustness.py caches them.

    python benchmarks/bench_named.py [--jobs 2]
"""

from __future__ import annotations

import argparse
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
from bench_robustness import cached_scans

from radioslam.eval.trajectory_metrics import ate_rmse
from radioslam.scene import load_scene
from radioslam.slam import RadioSlam

CHECKS = [("paper-cnv", seed, 0.02) for seed in range(1, 6)] + \
    [(name, seed, 0.15) for name in ("corridor-loop", "shelf-hall", "narrow-corridor") for seed in (1, 2)]
CACHE = Path.home() / ".cache" / "radioslam" / "robustness"


def run(check: tuple[str, int, float]) -> str:
    name, seed, target = check
    scene = load_scene(name)
    result = RadioSlam().run(cached_scans(scene, seed, CACHE))
    ate = ate_rmse(result.poses, scene.poses)
    counts = {k: v for k, v in result.status_counts().items() if v and k != "matched"}
    flags = ",".join(f for f, on in (("lost", result.tracking_lost), ("ambiguous", result.ambiguous_trajectory)) if on)
    return (f"{name:16} {seed:4d} {ate:8.4f} {ate_rmse(result.odometry, scene.poses):8.4f} {target:7.2f} "
            f"{'ok' if ate <= target else 'MISSED':>6} {np.median(result.seconds_per_scan) * 1e3:7.1f} "
            f"{flags or '-':>15}  {counts}")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--jobs", type=int, default=2)
    args = ap.parse_args()
    print(f"{'scene':16} {'seed':>4} {'ATE m':>8} {'front':>8} {'target':>7} {'':>6} {'ms/scan':>7} "
          f"{'flags':>15}  statuses")
    with ProcessPoolExecutor(args.jobs) as pool:
        for line in pool.map(run, CHECKS):
            print(line, flush=True)


if __name__ == "__main__":
    main()
