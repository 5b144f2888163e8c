"""Stability of the SLAM's decisions (issue #12, point 6): every scan range perturbed by up to
1 µm (uniform, one seeded draw per run), the SLAM rerun on the same scans, and the spread
(max − min) of the ATE over the draws. Target: ≤ 1 cm on paper-cnv and corridor-loop.

    python benchmarks/bench_stability.py [--draws 10] [--seed 1] [--scenes paper-cnv corridor-loop]
"""

from __future__ import annotations

import argparse
from dataclasses import replace

import numpy as np

from radioslam.eval.trajectory_metrics import ate_rmse
from radioslam.pipeline import calibrated_receiver
from radioslam.scene import load_scene
from radioslam.sim import Simulator
from radioslam.slam import RadioSlam

PERTURBATION_M = 1e-6


def perturbed(scans, rng: np.random.Generator, bound_m: float = PERTURBATION_M):
    """The scans with every range moved by a uniform draw within ±``bound_m``."""
    return [replace(s, range_m=s.range_m + rng.uniform(-bound_m, bound_m, len(s))) for s in scans]


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--draws", type=int, default=10)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--scenes", nargs="+", default=["paper-cnv", "corridor-loop"])
    args = ap.parse_args()
    print(f"{'scene':16} {'ATE unperturbed':>16} {'min':>8} {'max':>8} {'max − min':>10}  target ≤ 0.010 m")
    for name in args.scenes:
        scene = load_scene(name)
        receiver = calibrated_receiver(scene.radio, args.seed)
        scans = [receiver.sense(c).scan for c in Simulator.from_scene(scene).simulate(args.seed)]
        base = ate_rmse(RadioSlam().run(scans).poses, scene.poses)
        rng = np.random.default_rng(args.seed)
        ates = np.array([ate_rmse(RadioSlam().run(perturbed(scans, rng)).poses, scene.poses)
                         for _ in range(args.draws)])
        print(f"{name:16} {base:16.4f} {ates.min():8.4f} {ates.max():8.4f} {ates.max() - ates.min():10.4f}")


if __name__ == "__main__":
    main()
