"""The simulate stage (DESIGN.md §5 ★): a new run's scene.yaml, ground_truth.tum, calibration.json and, with
``--save-iq``, its SigMF captures."""

from __future__ import annotations

import hashlib
from collections.abc import Callable
from pathlib import Path

from radioslam.choices import ChannelKind
from radioslam.io import read_calibration, write_capture, write_tum
from radioslam.io.atomic import atomic_write_text
from radioslam.io.json_io import dumps
from radioslam.io.manifest import RunManifest
from radioslam.io.rundir import RunDir
from radioslam.io.sigmf_io import data_path, meta_path
from radioslam.io.trace_cache import TraceCache
from radioslam.pipeline.calibration import calibrate_simulated
from radioslam.progress import SILENT, Progress
from radioslam.scene import Scene, load_scene, scene_to_yaml
from radioslam.sim import Simulator
from radioslam.sim.channel_backend import check_channel
from radioslam.sim.memory import check_budget, default_budget
from radioslam.sim.odometry import odometry_rng, simulated_odometry


def capture_writer(seed: int, channel: ChannelKind = ChannelKind.BUILTIN, progress: Progress = SILENT):
    """What :func:`simulate_stage` calls for ``--save-iq``: every pose's SigMF capture written and recorded
    in run.json as it is simulated (a resumed run's recordings, both files as run.json lists them, kept)."""

    def write(scene: Scene, run: RunDir, kept: set[str]) -> None:
        def recorded(k: int) -> bool:
            base = run.capture_base(k)
            return {run.relative(meta_path(base)), run.relative(data_path(base))} <= kept

        done = frozenset(k for k in range(len(scene.poses)) if recorded(k))
        progress.start("simulating", len(scene.poses), len(done))
        manifest = RunManifest(run.root)
        for capture in scene_simulator(scene, run, channel).simulate(seed, skip=done):
            base = run.capture_base(capture.pose_index)
            write_capture(capture, base)
            manifest.record("simulate", [data_path(base), meta_path(base)])
            progress.advance()

    return write


def write_json(path: Path, doc: dict) -> None:
    """Strict JSON: a figure that does not exist (NaN) is null."""
    atomic_write_text(path, dumps(doc, indent=2) + "\n")


def simulate_stage(scene_name: str, out: Path, seed: int, snr_db: float | None, force: bool = False,
                   captures: Callable[[Scene, RunDir, set[str]], None] | None = None, max_memory: int | None = None,
                   resume: bool = False, channel: ChannelKind = ChannelKind.BUILTIN, radio: dict | None = None):
    """A new run in ``out`` (the old one there replaced whole, run.json): scene.yaml, ground_truth.tum and
    calibration.json (eq. (11) on plates simulated with this scene's radio), and what ``captures`` writes
    (given the files a resumed run kept); the scene, the run directory and the calibration. ``radio``
    overrides the scene's radio (a config file's ``radio:`` section; ``snr_db`` wins over it). With
    ``resume``, an unfinished run of the same scene, seed and settings there is gone on with."""
    given = {} if snr_db is None else {"snr_db": snr_db}
    scene = load_scene(scene_name).with_radio(**{**(radio or {}), **given})
    # what one pose needs, and the calibration's empty sweep (every beam too), before anything is written
    check_budget(Simulator.from_scene(scene, channel=channel).memory(), max_memory or default_budget(), scene_name)
    check_channel(channel, scene, scene_name)
    run, manifest = RunDir(out), RunManifest(out)
    manifest.new_run(seed, scene_name, force, resume)
    scene_text = scene_to_yaml(scene)
    settings = {"scene": scene_name, "scene_sha256": hashlib.sha256(scene_text.encode()).hexdigest(), "seed": seed,
                "snr_db": snr_db, "save_iq": captures is not None, "radio": scene.radio.model_dump(mode="json"),
                "channel": ChannelKind(channel).value}
    if resume and manifest.is_complete("simulate", settings):
        return scene, run, read_calibration(run.calibration)
    with manifest.stage("simulate", settings, resume) as kept:
        atomic_write_text(run.scene, scene_text)
        write_tum(run.ground_truth, run.pose_timestamps(len(scene.poses)), scene.poses)
        if scene.spec.odometry is not None:  # a drifting wheel/IMU odometry of the same walk
            write_tum(run.odometry, run.pose_timestamps(len(scene.poses)),
                      simulated_odometry(scene.poses, scene.spec.odometry, odometry_rng(seed)))
        cal = calibrate_simulated(scene.radio, run.calibration, seed)
        if captures is not None:
            captures(scene, run, kept)
    return scene, run, cal


def scene_simulator(scene: Scene, run: RunDir, channel: ChannelKind = ChannelKind.BUILTIN) -> Simulator:
    """The simulator of a run's scene; a ray tracer's paths are kept in the run's traces/ (issue #16)."""
    return Simulator.from_scene(scene, channel=channel, trace_cache=TraceCache(run.traces))
