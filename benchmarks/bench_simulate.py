"""Benchmark: simulate one paper-cnv pose, waveform and grid mode.

Prints a table of the median and spread of the wall time per pose and the peak
traced memory (tracemalloc; numpy allocations are traced). Not a test: run it
on an idle machine and quote the medians of one run.

    python benchmarks/bench_simulate.py [--repeats 15]
"""

from __future__ import annotations

import argparse
import platform
import time
import tracemalloc

import numpy as np

from radioslam.capture import CaptureMode
from radioslam.scene import builtin_scene
from radioslam.sim import Simulator

TARGET_MS = {CaptureMode.WAVEFORM: 70.0, CaptureMode.GRID: None}  # issue #13, point 4


def measure(mode: CaptureMode, repeats: int) -> dict:
    scene = builtin_scene("paper-cnv")
    sim = Simulator.from_scene(scene, mode)
    sim.simulate_pose(0, np.random.default_rng(0))  # warm-up: caches, FFT plans
    times = []
    for i in range(repeats):
        rng = np.random.default_rng(i)
        start = time.perf_counter()
        sim.simulate_pose(i % len(scene.poses), rng)
        times.append(time.perf_counter() - start)
    tracemalloc.start()
    sim.simulate_pose(1, np.random.default_rng(1))
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    t = np.array(times) * 1e3
    return {"mode": mode.value, "median_ms": np.median(t), "p10_ms": np.percentile(t, 10),
            "p90_ms": np.percentile(t, 90), "peak_mb": peak / 2**20, "target_ms": TARGET_MS[mode]}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=15)
    args = parser.parse_args()
    rows = [measure(mode, args.repeats) for mode in CaptureMode]
    print(f"simulate one paper-cnv pose (188 beams × 13 symbols), {args.repeats} repeats, "
          f"{platform.processor() or platform.machine()}, numpy {np.__version__}")
    print(f"{'mode':10s} {'median ms':>10s} {'p10 ms':>8s} {'p90 ms':>8s} {'peak MiB':>9s} {'target':>10s}")
    for r in rows:
        target = f"≤ {r['target_ms']:.0f} ms" if r["target_ms"] else "-"
        verdict = "" if not r["target_ms"] else ("  met" if r["median_ms"] <= r["target_ms"] else "  MISSED")
        print(f"{r['mode']:10s} {r['median_ms']:10.1f} {r['p10_ms']:8.1f} {r['p90_ms']:8.1f} "
              f"{r['peak_mb']:9.1f} {target:>10s}{verdict}")
    w, g = rows
    print(f"ratio waveform/grid: {w['median_ms'] / g['median_ms']:.2f}")


if __name__ == "__main__":
    main()
