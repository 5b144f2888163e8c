"""Sensing speed: median time to sense one paper-cnv pose (188 beams × 12 symbols, waveform mode),
per detector, by the receiver a run senses with (T_H and the leakage calibrated: the gate from 0.5 m).
The configurations are timed in turn within each repeat, and each one's time is also given as the
median of its per-repeat ratio to single mode's (bracketed): a load that slows the machine for a
while slows both, and the ratio stays.
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


def interleaved(receivers: dict, capture, repeats: int) -> dict:
    """Times (repeats,) of each receiver's ``sense``, taken in turn within each repeat, so that the
    machine's load at any moment falls on every configuration alike."""
    times = {name: [] for name in receivers}
    for _ in range(repeats):
        for name, rx in receivers.items():
            start = time.perf_counter()
            rx.sense(capture)
            times[name].append(time.perf_counter() - start)
    return {name: np.array(t) for name, t in times.items()}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=21)
    args = ap.parse_args()
    scene = load_scene("paper-cnv")
    cap = Simulator.from_scene(scene).simulate_pose(10, np.random.default_rng(0))
    receivers = {}
    for det in Detector:
        for refine in Refinement:
            rx = calibrated_receiver(scene.radio, 0, SensingConfig(detector=det, refine=refine))
            rx.sense(cap)
            receivers[(det, refine)] = rx
    times = interleaved(receivers, cap, args.repeats)
    reference = times[(Detector.SINGLE, Refinement.BRACKETED)]
    print(f"{'measurement':42s} {'min ms':>7s} {'median':>7s} {'p90':>7s} {'÷ single':>9s}  note")
    for (det, refine), t in times.items():
        target = "target ≤ 50 ms" if det is Detector.SINGLE else "target ≤ 60 ms (#13)"
        ratio = np.median(t / reference)  # per repeat: the load cancels
        print(f"{f'sense one pose ({det.value}, {refine.value})':42s} {t.min() * 1e3:7.2f} "
              f"{np.median(t) * 1e3:7.2f} {np.percentile(t, 90) * 1e3:7.2f} {ratio:9.2f}  {target}")


if __name__ == "__main__":
    main()
