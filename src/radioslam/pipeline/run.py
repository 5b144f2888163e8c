"""A whole run (simulate → sense → slam → evaluate) and its report."""

from __future__ import annotations

from pathlib import Path

from radioslam.choices import ChannelKind
from radioslam.errors import RadioslamError
from radioslam.io.manifest import RunManifest
from radioslam.io.rundir import RunDir
from radioslam.pipeline.evaluate import evaluate_stage
from radioslam.pipeline.sense import simulate_and_sense
from radioslam.pipeline.slam import slam_stage
from radioslam.scene import load_scene
from radioslam.sensing import SensingConfig
from radioslam.slam import SlamConfig, SlamResult

SIMULATED_ODOMETRY = "simulated"  # run --odometry simulated: the scene's own drifting odometry


def run_scene(scene_name: str, out: Path, seed: int, snr_db: float | None, advance=None,
              cfg: SlamConfig | None = None, odometry: Path | None = None,
              sensing: SensingConfig | None = None, force: bool = False,
              max_memory: int | None = None, resume: bool = False,
              channel: ChannelKind = ChannelKind.BUILTIN) -> tuple[SlamResult, dict]:
    """Simulate and sense, SLAM, evaluate: a whole run directory; the SLAM result and metrics."""
    simulated = odometry is not None and str(odometry) == SIMULATED_ODOMETRY
    if simulated and load_scene(scene_name).spec.odometry is None:
        raise RadioslamError("the scene has no odometry: block to simulate one from", file=scene_name,
                             field="odometry")
    timings = simulate_and_sense(scene_name, out, seed, snr_db, advance, sensing, force, max_memory, resume, channel)
    result = slam_stage(out, cfg, timings, RunDir(out).odometry if simulated else odometry)
    return result, evaluate_stage(out)


def report_stage(out: Path) -> Path:
    """report.html and its figures."""
    from radioslam.viz.report import write_report

    with RunManifest(out).stage("report"):
        return write_report(out)
