"""The sense stage: scans/NNNN.ply from captures (recorded, or simulated in memory by ``run``)."""

from __future__ import annotations

import time
from pathlib import Path

from radioslam.choices import ChannelKind
from radioslam.io import write_scan
from radioslam.io.manifest import RunManifest
from radioslam.pipeline.simulate import scene_simulator, simulate_stage
from radioslam.sensing import Receiver, SensingConfig


def sensing_settings(sensing: SensingConfig | None, cal, calibration: Path) -> dict:
    """What run.json records of a sense stage: the receiver's settings and the calibration it used."""
    return {"sensing": (sensing or SensingConfig()).model_dump(mode="json"), "calibration": str(calibration),
            "hardware_delay_s": cal.hardware_delay_s}


def simulate_and_sense(scene_name: str, out: Path, seed: int, snr_db: float | None, advance=None,
                       sensing: SensingConfig | None = None, force: bool = False,
                       max_memory: int | None = None, resume: bool = False,
                       channel: ChannelKind = ChannelKind.BUILTIN) -> dict:
    """The files of :func:`simulate_stage` and scans/ (IQ sensed in memory, by a receiver set by
    ``sensing``); stage seconds. With ``resume``, the poses whose scans an unfinished run of the same
    settings wrote (and recorded) are not simulated again."""
    timings = {}
    tick = time.perf_counter()
    scene, run, cal = simulate_stage(scene_name, out, seed, snr_db, force, max_memory=max_memory, resume=resume,
                                     channel=channel)
    timings["calibrate"] = time.perf_counter() - tick
    receiver, manifest = Receiver(scene.radio, cal.hardware_delay_s, sensing, cal.leakage), RunManifest(out)
    simulate_s = sense_s = 0.0
    with manifest.stage("sense", sensing_settings(sensing, cal, run.calibration), resume) as kept:
        done = frozenset(k for k in range(len(scene.poses)) if run.relative(run.scan_file(k)) in kept)
        for _ in done:
            if advance:
                advance()
        captures = scene_simulator(scene, run, channel).simulate(seed, skip=done)
        for _ in range(len(scene.poses) - len(done)):
            tick = time.perf_counter()
            capture = next(captures)
            simulate_s += time.perf_counter() - tick
            tick = time.perf_counter()
            path = run.scan_file(capture.pose_index)
            write_scan(path, receiver.sense(capture).scan, comment=f"pose {capture.pose_index}")
            manifest.record("sense", [path])
            sense_s += time.perf_counter() - tick
            if advance:
                advance()
    timings.update(simulate=simulate_s, sense=sense_s)
    return timings
