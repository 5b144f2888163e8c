"""Is the measurement model calibrated? (issue #47, point 1: "two poses' scores compare as a likelihood ratio")

    python benchmarks/bench_measurement.py [--every 3] [--family office] [--jobs 2]

For every ``--every``-th scan of the benchmark's radio-only cases (``suites.py``; scans from the robustness
benchmark's cache), the local map the front end would hold (the latest scans and the older ones near the
last pose) is built at the *true* poses, and branch and bound finds the scan's distinct candidate poses
within one step, as the front end searches them; each is refined, and the true pose's mode (the candidate
refined from the truth, and those within the front end's distinct radius of it) is set against the rivals.

It prints per family:
- how often a rival explains the scan better than the true pose with a perfect map (the decisions the
  measurement alone gets wrong: the motion prior must decide those), and by more than 3 nats (20 : 1);
- how often the posterior (the scaled log-likelihood plus the motion prior of each platform,
  ``slam.motion.platform``, given the true step before) would take a rival: what the front end's decision
  by posterior would get wrong with a perfect map;
- the log loss of the true pose among the candidates under a flat prior, at the model's scale
  (``measurement.TEMPERATURE``), unscaled, and at the scale that minimizes it (temperature scaling: Guo
  et al., "On calibration of modern neural networks", ICML 2017), for the points' terms alone and for the
  whole model (points and the scan's clear lines: ``measurement.line_log_likelihoods``).
"""

from __future__ import annotations

import argparse
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
from bench_robustness import sensed_scans
from scipy.special import logsumexp
from suites import BenchCase, benchmark_suite

from radioslam.slam import SlamConfig
from radioslam.slam.branch_bound import BranchAndBound, distinct
from radioslam.slam.front_end import local_map_keys
from radioslam.slam.measurement import TEMPERATURE, line_log_likelihoods, point_terms
from radioslam.slam.motion import MotionModel
from radioslam.slam.motion_prior import Platform
from radioslam.slam.refine import refine_poses
from radioslam.slam.rotation_search import HeadingSearch
from radioslam.slam.scan_points import map_grid, prepare_points
from radioslam.slam.se2 import between, wrap_angle

CACHE = Path.home() / ".cache" / "radioslam" / "robustness"
SCALES = np.exp(np.linspace(np.log(0.05), np.log(2.0), 80))


def case_terms(case: BenchCase, every: int, cache: Path = CACHE) -> list[tuple]:
    """Per sampled scan: the points' and the lines' log-likelihood terms (C,) of its candidates, which
    of them are the true pose's mode (C,), and each platform's log prior of their steps ({platform: (C,)})."""
    cfg = SlamConfig()
    f, g = cfg.front_end, cfg.grid
    truth, step_rad = case.scene.poses, np.radians(f.angle_step_deg)
    points = {k: prepare_points(scan, cfg.scan, g) for k, scan in enumerate(sensed_scans(case, cache))}
    estimates, rows = dict(enumerate(truth)), []
    for k in range(3, len(truth), every):
        matched = [m for m in range(k) if len(points[m]) >= cfg.scan.min_points]  # the front end skips the rest
        p, keys = points[k], local_map_keys(matched, estimates, f) if matched else []
        if len(p) < cfg.scan.min_points or not keys:
            continue
        grid, map_normals = map_grid(keys, estimates, points, g, observed=True)
        headings = HeadingSearch.from_config(f).headings(p.normals, map_normals, [truth[k - 1, 2], truth[k, 2]])
        found = BranchAndBound(grid, g.branch_levels).search(p.xy, p.normals, truth[k - 1, :2], headings,
                                                            cfg.motion.max_step_m, 0.0, 0.5, None, truth[k][None])
        if found.pose is None:
            continue
        rivals, _ = distinct(found.candidates, found.scores, f.distinct_m, np.radians(f.distinct_deg), 12)
        poses = refine_poses(grid, p.xy, p.normals, np.vstack([truth[k], rivals]), g.resolution_m, step_rad)
        mode = (np.linalg.norm(poses[:, :2] - truth[k, :2], axis=1) <= f.distinct_m) & \
            (np.abs(wrap_angle(poses[:, 2] - truth[k, 2])) <= np.radians(f.distinct_deg))
        mode[0] = True
        steps = np.array([between(truth[k - 1], pose) for pose in poses])
        priors = {}
        for platform in Platform:  # the true step before this one known, as the front end's tracking knows it
            motion = MotionModel.from_config(cfg.motion.model_copy(update={"platform": platform}))
            motion.velocity = between(truth[k - 2], truth[k - 1])
            priors[platform] = motion.prior(k, truth[k - 1]).log_prob(steps)
        rows.append((point_terms(grid, p.xy, p.normals, p.observation_weights, poses),
                     line_log_likelihoods(grid, p.sightings, poses, g.free_stop_m), mode, priors))
    return rows


def calibration(rows: list[tuple[np.ndarray, np.ndarray]]) -> dict:
    """From (log-likelihoods (C,), mode (C,)) per scan: how often a rival beats the true mode, and the true
    mode's log loss (nats per scan) at the model's scale, unscaled, and at the best scale."""
    margin = np.array([np.max(ll[~mode], initial=-np.inf) - ll[mode].max() for ll, mode in rows])

    def loss(scale: float) -> float:
        return float(np.mean([logsumexp(scale * ll) - logsumexp(scale * ll[mode]) for ll, mode in rows]))

    losses = np.array([loss(s) for s in SCALES])
    return {"scans": len(rows), "beaten": float(np.mean(margin > 0)), "beaten_20": float(np.mean(margin > np.log(20))),
            "loss_model": loss(TEMPERATURE), "loss_1": loss(1.0), "best_scale": float(SCALES[np.argmin(losses)]),
            "loss_best": float(losses.min())}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--every", type=int, default=3)
    ap.add_argument("--family", choices=["room", "lookalike", "office", "building"])
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--cache", type=Path, default=CACHE)
    args = ap.parse_args()
    cases = [c for c in benchmark_suite(0) if not c.with_odometry and args.family in (None, c.family)]
    with ProcessPoolExecutor(args.jobs) as pool:
        per_case = list(pool.map(case_terms, cases, [args.every] * len(cases), [args.cache] * len(cases)))
    families = {}
    for case, rows in zip(cases, per_case):
        families.setdefault(case.family, []).extend(rows)
    families["all"] = [row for rows in list(families.values()) for row in rows]
    print("the posterior's decision with a perfect map: the share of scans where a rival wins")
    print(f"{'family':10} " + " ".join(f"{p.value:>9}" for p in Platform) + f" {'no prior':>9}")
    for family, rows in families.items():
        wrong = [np.mean([not mode[np.argmax(TEMPERATURE * (p + q) + priors[platform])] for p, q, mode, priors in rows])
                 for platform in Platform]
        flat = np.mean([not mode[np.argmax(p + q)] for p, q, mode, _ in rows])
        print(f"{family:10} " + " ".join(f"{w:9.1%}" for w in wrong) + f" {flat:9.1%}")
    print(f"\nmodel scale (TEMPERATURE) {TEMPERATURE}; log loss in nats per scan (lower is better)")
    print(f"{'family':10} {'terms':7} {'scans':>6} {'rival>truth':>11} {'by 20:1':>8} {'loss@model':>10} "
          f"{'loss@1':>7} {'best scale':>10} {'loss@best':>9}")
    for family, rows in families.items():
        for terms, combine in (("points", lambda p, q: p), ("model", lambda p, q: p + q)):
            c = calibration([(combine(p, q), mode) for p, q, mode, _ in rows])
            print(f"{family:10} {terms:7} {c['scans']:6d} {c['beaten']:11.1%} {c['beaten_20']:8.1%} "
                  f"{c['loss_model']:10.3f} {c['loss_1']:7.3f} {c['best_scale']:10.2f} {c['loss_best']:9.3f}")


if __name__ == "__main__":
    main()
