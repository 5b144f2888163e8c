"""Command line (DESIGN.md §6 ★). Bad input exits with status 2 and one line."""

from __future__ import annotations

import math
import signal
import sys
import warnings
from pathlib import Path
from typing import Optional

import typer

from radioslam.choices import ChannelKind
from radioslam.cli_output import (
    FORCE_HELP,
    MAX_MEMORY_HELP,
    RESUME_HELP,
    TERMINATED,
    Interrupted,
    Terminated,
    err,
    gib,
    one_line_errors,
    out_path,
    progress,
    report_warnings,
    terminate,
)
from radioslam.errors import RadioslamError

CHANNEL_HELP = ("where the echo paths come from: the built-in 2D caster, or Sionna RT on the scene extruded to 3D "
                "(extrude: in the scene; pip install 'radioslam[sionna]')")

app = typer.Typer(add_completion=False, invoke_without_command=True, pretty_exceptions_enable=False,
                  rich_markup_mode=None, help="Active mmWave sensing SLAM in 5G NR (arXiv 2507.04662).")


def _version(value: bool) -> None:
    if value:
        from radioslam import __version__

        typer.echo(f"radioslam {__version__}")
        raise typer.Exit()


@app.callback()
def _root(ctx: typer.Context,
          version: bool = typer.Option(False, "--version", callback=_version, is_eager=True,
                                       help="print the version and exit")) -> None:
    """Active mmWave sensing SLAM in 5G NR (arXiv 2507.04662)."""
    if ctx.invoked_subcommand is None:
        typer.echo(ctx.get_help())
        raise typer.Exit()


@app.command()
@one_line_errors
def scenes() -> None:
    """List the built-in scenes."""
    from radioslam.scene import BUILTIN_SCENES

    for name, (_, summary) in BUILTIN_SCENES.items():
        typer.echo(f"{name:14s} {summary}")


@app.command()
@one_line_errors
def simulate(
    scene: str = typer.Argument(..., help="scene YAML file or built-in name (see 'radioslam scenes')"),
    out: Path = typer.Option(..., "--out", parser=out_path, help="run directory to write"),
    seed: int = typer.Option(0, "--seed", min=0, help="seed of every random draw (≥ 0)"),
    snr_db: Optional[float] = typer.Option(None, "--snr-db", help="per-RE SNR of the reference echo, dB"),
    save_iq: bool = typer.Option(False, "--save-iq", help="write SigMF captures/NNNN.sigmf-{meta,data}"),
    force: bool = typer.Option(False, "--force", help=FORCE_HELP),
    max_memory: Optional[float] = typer.Option(None, "--max-memory", min=0.01, help=MAX_MEMORY_HELP),
    resume: bool = typer.Option(False, "--resume", help=RESUME_HELP),
    channel: ChannelKind = typer.Option(ChannelKind.BUILTIN, "--channel", help=CHANNEL_HELP),
) -> None:
    """Simulate a scene: scene.yaml, ground_truth.tum, calibration.json and, with --save-iq, SigMF captures
    (a new run: whatever run the directory held is replaced)."""
    from radioslam.io import write_capture
    from radioslam.pipeline import scene_simulator, simulate_stage

    def captures(loaded, run, kept: set[str]) -> None:
        from radioslam.io.manifest import RunManifest
        from radioslam.io.sigmf_io import data_path, meta_path

        def recorded(k: int) -> bool:  # a resumed run's recording, both files as run.json lists them
            base = run.capture_base(k)
            return {run.relative(meta_path(base)), run.relative(data_path(base))} <= kept

        done = frozenset(k for k in range(len(loaded.poses)) if recorded(k))
        with progress() as bar:
            task = bar.add_task("simulating", total=len(loaded.poses), completed=len(done))
            for capture in scene_simulator(loaded, run, channel).simulate(seed, skip=done):
                base = run.capture_base(capture.pose_index)
                write_capture(capture, base)
                RunManifest(run.root).record("simulate", [data_path(base), meta_path(base)])
                bar.advance(task)

    loaded, run, _ = simulate_stage(scene, out, seed, snr_db, force, captures if save_iq else None,
                                    gib(max_memory), resume, channel)
    err.print(f"wrote {run.root} ({len(loaded.poses)} poses{', IQ captures' if save_iq else ''})",
              markup=False)


@app.command()
@one_line_errors
def calibrate(
    scene: Optional[str] = typer.Argument(None, help="scene whose radio to use (default: the paper's defaults)"),
    out: Path = typer.Option(..., "--out", parser=out_path, help="calibration JSON to write"),
    targets: Optional[int] = typer.Option(None, "--targets", min=1, max=256,
                                           help="number of targets N_T (default 16)"),
    spacing: Optional[float] = typer.Option(None, "--spacing", min=0.05, help="target spacing, m (default 0.8)"),
    captures: Optional[Path] = typer.Option(None, "--captures", help="directory of recorded target captures"),
    ranges: Optional[str] = typer.Option(None, "--ranges", help="their ranges, m, comma separated, in file order"),
    empty: Optional[Path] = typer.Option(None, "--empty", help="a recorded capture of every beam with nothing in "
                                         "range: measures the TX→RX leakage (with --captures)"),
    seed: int = typer.Option(0, "--seed", min=0, help="seed of the simulated measurements"),
) -> None:
    """Estimate the hardware delay T_H from targets at known ranges, eq. (11), and the leakage of every beam."""
    from radioslam.config import RadioConfig
    from radioslam.io import read_capture, write_calibration
    from radioslam.pipeline import calibrate_simulated
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
        files = _capture_files(captures)
        values = _parse_ranges(ranges, len(files))
        cal = estimate_hardware_delay([read_capture(f) for f in files], values, source=f"recorded: {captures}",
                                      empty=None if empty is None else read_capture(empty))
        write_calibration(out, cal)
    leakage = "no leakage measured" if cal.leakage is None else f"leakage of {len(cal.leakage.delay_s)} beams"
    err.print(f"T_H = {cal.hardware_delay_s * 1e6:.6f} µs from {len(cal.targets)} targets, {leakage} → {out}",
              markup=False)


def _capture_files(directory: Path) -> list[Path]:
    from radioslam.errors import RadioslamError

    if not directory.is_dir():
        raise RadioslamError("no such directory", file=directory, field="(directory)")
    files = sorted(directory.glob("*.sigmf-meta"))
    if not files:
        raise RadioslamError("no SigMF captures (*.sigmf-meta); run 'radioslam simulate --save-iq'",
                             file=directory, field="(directory)")
    return files


def _parse_ranges(text: Optional[str], count: int):
    import numpy as np

    from radioslam.errors import RadioslamError

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


@app.command()
@one_line_errors
def sense(
    run_dir: Path = typer.Argument(..., help="run directory with captures/ (from 'simulate --save-iq')"),
    calibration: Optional[Path] = typer.Option(None, "--calibration", help="default: DIR/calibration.json"),
    detector: Optional[str] = typer.Option(None, "--detector",
                                           help="single (the paper's; default) or multi (CFAR + cancellation)"),
    threshold_db: Optional[float] = typer.Option(None, "--threshold-db", max=0.0,
                                                 help="point threshold (default −13 single, −25 multi)"),
    point_filter: Optional[str] = typer.Option(None, "--point-filter",
                                               help="single detector: same-range (default: threshold re. the "
                                                    "strongest detection at each range, floor −25 dB) or scan-peak "
                                                    "(the paper's: re. the scan's peak)"),
    refine: Optional[str] = typer.Option(None, "--refine",
                                         help="peak refinement: bracketed (default: both sides of each peak "
                                              "bracketed) or paper-bisection (the paper's, to reproduce it)"),
    config: Optional[Path] = typer.Option(None, "--config", help="YAML config file; its sensing: section sets "
                                          "the receiver, the options above override it"),
    plot_pose: int = typer.Option(0, "--plot-pose", help="pose whose heatmap and cloud to draw; −1: none"),
    max_memory: Optional[float] = typer.Option(None, "--max-memory", min=0.01, help=MAX_MEMORY_HELP),
    resume: bool = typer.Option(False, "--resume", help=RESUME_HELP),
) -> None:
    """Turn SigMF captures into point clouds: DIR/scans/NNNN.ply."""
    from radioslam.errors import RadioslamError
    from radioslam.io import read_calibration, read_capture, write_scan
    from radioslam.io.manifest import RunManifest
    from radioslam.io.rundir import RunDir
    from radioslam.pipeline import sensing_settings
    from radioslam.sensing import Detector, PointFilter, Receiver, Refinement
    from radioslam.sim.memory import check_budget, default_budget, recording_memory

    run = RunDir(run_dir)
    cal = read_calibration(calibration or run.calibration)
    options = {"detector": (detector, Detector, "--detector"), "point_filter": (point_filter, PointFilter,
               "--point-filter"), "refine": (refine, Refinement, "--refine")}
    given = {"point_threshold_db": threshold_db} if threshold_db is not None else {}
    for name, (value, kind, flag) in options.items():
        if value is None:
            continue
        try:
            given[name] = kind(value)
        except ValueError:
            allowed = " or ".join(f"'{member.value}'" for member in kind)
            raise RadioslamError(f"must be {allowed}", file="(command line)", field=flag) from None
    cfg = _sensing_config(config).model_copy(update=given)
    files = _capture_files(run.captures)
    receiver = None
    manifest = RunManifest(run.root)
    with manifest.stage("sense", sensing_settings(cfg, cal, calibration or run.calibration), resume) as kept, \
            progress() as bar:
        task = bar.add_task("sensing", total=len(files))
        seen: dict[int, Path] = {}
        for f in files:
            stem = f.name.split(".")[0]  # captures/NNNN: pose NNNN (radioslam's names)
            if stem.isdigit() and run.relative(run.scan_file(int(stem))) in kept:
                bar.advance(task)  # a resumed run's scan, verified by its hash
                continue
            data = f.with_name(f.name.replace(".sigmf-meta", ".sigmf-data"))
            if data.is_file():  # what sensing it needs, before reading it
                check_budget(recording_memory(data.stat().st_size), gib(max_memory) or default_budget(), str(data))
            capture = read_capture(f)
            if capture.pose_index in seen:
                raise RadioslamError(f"pose {capture.pose_index} again (also in {seen[capture.pose_index].name}): "
                                     "one recording per pose", file=f, field="global.radioslam:pose_index")
            seen[capture.pose_index] = f
            receiver = receiver or Receiver(capture.radio, cal.hardware_delay_s, cfg, cal.leakage)
            result = receiver.sense(capture)
            write_scan(run.scan_file(capture.pose_index), result.scan, comment=f"pose {capture.pose_index}")
            manifest.record("sense", [run.scan_file(capture.pose_index)])
            if capture.pose_index == plot_pose:
                from radioslam.viz.figures import polar_heatmap_and_points

                polar_heatmap_and_points(run.scans / f"{capture.pose_index:04d}.png", capture.beam_angle_rad,
                                         result.profile_range_m, result.profile_power, result.scan.xy,
                                         result.scan.power_db)
            bar.advance(task)
    err.print(f"wrote {len(files)} scans to {run.scans}", markup=False)


CONFIG_HELP = ("YAML config file; its slam: section sets the SLAM, its sensing: section the receiver "
               "(docs/architecture.md)")
ODOMETRY_HELP = "relative motion from wheels or an IMU, one TUM pose per scan (its noise: slam.motion in --config)"
STRICT_HELP = ("exit with status 3 when tracking was lost (a stretch of scans matched nothing, or a long "
               "one in which none fixed one pose: a direction nothing fixes, rival poses alike)")
TRACKING_LOST = 3  # exit status of --strict when tracking was lost


def _sensing_config(path: Optional[Path]):
    from radioslam.sensing import SensingConfig
    from radioslam.sensing.config import load_sensing_config

    return load_sensing_config(path) if path is not None else SensingConfig()


def _slam_config(path: Optional[Path]):
    from radioslam.slam import SlamConfig, load_slam_config

    return load_slam_config(path) if path is not None else SlamConfig()


def _report_slam(result, strict: bool) -> None:
    """The SLAM's summary lines as warnings; with --strict, tracking lost ends in exit status 3."""
    for line in result.summary_lines():
        err.print(f"radioslam: warning: {line}", markup=False, soft_wrap=True)
    if strict and result.tracking_lost:
        err.print("radioslam: error: tracking lost (--strict)", markup=False)
        raise typer.Exit(TRACKING_LOST)


@app.command()
@one_line_errors
def slam(
    run_dir: Path = typer.Argument(..., help="run directory with scans/ (from 'sense' or 'run')"),
    config: Optional[Path] = typer.Option(None, "--config", help=CONFIG_HELP),
    odometry: Optional[Path] = typer.Option(None, "--odometry", help=ODOMETRY_HELP),
    strict: bool = typer.Option(False, "--strict", help=STRICT_HELP),
    follow: bool = typer.Option(False, "--follow", help="map each pose as its scan (scans/NNNN.ply) or "
                                "recording (captures/NNNN.sigmf-*, sensed with calibration.json) appears, its "
                                "pose printed at once; the walk ends at scans/END or captures/END, after --idle "
                                "seconds with nothing new, or on Ctrl-C"),
    idle: float = typer.Option(60.0, "--idle", min=0.0, help="with --follow: seconds without a new scan that end "
                               "the walk"),
) -> None:
    """SLAM on the scans: trajectory.tum, trajectory_odometry.tum, map.pgm + map.yaml, map.ply, slam.json."""
    if follow:
        from radioslam.live import follow_stage

        if odometry is not None:
            raise RadioslamError("--odometry needs every scan's pose up front; not with --follow", file=odometry,
                                 field="--odometry")
        result = follow_stage(run_dir, _slam_config(config), idle, _print_update, _sensing_config(config))
    else:
        from radioslam.pipeline import slam_stage

        result = slam_stage(run_dir, _slam_config(config), odometry=odometry)
    err.print(f"wrote {run_dir}: {len(result.poses)} poses, {len(result.loop_closures)} loop closures", markup=False)
    _report_slam(result, strict)


@app.command()
@one_line_errors
def sweep(
    sweep_file: Path = typer.Argument(..., help="sweep YAML: scenes, seeds, snr_db, overrides, variants, robustness"),
    out: Path = typer.Option(..., "--out", parser=out_path,
                             help="sweep directory: runs/, rows/, results.parquet, results.csv, plots"),
    scheduler: Optional[str] = typer.Option(None, "--scheduler", help="a running Dask scheduler (tcp://HOST:8786; "
                                            "its workers must see --out), or 'synchronous' (one by one, in this "
                                            "process); default: a LocalCluster"),
    workers: Optional[int] = typer.Option(None, "--workers", min=1, help="LocalCluster worker processes (default: "
                                          "one per core)"),
    retry_failed: bool = typer.Option(False, "--retry-failed", help="run again the runs that failed before"),
) -> None:
    """Monte Carlo sweep on Dask: every scene × seed × SNR × variant as a whole run; a tidy table and plots."""
    from radioslam.sweep import load_sweep, run_sweep

    spec = load_sweep(sweep_file)

    def report(row: dict, done: int, total: int) -> None:
        what = f"ATE {row['ate_rmse_m']:.3f} m" if row["status"] == "ok" else row["error"]
        err.print(f"[{done}/{total}] {row['scene']} seed {row['seed']} snr {row['snr_db']}: {row['status']}, {what} "
                  f"({row['run_seconds']:.0f} s)", markup=False, highlight=False, soft_wrap=True)

    result = run_sweep(spec, out, scheduler, workers, retry_failed, report)
    err.print(f"wrote {out}/results.parquet and results.csv: {len(result.table)} runs ({result.ran} run now, "
              f"{result.skipped} finished before, {result.failed} failed) in {result.seconds:.0f} s", markup=False,
              highlight=False, soft_wrap=True)


def _print_update(update) -> None:
    x, y, theta = update.pose
    err.print(f"scan {update.key}: x {x:.3f} m, y {y:.3f} m, θ {math.degrees(theta):.2f}°, {update.status.value}, "
              f"{update.seconds * 1e3:.0f} ms", markup=False)


def _print_metrics(metrics: dict, json_out: bool) -> None:
    from radioslam.io.json_io import dumps

    if json_out:
        typer.echo(dumps(metrics))
        return
    for key, value in metrics.items():
        shown = f"{value:.4f}" if isinstance(value, float) else value
        typer.echo(f"{key:22s} {shown}")


@app.command()
@one_line_errors
def evaluate(
    run_dir: Path = typer.Argument(..., help="run directory after 'slam'"),
    json_out: bool = typer.Option(False, "--json", help="print one JSON object of the metrics on stdout"),
) -> None:
    """Trajectory and map metrics against the ground truth (writes metrics.json)."""
    from radioslam.pipeline import evaluate_stage

    _print_metrics(evaluate_stage(run_dir), json_out)


def _run_all(scene: str, out: Path, seed: int, snr_db: Optional[float], json_out: bool, config: Optional[Path] = None,
             odometry: Optional[Path] = None, strict: bool = False, force: bool = False,
             max_memory: Optional[float] = None, resume: bool = False,
             channel: ChannelKind = ChannelKind.BUILTIN) -> None:
    from radioslam.pipeline import report_stage, run_scene
    from radioslam.scene import load_scene

    cfg = _slam_config(config)
    poses = len(load_scene(scene).poses)
    with progress() as bar:
        task = bar.add_task("simulating and sensing", total=poses)
        result, metrics = run_scene(scene, out, seed, snr_db, lambda: bar.advance(task), cfg, odometry,
                                    _sensing_config(config), force, gib(max_memory), resume, channel)
    report_stage(out)
    _print_metrics(metrics, json_out)
    err.print(f"wrote {out} (report.html)", markup=False)
    _report_slam(result, strict)


@app.command()
@one_line_errors
def run(
    scene: str = typer.Argument(..., help="scene YAML file or built-in name"),
    out: Path = typer.Option(..., "--out", parser=out_path, help="run directory to write"),
    seed: int = typer.Option(0, "--seed", min=0),
    snr_db: Optional[float] = typer.Option(None, "--snr-db", help="per-RE SNR of the reference echo, dB"),
    json_out: bool = typer.Option(False, "--json", help="print one JSON object of the metrics on stdout"),
    config: Optional[Path] = typer.Option(None, "--config", help=CONFIG_HELP),
    odometry: Optional[Path] = typer.Option(None, "--odometry",
                                            help=ODOMETRY_HELP + "; 'simulated': the scene's own (odometry.tum)"),
    strict: bool = typer.Option(False, "--strict", help=STRICT_HELP),
    force: bool = typer.Option(False, "--force", help=FORCE_HELP),
    max_memory: Optional[float] = typer.Option(None, "--max-memory", min=0.01, help=MAX_MEMORY_HELP),
    resume: bool = typer.Option(False, "--resume", help=RESUME_HELP),
    channel: ChannelKind = typer.Option(ChannelKind.BUILTIN, "--channel", help=CHANNEL_HELP),
) -> None:
    """simulate → sense → slam → evaluate on any scene, and write report.html (a new run: whatever run the
    directory held is replaced)."""
    _run_all(scene, out, seed, snr_db, json_out, config, odometry, strict, force, max_memory, resume, channel)


@app.command()
@one_line_errors
def demo(
    out: Path = typer.Option(Path("runs/demo"), "--out", parser=out_path, help="run directory to write"),
    seed: int = typer.Option(1, "--seed", min=0),
    json_out: bool = typer.Option(False, "--json", help="print one JSON object of the metrics on stdout"),
    strict: bool = typer.Option(False, "--strict", help=STRICT_HELP),
    force: bool = typer.Option(False, "--force", help=FORCE_HELP),
    max_memory: Optional[float] = typer.Option(None, "--max-memory", min=0.01, help=MAX_MEMORY_HELP),
    resume: bool = typer.Option(False, "--resume", help=RESUME_HELP),
    channel: ChannelKind = typer.Option(ChannelKind.BUILTIN, "--channel", help=CHANNEL_HELP),
) -> None:
    """The paper's Fig. 6 simulation end to end: paper-cnv, 60 poses, SNR 10 dB, waveform IQ."""
    _run_all("paper-cnv", out, seed, None, json_out, strict=strict, force=force, max_memory=max_memory,
             resume=resume, channel=channel)


@app.command()
@one_line_errors
def reproduce(
    experiment: str = typer.Argument(..., help="table1, fig5, fig8, fig6 or all"),
    out: Path = typer.Option(..., "--out", parser=out_path,
                             help="directory for the figure (PNG) and table (CSV, Markdown)"),
    json_out: bool = typer.Option(False, "--json", help="print one JSON object of the results on stdout"),
    seed: int = typer.Option(0, "--seed", min=0),
    trials: Optional[int] = typer.Option(None, "--trials", min=1, help="Monte Carlo trials (default per experiment)"),
    impairments: str = typer.Option("ideal", "--impairments",
                                    help="table1: the radio's hardware profile (ideal, iq, adc, pa, elements, "
                                         "drift, phase-noise, leakage, extended, prototype; "
                                         "docs/architecture.md)"),
) -> None:
    """Reproduce the paper's experiments: Table I, Fig. 5, Fig. 8 and Fig. 6 (SLAM on paper-cnv); and
    Table I under hardware impairments (impairments)."""
    from radioslam.errors import RadioslamError
    from radioslam.eval.experiments.reproduce import EXPERIMENTS, IMPAIRMENT_PROFILES, run_experiment
    from radioslam.io.json_io import dumps

    names = list(EXPERIMENTS) if experiment == "all" else [experiment]
    if any(n not in EXPERIMENTS for n in names):
        raise RadioslamError(f"unknown experiment {experiment!r} (known: {', '.join(EXPERIMENTS)}, all)",
                             file="(command line)", field="EXPERIMENT")
    if impairments not in IMPAIRMENT_PROFILES:
        raise RadioslamError(f"unknown profile {impairments!r} (known: {', '.join(IMPAIRMENT_PROFILES)})",
                             file="(command line)", field="--impairments")
    out.mkdir(parents=True, exist_ok=True)
    results = {n: run_experiment(n, out, seed, trials, impairments) for n in names}
    if json_out:
        typer.echo(dumps(results[names[0]] if len(names) == 1 else results))
    err.print(f"wrote {', '.join(names)} to {out}", markup=False)


def main() -> None:
    """Entry point: usage errors and interrupts end in one line too.

    typer ≤ 0.2x raises click's exceptions, newer typer its vendored copy of them;
    both carry ``format_message()`` and ``exit_code``, which is all this needs. Warnings of the
    numerical libraries (a log of zero, an empty mean) are counted, not printed line by line.
    """
    command = typer.main.get_command(app)
    signal.signal(signal.SIGTERM, terminate)
    try:
        with warnings.catch_warnings(record=True) as caught:  # the filters as they are: libraries' deprecations
            code = command.main(prog_name="radioslam", standalone_mode=False)
        if not code:
            report_warnings(caught)
    except Terminated:
        err.print("radioslam: terminated (SIGTERM); unfinished stages are marked failed in run.json")
        sys.exit(TERMINATED)
    except (Interrupted, KeyboardInterrupt):
        err.print("radioslam: interrupted (Ctrl-C); unfinished stages are marked failed in run.json")
        sys.exit(130)
    except Exception as exc:  # noqa: BLE001 - only click-style exceptions are handled here
        if type(exc).__name__ == "Abort":
            err.print("radioslam: interrupted (Ctrl-C)")
            sys.exit(130)
        if not (hasattr(exc, "format_message") and hasattr(exc, "exit_code")):
            raise
        ctx = getattr(exc, "ctx", None)
        where = f"{ctx.command_path}: " if ctx is not None else ""
        err.print(f"radioslam: error: {where}{exc.format_message()}", markup=False, soft_wrap=True)
        sys.exit(exc.exit_code)
    sys.exit(code if isinstance(code, int) else 0)


if __name__ == "__main__":
    main()
