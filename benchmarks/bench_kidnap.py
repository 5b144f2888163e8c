"""The kidnapped terminal (issue #12, point 3): from the middle of a walk, five scans are taken
elsewhere in the room (:func:`radioslam.scene.procedural.kidnapped`), then the walk resumes.
The SLAM must not bend the map around the five: it should place them where they were (or mark
them lost) and find the terminal again when it comes back.

Prints per scene the statuses of the kidnapped scans and of the five after them, the kidnapped
scans' median error (the estimate aligned on the walk before the kidnap), the ATE of every other
scan, aligned once over the whole walk without the kidnapped scans ("after" is the part after the
kidnap in that same alignment), and whether ``tracking_lost`` or ``ambiguous_trajectory`` was set. Target:
ATE ≤ 0.2 m after it, or the run flagged.

    python benchmarks/bench_kidnap.py [--seed 1] [--scenes paper-cnv corridor-loop ...] [--cases 6]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from bench_robustness import cached_scans

from radioslam.eval.trajectory_metrics import align
from radioslam.scene import load_scene
from radioslam.scene.procedural import Kidnap, MotionKind, kidnapped, robustness_suite
from radioslam.slam import RadioSlam
from radioslam.slam.se2 import compose

TARGET_M = 0.2


def kidnap_cases(scenes: list[str], cases: int, seed: int) -> list[Kidnap]:
    """The named scenes and the first ``cases`` generated smooth, sharp and spot walks of the
    robustness suite drawn with ``seed + 100`` (cases not in the default suite), each kidnapped."""
    rng = np.random.default_rng(seed)
    walks = (MotionKind.SMOOTH, MotionKind.SHARP, MotionKind.SPOT)
    generated = [c.scene for c in robustness_suite(7 * cases, seed + 100) if c.motion in walks]
    return [kidnapped(s, rng) for s in [load_scene(n) for n in scenes] + generated[:cases]]


def evaluate(case: Kidnap, poses: np.ndarray) -> dict:
    truth, taken = case.scene.poses, case.kidnapped
    aligned_rest, _ = align(poses[~taken], truth[~taken])
    error = np.linalg.norm(aligned_rest[:, :2] - truth[~taken, :2], axis=1)
    after = np.arange(len(truth))[~taken] >= case.start + case.length
    # the kidnapped scans against the walk before them (aligned on it alone: a miss after them must not move it)
    before = np.arange(len(truth)) < case.start
    _, transform = align(poses[before], truth[before])
    kidnapped_error = np.linalg.norm(compose(transform, poses[taken])[:, :2] - truth[taken, :2], axis=1)
    return {"ate_m": float(np.sqrt(np.mean(error ** 2))), "ate_after_m": float(np.sqrt(np.mean(error[after] ** 2))),
            "kidnapped_error_m": kidnapped_error}


def letters(statuses) -> str:
    """'mmra…': each status's first letter."""
    return "".join(s.value[0] for s in statuses)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--scenes", nargs="*", default=["paper-cnv", "corridor-loop", "shelf-hall"])
    ap.add_argument("--cases", type=int, default=6, help="generated cases besides the named scenes")
    ap.add_argument("--cache", type=Path, default=Path.home() / ".cache" / "radioslam" / "kidnap")
    args = ap.parse_args()
    print(f"{'scene':34} {'start':>5} {'kidnapped: status':28} {'err m (median)':>14} {'next 5':28} "
          f"{'ATE m':>7} {'after':>7} {'lost':>5} {'ambig':>5}")
    passed = silent = 0
    cases = kidnap_cases(args.scenes, args.cases, args.seed)
    for case in cases:
        result = RadioSlam().run(cached_scans(case.scene, args.seed, args.cache))
        row = evaluate(case, result.poses)
        taken = slice(case.start, case.start + case.length)
        nxt = slice(case.start + case.length, case.start + 2 * case.length)
        passed += row["ate_after_m"] <= TARGET_M
        silent += row["ate_after_m"] > TARGET_M and not (result.tracking_lost or result.ambiguous_trajectory)
        print(f"{case.scene.name:34} {case.start:5d} {letters(result.status[taken]):28} "
              f"{np.median(row['kidnapped_error_m']):14.2f} {letters(result.status[nxt]):28} "
              f"{row['ate_m']:7.3f} {row['ate_after_m']:7.3f} {'yes' if result.tracking_lost else 'no':>5} "
              f"{'yes' if result.ambiguous_trajectory else 'no':>5}")
    print(f"\nfound again (ATE after ≤ {TARGET_M} m): {passed}/{len(cases)}; neither found nor flagged (tracking_lost "
          f"or ambiguous_trajectory): {silent}   "
          "statuses: m matched, a ambiguous, r relocalized, p predicted, s skipped, d degenerate")


if __name__ == "__main__":
    main()
