"""The sense stage: scans/NNNN.ply from captures (recorded, or simulated in memory by ``run``)."""

from __future__ import annotations

import time
from pathlib import Path

from radioslam.choices import ChannelKind
from radioslam.errors import RadioslamError
from radioslam.io import read_calibration, read_capture, write_scan
from radioslam.io.manifest import RunManifest
from radioslam.io.rundir import RunDir
from radioslam.pipeline.simulate import scene_simulator, simulate_stage
from radioslam.progress import SILENT, Progress
from radioslam.sensing import Receiver, SensingConfig
from radioslam.sim.memory import check_budget, default_budget, recording_memory


def sensing_settings(sensing: SensingConfig | None, cal, calibration: Path) -> dict:
    """What run.json records of a sense stage: the receiver's settings and the calibration it used."""
    return {"sensing": (sensing or SensingConfig()).model_dump(mode="json"), "calibration": str(calibration),
            "hardware_delay_s": cal.hardware_delay_s}


def simulate_and_sense(scene_name: str, out: Path, seed: int, snr_db: float | None, progress: Progress = SILENT,
                       sensing: SensingConfig | None = None, force: bool = False,
                       max_memory: int | None = None, resume: bool = False,
                       channel: ChannelKind = ChannelKind.BUILTIN, radio: dict | None = None,
                       plot_pose: int = 0) -> dict:
    """The files of :func:`simulate_stage` and scans/ (IQ sensed in memory, by a receiver set by
    ``sensing``; pose ``plot_pose``'s radar heatmap too); stage seconds. With ``resume``, the poses whose
    scans an unfinished run of the same settings wrote (and recorded) are not simulated again."""
    timings = {}
    tick = time.perf_counter()
    scene, run, cal = simulate_stage(scene_name, out, seed, snr_db, force, max_memory=max_memory, resume=resume,
                                     channel=channel, radio=radio)
    timings["calibrate"] = time.perf_counter() - tick
    receiver, manifest = Receiver(scene.radio, cal.hardware_delay_s, sensing, cal.leakage), RunManifest(out)
    simulate_s = sense_s = 0.0
    with manifest.stage("sense", sensing_settings(sensing, cal, run.calibration), resume) as kept:
        done = frozenset(k for k in range(len(scene.poses)) if run.relative(run.scan_file(k)) in kept)
        progress.start("simulating and sensing", len(scene.poses), len(done))
        captures = scene_simulator(scene, run, channel).simulate(seed, skip=done)
        for _ in range(len(scene.poses) - len(done)):
            tick = time.perf_counter()
            capture = next(captures)
            simulate_s += time.perf_counter() - tick
            tick = time.perf_counter()
            write_sensed(run, manifest, capture, receiver.sense(capture), plot_pose)
            sense_s += time.perf_counter() - tick
            progress.advance()
    timings.update(simulate=simulate_s, sense=sense_s)
    return timings


def capture_files(directory: Path) -> list[Path]:
    """The SigMF recordings (``*.sigmf-meta``) of a directory, by name."""
    if not directory.is_dir():
        raise RadioslamError("no such directory", file=directory, field="(directory)")
    files = sorted(directory.glob("*.sigmf-meta"))
    if not files:
        raise RadioslamError("no SigMF captures (*.sigmf-meta); run 'radioslam simulate --save-iq'",
                             file=directory, field="(directory)")
    return files


def sense_stage(out: Path, sensing: SensingConfig | None = None, calibration: Path | None = None,
                plot_pose: int = 0, max_memory: int | None = None, resume: bool = False,
                progress: Progress = SILENT) -> int:
    """scans/NNNN.ply from the recordings in captures/ (one per pose), sensed with ``calibration``
    (default: the run's calibration.json), and scans/NNNN.png of pose ``plot_pose`` (−1: none): its radar
    heatmap and cloud (paper Fig. 4(b)); the number of scans. Each recording's memory is checked before it
    is read; with ``resume`` the scans an unfinished stage recorded are kept."""
    run = RunDir(out)
    calibration = calibration or run.calibration
    cal, cfg = read_calibration(calibration), sensing or SensingConfig()
    files = capture_files(run.captures)
    receiver, manifest = None, RunManifest(run.root)
    seen: dict[int, Path] = {}
    with manifest.stage("sense", sensing_settings(cfg, cal, calibration), resume) as kept:
        progress.start("sensing", len(files))
        for f in files:
            stem = f.name.split(".")[0]  # captures/NNNN: pose NNNN (radioslam's names)
            if stem.isdigit() and run.relative(run.scan_file(int(stem))) in kept:
                progress.advance()  # a resumed run's scan, verified by its hash
                continue
            data = f.with_name(f.name.replace(".sigmf-meta", ".sigmf-data"))
            if data.is_file():  # what sensing it needs, before reading it
                check_budget(recording_memory(data.stat().st_size), max_memory or default_budget(), str(data))
            capture = read_capture(f)
            if capture.pose_index in seen:
                raise RadioslamError(f"pose {capture.pose_index} again (also in {seen[capture.pose_index].name}): "
                                     "one recording per pose", file=f, field="global.radioslam:pose_index")
            seen[capture.pose_index] = f
            receiver = receiver or Receiver(capture.radio, cal.hardware_delay_s, cfg, cal.leakage)
            write_sensed(run, manifest, capture, receiver.sense(capture), plot_pose)
            progress.advance()
    return len(files)


def write_sensed(run: RunDir, manifest: RunManifest, capture, result, plot_pose: int) -> None:
    """A pose's scans/NNNN.ply, and its heatmap if it is ``plot_pose``, written and recorded under sense."""
    write_scan(run.scan_file(capture.pose_index), result.scan, comment=f"pose {capture.pose_index}")
    manifest.record("sense", [run.scan_file(capture.pose_index)])
    if capture.pose_index == plot_pose:
        manifest.record("sense", [plot_heatmap(run, capture, result)])


def plot_heatmap(run: RunDir, capture, result) -> Path:
    """scans/NNNN.png: the pose's radar heatmap over beams and range, and its point cloud (paper Fig. 4(b))."""
    from radioslam.viz.figures import polar_heatmap_and_points

    path = run.heatmap_file(capture.pose_index)
    polar_heatmap_and_points(path, capture.beam_angle_rad, result.profile_range_m, result.profile_power,
                             result.scan.xy, result.scan.power_db)
    return path
