"""The stage commands (DESIGN.md §6 ★): ``simulate``, ``calibrate``, ``sense``, ``slam``, ``evaluate`` and
``report``, each reading what the stage before wrote in a run directory."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Optional

import typer

from radioslam.choices import ChannelKind, Detector, PointFilter, Refinement
from radioslam.cli import options as opt
from radioslam.cli.app import app
from radioslam.cli.options import register
from radioslam.cli.output import detail, err, gib, info, out_path, progress, warn
from radioslam.errors import RadioslamError

TRACKING_LOST = 3  # exit status of --strict when tracking was lost or the trajectory is ambiguous


@register(app)
def simulate(
    scene: str = opt.scene_argument(),
    out: Path = opt.out_option(),
    seed: int = opt.seed_option(),
    snr_db: Optional[float] = opt.snr_option(),
    save_iq: bool = opt.save_iq_option(),
    config: Optional[Path] = opt.config_option(),
    channel: ChannelKind = opt.channel_option(),
    force: bool = opt.force_option(),
    max_memory: Optional[float] = opt.max_memory_option(),
    resume: bool = opt.resume_option(),
) -> None:
    """Simulate a scene: scene.yaml, ground_truth.tum, calibration.json and, with --save-iq, SigMF captures.

    A new run: whatever run the directory held is replaced. The config file's radio: section replaces fields
    of the scene's radio.
    """
    from radioslam.pipeline import capture_writer, simulate_stage

    cfg = opt.run_config(config)
    with progress() as shown:
        loaded, run, _ = simulate_stage(scene, out, seed, snr_db, force,
                                        capture_writer(seed, channel, shown) if save_iq else None,
                                        gib(max_memory), resume, channel, cfg.radio)
    detail(f"simulate: {scene}, {len(loaded.poses)} poses, seed {seed}, SNR {loaded.radio.snr_db:g} dB, "
           f"{len(loaded.radio.model_dump(exclude_defaults=True))} radio fields off their defaults, "
           f"channel {ChannelKind(channel).value}")
    info(f"wrote {run.root} ({len(loaded.poses)} poses{', IQ captures' if save_iq else ''})")


@register(app)
def calibrate(
    scene: Optional[str] = typer.Argument(None, help="scene whose radio to use (default: the paper's defaults)"),
    out: Path = opt.out_option("calibration JSON to write"),
    targets: Optional[int] = typer.Option(None, "--targets", min=1, max=256,
                                           help="number of targets N_T (default 16)"),
    spacing: Optional[float] = typer.Option(None, "--spacing", min=0.05, help="target spacing, m (default 0.8)"),
    captures: Optional[Path] = typer.Option(None, "--captures", help="directory of recorded target captures"),
    ranges: Optional[str] = typer.Option(None, "--ranges", help="their ranges, m, comma separated, in file order"),
    empty: Optional[Path] = typer.Option(None, "--empty", help="a recorded capture of every beam with nothing in "
                                         "range: measures the TX→RX leakage (with --captures)"),
    seed: int = opt.seed_option(),
) -> None:
    """Estimate the hardware delay T_H from targets at known ranges (eq. 11), and the leakage of every beam."""
    from radioslam.config import RadioConfig
    from radioslam.io import read_capture, write_calibration
    from radioslam.pipeline import calibrate_simulated, capture_files
    from radioslam.scene import load_scene
    from radioslam.sensing import estimate_hardware_delay

    if captures is None:
        from radioslam.sim import Simulator
        from radioslam.sim.memory import check_budget, default_budget

        radio = load_scene(scene).radio if scene else RadioConfig()
        # the empty sweep is every beam at once, as a pose of a walk is
        check_budget(Simulator.from_radio(radio).memory(), default_budget(), scene or "(default radio)")
        cal = calibrate_simulated(radio, out, seed, targets, spacing)
    else:
        files = capture_files(captures)
        values = _parse_ranges(ranges, len(files))
        cal = estimate_hardware_delay([read_capture(f) for f in files], values, source=f"recorded: {captures}",
                                      empty=None if empty is None else read_capture(empty))
        write_calibration(out, cal)
    leakage = "no leakage measured" if cal.leakage is None else f"leakage of {len(cal.leakage.delay_s)} beams"
    info(f"T_H = {cal.hardware_delay_s * 1e6:.6f} µs from {len(cal.targets)} targets, {leakage} → {out}")


def _parse_ranges(text: Optional[str], count: int):
    import numpy as np

    if not text:
        raise RadioslamError("--ranges is required with --captures", file="(command line)", field="--ranges")
    try:
        values = np.array([float(v) for v in text.split(",")])
    except ValueError:
        raise RadioslamError(f"not a comma-separated list of numbers: {text!r}", file="(command line)",
                             field="--ranges") from None
    if len(values) != count or not np.all(np.isfinite(values)) or np.any(values <= 0):
        raise RadioslamError(f"need {count} positive ranges, one per capture", file="(command line)", field="--ranges")
    return values


@register(app)
def sense(
    run_dir: Path = typer.Argument(..., help="run directory with captures/ (from 'simulate --save-iq')"),
    calibration: Optional[Path] = typer.Option(None, "--calibration", help="default: DIR/calibration.json"),
    detector: Optional[Detector] = opt.detector_option(),
    threshold_db: Optional[float] = opt.threshold_option(),
    point_filter: Optional[PointFilter] = opt.point_filter_option(),
    refine: Optional[Refinement] = opt.refine_option(),
    config: Optional[Path] = opt.config_option(),
    plot_pose: int = opt.plot_pose_option(),
    max_memory: Optional[float] = opt.max_memory_option(),
    resume: bool = opt.resume_option(),
) -> None:
    """Turn SigMF captures into radio point clouds: DIR/scans/NNNN.ply (and scans/NNNN.png of --plot-pose)."""
    from radioslam.pipeline import sense_stage

    cfg = opt.run_config(config, opt.sensing_overrides(detector, threshold_db, point_filter, refine))
    detail(f"sense: {cfg.sensing.model_dump(mode='json', exclude_defaults=True) or 'the default receiver'}")
    with progress() as shown:
        count = sense_stage(run_dir, cfg.sensing, calibration, plot_pose, gib(max_memory), resume, shown)
    info(f"wrote {count} scans to {run_dir / 'scans'}")


def report_slam(result, strict: bool) -> None:
    """The SLAM's summary lines as warnings; with --strict, tracking lost or an ambiguous trajectory ends in
    exit status 3."""
    for line in result.summary_lines():
        warn(line)
    if strict and (result.tracking_lost or result.ambiguous_trajectory):
        why = "tracking lost" if result.tracking_lost else "ambiguous trajectory"
        err.print(f"radioslam: error: {why} (--strict)", markup=False)
        raise typer.Exit(TRACKING_LOST)


@register(app)
def slam(
    run_dir: Path = typer.Argument(..., help="run directory with scans/ (from 'sense' or 'run')"),
    config: Optional[Path] = opt.config_option(),
    odometry: Optional[Path] = typer.Option(None, "--odometry", help=opt.ODOMETRY_HELP),
    strict: bool = opt.strict_option(),
    scene_frame: bool = opt.scene_frame_option(),
    follow: bool = typer.Option(False, "--follow", help="map each pose as its scan (scans/NNNN.ply) or "
                                "recording (captures/NNNN.sigmf-*, sensed with calibration.json) appears, its "
                                "pose printed at once; the walk ends at scans/END or captures/END, after --idle "
                                "seconds with nothing new, or on Ctrl-C"),
    idle: float = typer.Option(60.0, "--idle", min=0.0, help="with --follow: seconds without a new scan that end "
                               "the walk"),
) -> None:
    """SLAM on the scans: trajectory.tum, trajectory_odometry.tum, map.pgm + map.yaml, map.ply, slam.json."""
    cfg = opt.run_config(config)
    if follow:
        from radioslam.live import follow_stage

        if odometry is not None or scene_frame:
            flag = "--odometry" if odometry is not None else "--scene-frame"
            raise RadioslamError(f"{flag} needs the whole walk up front; not with --follow",
                                 file="(command line)", field=flag)
        result = follow_stage(run_dir, cfg.slam, idle, _print_update, cfg.sensing)
    else:
        from radioslam.pipeline import slam_stage

        with progress() as shown:
            result = slam_stage(run_dir, cfg.slam, odometry=odometry, scene_frame=scene_frame, progress=shown)
    info(f"wrote {run_dir}: {len(result.poses)} poses, {len(result.loop_closures)} loop closures")
    report_slam(result, strict)


def _print_update(update) -> None:
    x, y, theta = update.pose
    err.print(f"scan {update.key}: x {x:.3f} m, y {y:.3f} m, θ {math.degrees(theta):.2f}°, {update.status.value}, "
              f"{update.seconds * 1e3:.0f} ms", markup=False)


def print_metrics(metrics: dict, json_out: bool) -> None:
    """--json: one JSON object on stdout; else a table of the metrics with their units."""
    from radioslam.io.json_io import dumps

    if json_out:
        typer.echo(dumps(metrics))
        return
    from radioslam.eval.metric_table import metric_rows

    for name, value, unit in metric_rows(metrics):
        typer.echo(f"{name:34s} {value} {unit}".rstrip())


@register(app)
def evaluate(
    run_dir: Path = typer.Argument(..., help="run directory after 'slam'"),
    json_out: bool = opt.json_option(),
) -> None:
    """Trajectory and map metrics against the ground truth: metrics.json."""
    from radioslam.pipeline import evaluate_stage

    print_metrics(evaluate_stage(run_dir), json_out)


@register(app)
def report(
    run_dir: Path = typer.Argument(..., help="run directory after 'evaluate' (a run's or the stages' one by one)"),
) -> None:
    """Write DIR/report.html: provenance, metrics, trajectories, map, scan statuses and figures."""
    from radioslam.pipeline import report_stage

    path = report_stage(run_dir)
    info(f"wrote {path}")


@register(app)
def export(
    run_dir: Path = typer.Argument(..., help="run directory after 'slam'"),
    mcap: Path = typer.Option(..., "--mcap", parser=out_path, help="ROS 2 bag to write (MCAP; Foxglove Studio and "
                              "RViz 2 open it)"),
) -> None:
    """Export a run as a ROS 2 bag (MCAP): scans as PointCloud2, paths, the occupancy grid, TF, loop closures."""
    from radioslam.pipeline.export import export_mcap

    counts = export_mcap(run_dir, mcap)
    detail("messages: " + ", ".join(f"{topic} {count}" for topic, count in counts.items()))
    info(f"wrote {mcap} ({sum(counts.values())} messages on {len(counts)} topics)")
