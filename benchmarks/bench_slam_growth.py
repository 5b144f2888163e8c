"""SLAM's cost as the walk grows (issue #14): paper-cnv's room walked 1, 4, … laps (``paper-cnv-laps:N``,
60 poses a lap), scans sensed once and cached, each SLAM run in a process of its own so that its peak
resident memory is its own. Per lap count: the median SLAM time per scan, the median of the last 10 %
of scans against the first 10 % (a cost that grows with the walk shows there), the loop closures, the
whole run, the peak RSS and the resident memory each scan adds (fed scan by scan to a ``SlamSession``, as
online: first half of the walk against the second),
and where the time went: the back end's graph updates and solves (``BackEnd.add``, ``add_loops``,
``switch``, ``finish``), the loop search (``LoopCloser.close``) and the rest (front end, forks, lost and
found), as shares of the run, and the trajectory's ATE (a cheaper loop search must not cost accuracy).
Not a test: run it on a quiet machine and quote one run's medians.

    python benchmarks/bench_slam_growth.py [--laps 1 4] [--seed 1] [--cache DIR]
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
from bench_robustness import cached_scans

from radioslam.eval.trajectory_metrics import ate_rmse
from radioslam.scene import load_scene
from radioslam.slam import SlamSession
from radioslam.slam.back_end import BackEnd
from radioslam.slam.loop_closer import LoopCloser

BACK_END = ("add", "add_loops", "switch", "finish")


def clock(cls, names: tuple[str, ...], spent: list[float]) -> None:
    """Every method of ``cls`` in ``names`` adds its wall time to ``spent[0]``."""
    for name in names:
        method = getattr(cls, name)

        def timed(*args, _method=method, **kwargs):
            tick = time.perf_counter()
            try:
                return _method(*args, **kwargs)
            finally:
                spent[0] += time.perf_counter() - tick
        setattr(cls, name, timed)


def resident_mb() -> float:
    """This process's resident memory now (Linux /proc; NaN elsewhere)."""
    try:
        return int(Path("/proc/self/statm").read_text().split()[1]) * resource.getpagesize() / 2**20
    except OSError:
        return float("nan")


def one_run(laps: int, seed: int, cache: Path) -> dict:
    """SLAM on ``paper-cnv-laps:laps`` in this process: its figures as a dict."""
    scene = load_scene(f"paper-cnv-laps:{laps}")
    scans = cached_scans(scene, seed, cache)
    back, search = [0.0], [0.0]
    clock(BackEnd, BACK_END, back)
    clock(LoopCloser, ("close",), search)
    session, rss = SlamSession(), []
    tick = time.perf_counter()
    for scan in scans:  # scan by scan, as online: the resident memory after each
        session.add(scan)
        rss.append(resident_mb())
    result = session.finish()
    total = time.perf_counter() - tick
    per_scan = np.asarray(result.seconds_per_scan) * 1e3
    tenth = max(1, len(per_scan) // 10)
    head, tail = per_scan[:tenth], per_scan[-tenth:]
    half = len(rss) // 2
    return {"laps": laps, "poses": len(scans), "ms_median": float(np.median(per_scan)),
            "ms_first_10pct": float(np.median(head)), "ms_last_10pct": float(np.median(tail)),
            "ms_mean_first_10pct": float(np.mean(head)), "ms_mean_last_10pct": float(np.mean(tail)),
            "ms_p90_last_10pct": float(np.percentile(tail, 90)),
            "mb_per_scan_first_half": (rss[half - 1] - rss[0]) / max(1, half - 1),
            "mb_per_scan_second_half": (rss[-1] - rss[half]) / max(1, len(rss) - half - 1),
            "loops": len(result.loop_closures), "total_s": total,
            "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0,
            "back_end_share": back[0] / total, "loop_search_share": search[0] / total,
            "ate_m": ate_rmse(result.poses, scene.poses)}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--laps", type=int, nargs="+", default=[1, 4])
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--cache", type=Path, default=Path.home() / ".cache" / "radioslam" / "growth")
    ap.add_argument("--one", type=int, help=argparse.SUPPRESS)  # a child: one lap count, JSON on stdout
    args = ap.parse_args()
    if args.one is not None:
        print(json.dumps(one_run(args.one, args.seed, args.cache)))
        return
    rows = []
    for laps in args.laps:
        done = subprocess.run([sys.executable, __file__, "--one", str(laps), "--seed", str(args.seed),
                               "--cache", str(args.cache)], capture_output=True, text=True, check=True)
        rows.append(json.loads(done.stdout.strip().splitlines()[-1]))
    print(f"{'poses':>6} {'ms/scan':>8} {'first 10 %':>11} {'last 10 %':>10} {'last/first':>10} {'mean l/f':>9} "
          f"{'p90 last':>9} {'loops':>6} "
          f"{'SLAM s':>8} {'peak RSS':>9} {'MB/scan 1st½':>13} {'2nd½':>6} {'back end':>9} {'loop search':>12} "
          f"{'ATE m':>7}")
    for r in rows:
        print(f"{r['poses']:>6} {r['ms_median']:>8.1f} {r['ms_first_10pct']:>11.1f} {r['ms_last_10pct']:>10.1f} "
              f"{r['ms_last_10pct'] / r['ms_first_10pct']:>10.2f} "
              f"{r['ms_mean_last_10pct'] / r['ms_mean_first_10pct']:>9.2f} {r['ms_p90_last_10pct']:>9.1f} "
              f"{r['loops']:>6} {r['total_s']:>8.1f} "
              f"{r['peak_rss_mb']:>7.0f} MB {r['mb_per_scan_first_half']:>13.2f} {r['mb_per_scan_second_half']:>6.2f} "
              f"{100 * r['back_end_share']:>8.0f} % {100 * r['loop_search_share']:>11.0f} % {r['ate_m']:>7.3f}")
    print(f"(paper-cnv-laps:N, 60 poses a lap, seed {args.seed}; first/last 10 %: medians of the first and last "
          "tenth of the scans; mean l/f: the ratio of their means; p90 last: the 90th percentile of the last tenth; "
          "target, issue #14: a flat cost per scan, last/first ≤ 1.5)")


if __name__ == "__main__":
    main()
