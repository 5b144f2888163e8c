"""Sensing speed: median time to sense one paper-cnv pose (188 beams × 12 symbols, waveform mode),
per detector, by the receiver a run senses with (T_H and the leakage calibrated: the gate from 0.5 m).
The peak refinement's accuracy and cost on real echo peaks: ``bench_refine.py``.

    python benchmarks/bench_sense.py [--repeats 21]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from radioslam.pipeline import calibrated_receiver
from radioslam.scene import load_scene
from radioslam.sensing import Detector, Refinement, SensingConfig
from radioslam.sim import Simulator


def timed(fn, repeats):
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return np.median(times), np.percentile(times, 90)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=21)
    args = ap.parse_args()
    scene = load_scene("paper-cnv")
    cap = Simulator.from_scene(scene).simulate_pose(10, np.random.default_rng(0))
    rows = []
    for det in Detector:
        for refine in Refinement:
            rx = calibrated_receiver(scene.radio, 0, SensingConfig(detector=det, refine=refine))
            rx.sense(cap)
            med, p90 = timed(lambda rx=rx: rx.sense(cap), args.repeats)
            target = "target ≤ 50 ms" if det is Detector.SINGLE else "target ≤ 60 ms (#13)"
            rows.append((f"sense one pose ({det.value}, {refine.value})", med * 1e3, p90 * 1e3, target))
    print(f"{'measurement':42s} {'median ms':>10s} {'p90 ms':>8s}  note")
    for name, med, p90, note in rows:
        print(f"{name:42s} {med:10.2f} {p90 if p90 is not None else float('nan'):8.2f}  {note}")


if __name__ == "__main__":
    main()
