"""`radioslam slam` on scans of up to 10⁶ points (issue #15, point 3: bounded memory, thinned, not
refused). Each case is a recorder's directory (no run.json, adopted as found) of two poses whose first
scan holds N points on the walls of an 8 m × 6 m room plus clutter; `slam` runs as a child process and
its peak RSS (getrusage) and wall time are printed, one row per N.

    python benchmarks/bench_big_scan.py [--points 1000 100000 1000000] [--work DIR] [--seed 0]
"""

from __future__ import annotations

import argparse
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from radioslam.io.ply import write_scan
from radioslam.sensing.pointcloud import Scan


def room_scan(count: int, rng: np.random.Generator) -> Scan:
    """``count`` echoes: 90 % on the room's four walls seen from (0, 0), 10 % clutter inside."""
    walls = rng.integers(0, 4, count)
    along = rng.uniform(-1.0, 1.0, count)
    x = np.choose(walls, [np.full(count, 4.0), np.full(count, -4.0), 4.0 * along, 4.0 * along])
    y = np.choose(walls, [3.0 * along, 3.0 * along, np.full(count, 3.0), np.full(count, -3.0)])
    clutter = rng.random(count) < 0.1
    x[clutter], y[clutter] = rng.uniform(-3.5, 3.5, clutter.sum()), rng.uniform(-2.5, 2.5, clutter.sum())
    return Scan(np.hypot(x, y), np.arctan2(y, x), rng.uniform(-13.0, 0.0, count),
                rng.integers(0, 47, count), rng.integers(0, 4, count))


def measure(count: int, work: Path, rng: np.random.Generator) -> tuple[float, float, int]:
    """(peak RSS MiB, wall s, exit status) of `radioslam slam` on a two-pose directory."""
    run = Path(tempfile.mkdtemp(dir=work))
    (run / "scans").mkdir()
    write_scan(run / "scans" / "0000.ply", room_scan(count, rng))
    write_scan(run / "scans" / "0001.ply", room_scan(200, rng))
    tick = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "radioslam.cli", "slam", str(run)], capture_output=True, text=True)
    wall = time.perf_counter() - tick
    if done.returncode:
        print(f"  N={count}: exit {done.returncode}: {done.stderr.strip()[:200]}", file=sys.stderr)
    return resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024, wall, done.returncode


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--points", type=int, nargs="+", default=[1_000, 100_000, 1_000_000])
    ap.add_argument("--work", type=Path, default=None)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    work = args.work or Path(tempfile.mkdtemp(prefix="radioslam-big-"))
    work.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(args.seed)
    print(f"{'points':>10} {'peak RSS MiB':>13} {'wall s':>8} {'exit':>5}")
    # RUSAGE_CHILDREN's maxrss is the largest child so far: run the sizes smallest first
    for count in sorted(args.points):
        rss, wall, status = measure(count, work, rng)
        print(f"{count:>10,} {rss:>13.0f} {wall:>8.1f} {status:>5}", flush=True)


if __name__ == "__main__":
    main()
