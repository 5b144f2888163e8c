"""A whole run (simulate → sense → slam → evaluate) and its report."""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path

from radioslam.choices import ChannelKind
from radioslam.errors import RadioslamError
from radioslam.io.manifest import RunManifest
from radioslam.io.rundir import RunDir
from radioslam.pipeline.evaluate import evaluate_stage
from radioslam.pipeline.sense import sense_stage, simulate_and_sense
from radioslam.pipeline.simulate import capture_writer, simulate_stage
from radioslam.pipeline.slam import slam_stage
from radioslam.progress import SILENT, Progress
from radioslam.scene import load_scene
from radioslam.sensing import SensingConfig
from radioslam.sim.odometry import per_step_sigmas
from radioslam.slam import SlamConfig, SlamResult

SIMULATED_ODOMETRY = "simulated"  # run --odometry simulated: the scene's own drifting odometry


@dataclass(frozen=True)
class RunOptions:
    """Every stage's settings of a whole run: the command line's options and a config file's sections."""

    seed: int = 0
    snr_db: float | None = None  # the reference echo's per-RE SNR; None: the scene's
    radio: dict = field(default_factory=dict)  # fields of the scene's radio to replace (a config's radio:)
    sensing: SensingConfig = field(default_factory=SensingConfig)
    slam: SlamConfig = field(default_factory=SlamConfig)
    odometry: Path | None = None  # a TUM file, or SIMULATED_ODOMETRY: the scene's own
    channel: ChannelKind = ChannelKind.BUILTIN
    save_iq: bool = False  # write captures/ and sense them from the files, as the stages one by one do
    plot_pose: int = 0  # the pose whose radar heatmap scans/NNNN.png shows (−1: none)
    scene_frame: bool = False  # also trajectory_scene.tum, the trajectory in the scene's frame
    force: bool = False
    max_memory: int | None = None
    resume: bool = False


def run_scene(scene_name: str, out: Path, options: RunOptions | None = None,
              progress: Progress = SILENT) -> tuple[SlamResult, dict]:
    """Simulate and sense, SLAM, evaluate: a whole run directory; the SLAM result and metrics."""
    o = options or RunOptions()
    simulated = o.odometry is not None and str(o.odometry) == SIMULATED_ODOMETRY
    slam = o.slam
    if simulated:
        scene = load_scene(scene_name)
        if scene.spec.odometry is None:
            raise RadioslamError("the scene has no odometry: block to simulate one from", file=scene_name,
                                 field="odometry")
        slam = slam.with_odometry_noise(*per_step_sigmas(scene.spec.odometry, scene.poses))  # its stated noise
    if o.save_iq:  # the stages one by one: captures written, then read back and sensed
        tick = time.perf_counter()
        simulate_stage(scene_name, out, o.seed, o.snr_db, o.force, capture_writer(o.seed, o.channel, progress),
                       o.max_memory, o.resume, o.channel, o.radio)
        timings = {"simulate": time.perf_counter() - tick}
        tick = time.perf_counter()
        sense_stage(out, o.sensing, None, o.plot_pose, o.max_memory, o.resume, progress)
        timings["sense"] = time.perf_counter() - tick
    else:
        timings = simulate_and_sense(scene_name, out, o.seed, o.snr_db, progress, o.sensing, o.force, o.max_memory,
                                     o.resume, o.channel, o.radio, o.plot_pose)
    result = slam_stage(out, slam, timings, RunDir(out).odometry if simulated else o.odometry, o.scene_frame,
                        progress)
    return result, evaluate_stage(out)


def report_stage(out: Path) -> Path:
    """report.html and its figures."""
    from radioslam.viz.report import write_report

    with RunManifest(out).stage("report"):
        return write_report(out)
